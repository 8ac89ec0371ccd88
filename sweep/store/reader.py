"""Reading the stored layout back: the one place that parses a store file.

:mod:`sweep.store.schema` says what the layout is; this module reads it: the root and run
attributes, the committed table (rows below ``/table.attrs["n_rows"]``; a column an
older schema version lacks reads as its fill value), a point's profile group, and every
committed point as a :class:`sweep.store.record.Record`. Bytes are decoded by
:func:`sweep.store.cells.text`. Used by :func:`sweep.analysis.load.load` and its relatives,
:func:`sweep.store.merge.merge`, :func:`sweep.store.validate.validate` and the store's repair path
(:meth:`sweep.store.store.Store` journals stored rows its journal lacks).

Each reader re-checks that every stored row's ``config_json`` still hashes to its
``hash`` (:func:`hash_mismatches`; the journal does the same for its lines): a row
altered after it was written is a :class:`sweep.errors.StoreCorruptedError` naming the
hash for ``load`` and ``merge``, and a problem for ``validate``.
"""
from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from sweep.errors import StoreCorruptedError
from sweep.identity import config_hashes_to
from sweep.store.cells import text, texts
from sweep.store.journal import Journal
from sweep.store.record import Record
from sweep.store.schema import (
    COLUMNS,
    FROM_CONFIG,
    HISTORY_VAR,
    MIGRATION_FILL,
    PROFILE_VARS,
    REPLICA_VARS,
    config_values,
    profile_path,
)

__all__ = ["attrs_of", "open_file", "n_rows", "table_columns",
           "profile_group", "iter_records", "model_version", "hash_mismatches",
           "check_hashes", "read_journal"]


def attrs_of(obj: Any) -> dict[str, Any]:
    """The HDF5 attributes of ``obj`` (a file, group or dataset), strings decoded."""
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in obj.attrs.items()}


def open_file(path: str | Path) -> h5py.File:
    """A store opened read-only without HDF5 file locking (a reader never blocks the
    writer; :mod:`sweep.store.lock` is the writers' lock)."""
    return h5py.File(path, "r", locking=False)


def not_a_store(path: str | Path) -> str | None:
    """Why ``path`` cannot be a store, in words (``None``: it may be one): no such file,
    a directory, or a file without HDF5's signature (a campaign file given by mistake).
    An empty file is not judged (a writer may be creating it)."""
    p = Path(path)
    if not p.exists():
        return "no such store (file not found)"
    if p.is_dir():
        return "is a directory, not a store (a store is the .h5 file of sweep run --store)"
    try:
        if p.is_file() and p.stat().st_size > 0 and not h5py.is_hdf5(p):
            return ("not a sweep store: not an HDF5 file (a store is the .h5 file of sweep"
                    " run --store)")
    except OSError:
        return None
    return None


def n_rows(f: h5py.File) -> int:
    """The committed rows of the store's table."""
    return int(f["table"].attrs["n_rows"])


def table_columns(f: h5py.File, names: Iterable[str] | None = None,
                  n: int | None = None) -> dict[str, np.ndarray]:
    """The committed rows of the table columns ``names`` (default: all of
    :data:`sweep.store.schema.COLUMNS`), strings decoded; a column an older schema version
    lacks reads as its fill value (:data:`sweep.store.schema.MIGRATION_FILL` where given;
    a :data:`sweep.store.schema.FROM_CONFIG` column as each row's value in its
    ``config_json``, as the migration fills it)."""
    table = f["table"]
    n = n_rows(f) if n is None else n
    wanted = set(names) if names is not None else None
    out = {}
    for c in COLUMNS:
        if wanted is not None and c.name not in wanted:
            continue
        if c.name in table:
            out[c.name] = texts(table[c.name][:n])
        elif c.name in FROM_CONFIG:
            out[c.name] = np.asarray(config_values(c.name, table["config_json"][:n]),
                                     dtype=np.int64 if c.kind == "int" else None)
        else:
            out[c.name] = np.full(n, MIGRATION_FILL.get(c.name, c.fill),
                                  dtype=object if c.kind == "str" else None)
    return out


def profile_group(f: h5py.File, h: str, names: Iterable[str] | None = None,
                  history: bool = True) -> tuple[dict[str, np.ndarray], Any] | None:
    """Point ``h``'s stored profiles among ``names`` (default :data:`PROFILE_VARS` then
    :data:`REPLICA_VARS`; those present) and its residual history (``None`` unless
    ``history``); ``None`` without a profile group."""
    name = profile_path(h)
    if name not in f:
        return None
    g = f[name]
    names = (*PROFILE_VARS, *REPLICA_VARS) if names is None else names
    profiles = {k: g[k][()] for k in names if k in g}
    return profiles, (g[HISTORY_VAR[0]][()] if history else None)


def iter_records(f: h5py.File, only: set[str] | None = None,
                 normalise: bool = True) -> Iterator[Record]:
    """Every committed point of an open store (those whose hash is in ``only``, when
    given) as a :class:`sweep.store.record.Record`, in table order; ``normalise=False``: the
    values as read, not converted again (:meth:`Record.coerce`)."""
    cols = table_columns(f)
    for i in range(len(cols["hash"])):
        h = cols["hash"][i]
        if only is not None and h not in only:
            continue
        row = {name: (v[i].item() if hasattr(v[i], "item") else v[i])
               for name, v in cols.items()}
        got = profile_group(f, h)
        profiles, history = got if got is not None else ({}, np.zeros(0))
        rec = Record(row, profiles, history)
        yield Record.coerce(rec) if normalise else rec


def model_version(f: h5py.File) -> Any:
    """The model version the store's points were hashed with (its campaign's), or
    ``None`` when the store does not say."""
    try:
        return json.loads(text(f.attrs["campaign_json"]))["model_version"]
    except (KeyError, TypeError, ValueError):
        return None


def _versions_of(provenances: Iterable[str] | None, n: int, version: Any) -> list[tuple]:
    """Per row, the model versions its hash may be under: the one its ``provenance``
    records (the model that computed it) and the store's campaign's ``version``."""
    if provenances is None:
        return [(version,)] * n
    cache: dict[str, tuple] = {}
    out = []
    for prov in provenances:
        got = cache.get(prov)
        if got is None:
            try:
                own = json.loads(prov).get("model_version") if prov else None
            except (ValueError, AttributeError):
                own = None
            if not isinstance(own, (str, int)):
                own = None
            got = cache[prov] = tuple(v for v in dict.fromkeys((own, version))
                                      if v is not None)
        out.append(got)
    return out


def hash_mismatches(hashes: Iterable[str], config_jsons: Iterable[str], version: Any,
                    provenances: Iterable[str] | None = None,
                    swept: dict[str, Any] | None = None) -> list[tuple[int, str]]:
    """``(row, hash)`` of every row whose non-empty ``config_json`` does not hash to its
    ``hash`` under the model version of its ``provenance`` (the model that computed
    it) nor under the store's ``version`` (rows with neither are not checked), or whose
    swept columns (``swept``: column name -> values, the columns users select and group
    by) differ from the values in its ``config_json``."""
    hashes, config_jsons = list(hashes), list(config_jsons)
    versions = _versions_of(provenances, len(hashes), version)
    bad = []
    for i, (h, cj, vs) in enumerate(zip(hashes, config_jsons, versions, strict=True)):
        if not (cj and vs):
            continue
        if not any(config_hashes_to(cj, h, v) for v in vs) or (
                swept and not _columns_match(cj, swept, i)):
            bad.append((i, h))
    return bad


def _columns_match(config_json: str, swept: dict[str, Any], i: int) -> bool:
    """Row ``i``'s swept columns equal the values of its ``config_json``."""
    try:
        cfg = json.loads(config_json)
        cfg = cfg.get("config", cfg)
    except (ValueError, AttributeError):
        return False
    for name, col in swept.items():
        if name in cfg and col[i] != cfg[name]:
            return False
    return True


def check_hashes(path: str | Path, hashes: Iterable[str], config_jsons: Iterable[str],
                 version: Any, provenances: Iterable[str] | None = None,
                 swept: dict[str, Any] | None = None) -> None:
    """Raise :class:`StoreCorruptedError` naming the rows of :func:`hash_mismatches`."""
    bad = hash_mismatches(hashes, config_jsons, version, provenances, swept)
    if not bad:
        return
    i, h = bad[0]
    more = f" (and {len(bad) - 1} more row(s))" if len(bad) > 1 else ""
    raise StoreCorruptedError(
        f"{path}: stored point {h} (table row {i}): its config_json no longer hashes to"
        f" its hash, or its swept columns differ from it{more}; the row was altered after"
        " it was written. The store's journal"
        " holds the row as written (sweep validate lists every such row): with an intact"
        " journal, moving the store file away and running the campaign again rebuilds it",
        [h for _, h in bad])


def read_journal(path: str | Path) -> Iterator[Record]:
    """Yield the point records of a journal as written (torn or unreadable lines
    skipped; values as the journal holds them, profiles and history as arrays)."""
    for rec in Journal(path).read():
        try:
            yield Record(rec["row"], {k: np.asarray(v, dtype=np.float64)
                                      for k, v in rec.get("profiles", {}).items()},
                         np.asarray(rec.get("residual_history", []), dtype=np.float64))
        except (TypeError, ValueError, AttributeError):
            continue
