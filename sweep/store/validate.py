"""Checking a store file against the schema: attributes, columns, hashes, statuses, profiles.

:func:`validate` returns the problems found (``sweep validate``); the deep comparison
with the journal is :mod:`sweep.store.verify`.
"""
from __future__ import annotations

from pathlib import Path

import h5py

from sweep.errors import SchemaVersionError
from sweep.identity import DIMENSIONS, HASH_LENGTH
from sweep.store import reader
from sweep.store.migrate import migration_steps
from sweep.store.schema import (
    ADDED_IN,
    COLUMNS,
    FORMAT,
    HISTORY_VAR,
    PROFILE_VARS,
    REPLICA_VARS,
    ROOT_ATTRS,
    SCHEMA_VERSION,
    STATUSES,
    profile_path,
)

__all__ = ["validate"]


def validate(path: str | Path) -> list[str]:
    """Check a store against this schema; returns the problems found (empty: valid).

    Checks the root attributes and version (an older version with a migration path is
    valid: readers read it as it is, a writer migrates it), that every column of its
    version exists, has the kind of
    its schema entry and at least ``n_rows`` values, that hashes are unique 64-hex
    strings and statuses known, and that every committed non-failed point has a profile
    group whose datasets have length ``n_floes``.
    """
    problems: list[str] = []
    try:
        f = h5py.File(path, "r", locking=False)
    except OSError as exc:
        return [f"{path}: not a readable HDF5 file: {reader.not_a_store(path) or exc}"]
    with f:
        for key in ROOT_ATTRS:
            if key not in f.attrs:
                problems.append(f"/: missing attribute {key!r}")
        version = f.attrs.get("schema_version")
        try:
            version = SCHEMA_VERSION if version is None else int(version)
        except (TypeError, ValueError):
            return problems + [f"/: schema_version {version!r} is not a number"]
        if version > SCHEMA_VERSION:
            problems.append(f"/: schema_version {version} is newer than {SCHEMA_VERSION}")
        else:
            try:
                migration_steps(version)
            except SchemaVersionError:
                problems.append(f"/: schema_version {version} has no migration to"
                                f" {SCHEMA_VERSION}")
        if f.attrs.get("format") not in (FORMAT, FORMAT.encode()):
            problems.append(f"/: format {f.attrs.get('format')!r} != {FORMAT!r}")
        if "table" not in f:
            return problems + ["/table: missing"]
        n = int(f["table"].attrs.get("n_rows", -1))
        if n < 0:
            problems.append("/table: missing attribute 'n_rows'")
        for col in COLUMNS:
            if col.name not in f["table"]:
                if ADDED_IN.get(col.name, 1) > version:
                    continue        # an older (readable, migratable) store lacks it
                problems.append(f"/table/{col.name}: missing")
                continue
            ds = f["table"][col.name]
            kind = ds.dtype.kind
            ok = {"float": kind == "f", "int": kind in "iu", "str": kind in "OSU"}[col.kind]
            if not ok:
                problems.append(f"/table/{col.name}: dtype {ds.dtype} is not {col.kind}")
            if ds.shape[0] < n:
                problems.append(f"/table/{col.name}: {ds.shape[0]} values < n_rows {n}")
        if problems:
            return problems
        table = f["table"]
        swept_names = tuple(DIMENSIONS)
        cols = reader.table_columns(f, ("hash", "status", "config_json", "provenance",
                                        *swept_names), n)
        hashes, status = list(cols["hash"]), list(cols["status"])
        n_floes = table["n_floes"][:n]
        replicas = table["replicas"][:n] if "replicas" in table else None
        if len(set(hashes)) != len(hashes):
            problems.append("/table/hash: duplicate hashes")
        if "campaign_json" in f.attrs:
            well_formed = [(i, h, cj, prov) for i, (h, cj, prov) in enumerate(zip(
                hashes, cols["config_json"], cols["provenance"], strict=True))
                if len(h) == HASH_LENGTH and set(h) <= set("0123456789abcdef")]
            rows = [w[0] for w in well_formed]
            for k, h in reader.hash_mismatches([w[1] for w in well_formed],
                                               [w[2] for w in well_formed],
                                               reader.model_version(f),
                                               [w[3] for w in well_formed],
                                               {c: [cols[c][r] for r in rows]
                                                for c in swept_names if c in cols}):
                problems.append(f"/table/config_json[{well_formed[k][0]}]: does not hash"
                                f" to its hash {h}, or the row's swept columns differ from"
                                " it (the row was altered after it was written)")
        for i, (h, s) in enumerate(zip(hashes, status, strict=False)):
            if len(h) != HASH_LENGTH or any(c not in "0123456789abcdef" for c in h):
                problems.append(f"/table/hash[{i}]: {h!r} is not a {HASH_LENGTH}-character"
                                " hex hash")
                continue
            if s not in STATUSES:
                problems.append(f"/table/status[{i}]: unknown status {s!r}")
            if s in ("failed", "invalid", "crashed", "timeout"):
                continue
            name = profile_path(h)
            # the point's group opened once and its members listed once (a path lookup
            # per dataset made this loop 55 s for 24,192 points)
            g = f.get(name)
            if not isinstance(g, h5py.Group):
                problems.append(f"/{name}: missing profile group of a {s} point")
                continue
            present = set(g.keys())
            nf = int(n_floes[i])
            for var in PROFILE_VARS:
                if var not in present:
                    problems.append(f"/{name}/{var}: missing")
                elif (shp := g[var].shape) != (nf,):
                    problems.append(f"/{name}/{var}: shape {shp} != ({nf},)")
            if HISTORY_VAR[0] not in present:
                problems.append(f"/{name}/{HISTORY_VAR[0]}: missing")
            R = int(replicas[i]) if replicas is not None else -1
            for var, (_, _, shape) in REPLICA_VARS.items():
                if var not in present:
                    continue        # optional: points stored before schema 3
                want = tuple({"R": R, "N_f": nf}[d] for d in shape)
                if (shp := g[var].shape) != want:
                    problems.append(f"/{name}/{var}: shape {shp} != {want}")
    return problems
