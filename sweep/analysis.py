"""Reading a store: pandas table, xarray grid, per-point profiles.

Readers open the file read-only without HDF5 file locking, so they never block the
writer; only committed rows (below ``/table.attrs["n_rows"]``) are returned.
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pandas as pd
import xarray as xr

from .errors import StoreError
from .schema import (
    COLUMNS,
    HISTORY_VAR,
    MIGRATION_FILL,
    PROFILE_VARS,
    REPLICA_VARS,
    column,
    profile_path,
)

__all__ = ["load", "load_xarray", "load_profile", "store_attrs", "resolve_hash",
           "journal_points"]

#: Columns that are bookkeeping, not results: left out of :func:`load_xarray`.
_NOT_RESULTS = {"hash", "message", "host", "rank", "pid", "start_time", "end_time", "run",
                "seq", "config_json", "provenance", "kernel_mode"}


class _OpenError(StoreError):
    """The file exists but HDF5 cannot open it (yet): a writer may be mid-commit."""


def _open(path: str | Path) -> h5py.File:
    try:
        return h5py.File(path, "r", locking=False)
    except (OSError, FileNotFoundError) as exc:
        cls = _OpenError if Path(path).is_file() else StoreError
        raise cls(f"{path}: cannot open store: {exc}") from None


def _decode(values: np.ndarray) -> np.ndarray:
    if values.dtype.kind == "O" or values.dtype.kind == "S":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in values],
                        dtype=object)
    return values


def store_attrs(path: str | Path) -> dict[str, Any]:
    """The root attributes of a store (strings decoded)."""
    def read() -> dict[str, Any]:
        with _open(path) as f:
            return {k: (v.decode() if isinstance(v, bytes) else v)
                    for k, v in f.attrs.items()}

    return _retried(read)


def journal_points(path: str | Path) -> int | None:
    """Distinct points recorded in the store's journal (``None`` without a journal).

    Counts what is durable even when the HDF5 file lags behind (a live run between its
    journal write and its HDF5 write, or a killed run whose next start writes them).
    A quick count: the hash of each record line, not its checksum.
    """
    import re

    from .journal import journal_path

    jp = journal_path(path)
    if not jp.exists():
        return None
    pattern = re.compile(rb'"hash":"([0-9a-f]{64})"')
    seen = set()
    with open(jp, "rb") as fh:
        for line in fh:
            if line.startswith(b'{"row":') and line.endswith(b"\n"):
                m = pattern.search(line)
                if m:
                    seen.add(m.group(1))
    return len(seen)


#: A read that fails while a writer changes the file is tried again this many times,
#: after 0.05, 0.1, 0.2 ... s (readers open without HDF5 locking and may see metadata
#: half-written; each commit ends with a flush, so a later read sees a consistent file).
READ_RETRIES = 6


def _retried(read: Any) -> Any:
    """Run ``read()``; on an HDF5 read error try again (a writer is mid-commit)."""
    delay = 0.05
    for attempt in range(READ_RETRIES + 1):
        try:
            return read()
        except StoreError as exc:
            if not isinstance(exc, _OpenError) or attempt == READ_RETRIES:
                raise
            time.sleep(delay)
            delay *= 2
        except (OSError, RuntimeError, ValueError, KeyError, TypeError):
            if attempt == READ_RETRIES:
                raise
            time.sleep(delay)
            delay *= 2
    raise AssertionError("unreachable")  # pragma: no cover


def load(path: str | Path) -> pd.DataFrame:
    """The per-point table as a DataFrame: one row per stored point (see :func:`_load`);
    a read that fails while a live writer commits is tried again."""
    try:
        return _retried(lambda: _load(path))
    except KeyError as exc:
        raise StoreError(f"{path}: cannot read the store: {exc}") from None


def _load(path: str | Path) -> pd.DataFrame:
    """The per-point table as a DataFrame: one row per stored point.

    Columns are those of :data:`sweep.schema.COLUMNS` (swept values, status, message,
    scalar results and diagnostics, provenance); ``DataFrame.attrs`` holds ``units`` and
    ``long_name`` per column and the campaign JSON.
    """
    with _open(path) as f:
        if "table" not in f:
            raise StoreError(f"{path}: not a sweep store (no /table)")
        table = f["table"]
        n = int(table.attrs["n_rows"])
        # a column an older schema version lacks reads as its fill value
        data = {c.name: (_decode(table[c.name][:n]) if c.name in table
                         else np.full(n, MIGRATION_FILL.get(c.name, c.fill),
                                      dtype=object if c.kind == "str" else None))
                for c in COLUMNS}
        campaign = f.attrs.get("campaign_json", "")
    df = pd.DataFrame(data)
    df.attrs["units"] = {c.name: c.units for c in COLUMNS}
    df.attrs["long_name"] = {c.name: c.long_name for c in COLUMNS}
    df.attrs["campaign"] = campaign.decode() if isinstance(campaign, bytes) else campaign
    return df


def load_xarray(path: str | Path) -> xr.Dataset:
    """The campaign as an xarray Dataset with one dimension per swept parameter.

    Swept parameters are coordinates holding the campaign's full value lists, so a
    point that is missing, ``failed`` or ``invalid`` is NaN in every numeric variable
    (its ``status`` is kept). Every variable has ``units`` and ``long_name``; the
    campaign definition is the JSON string attribute ``campaign``.
    """
    df = load(path)
    attrs = store_attrs(path)
    campaign = json.loads(attrs["campaign_json"])
    dims = json.loads(attrs["swept_fields"])
    coords = {d: np.asarray(sorted(campaign["sweep"][d])) for d in dims}
    keep = [c.name for c in COLUMNS if c.name not in _NOT_RESULTS and c.name not in dims
            and c.name not in ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")]
    bad = df["status"].isin(["failed", "invalid", "crashed", "timeout"])
    values = df[dims + keep].copy()
    for name in keep:
        if column(name).kind != "str":
            values[name] = values[name].astype(float)
            values.loc[bad, name] = np.nan
    ds = values.set_index(dims).to_xarray() if len(values) else xr.Dataset(
        coords={d: [] for d in dims})
    ds = ds.reindex(coords)
    for name in list(ds.data_vars):
        col = column(name)
        ds[name].attrs.update(units=col.units, long_name=col.long_name)
    for d in dims:
        col = column(d)
        ds[d].attrs.update(units=col.units, long_name=col.long_name)
    ds.attrs.update(campaign=attrs["campaign_json"], campaign_toml=attrs["campaign_toml"],
                    schema_version=int(attrs["schema_version"]), source=str(path))
    return ds


def resolve_hash(path: str | Path, prefix: str) -> str:
    """The full hash of the one stored point whose hash starts with ``prefix``."""
    df = load(path)
    matches = [h for h in df["hash"] if h.startswith(prefix.lower())]
    if len(matches) != 1:
        raise KeyError(f"{path}: {len(matches)} stored points have a hash starting with"
                       f" {prefix!r}")
    return matches[0]


def load_profile(path: str | Path, hash: str) -> xr.Dataset:
    """One point's profiles along the floe index (and residual history per iteration;
    for an ensemble stored with schema 3, the per-replica results along ``replica``).

    Reads only that point's group. ``hash`` may be a unique prefix (the short hash).
    """
    h = hash if len(hash) == 64 else resolve_hash(path, hash)

    def read() -> tuple[dict[str, Any], Any] | None:
        with _open(path) as f:
            name = profile_path(h)
            if name not in f:
                return None
            g = f[name]
            rep = {k: g[k][()] for k in REPLICA_VARS if k in g}
            return {k: g[k][()] for k in PROFILE_VARS}, g[HISTORY_VAR[0]][()], rep

    got = _retried(read)
    if got is None:
        raise KeyError(f"{path}: no profiles stored for point {h[:12]} (missing, failed"
                       " or invalid)")
    data, history, rep = got
    n = len(data["a"])
    ds = xr.Dataset({k: ("floe", v) for k, v in data.items()},
                    coords={"floe": np.arange(n)})
    ds["x"] = ("floe", data["x_mean"])
    ds = ds.set_coords("x")
    ds["residual_history"] = ("iteration", history)
    ds = ds.assign_coords(iteration=np.arange(1, len(history) + 1))
    for k, (units, long_name) in PROFILE_VARS.items():
        ds[k].attrs.update(units=units, long_name=long_name)
    ds["x"].attrs.update(units="m", long_name="time-mean floe centre from the ice edge")
    ds["residual_history"].attrs.update(units=HISTORY_VAR[1], long_name=HISTORY_VAR[2])
    ds["floe"].attrs.update(long_name="floe index from the ice edge")
    for k, v in rep.items():      # ensembles (schema 3): per-replica results
        units, long_name, shape = REPLICA_VARS[k]
        dims = tuple({"R": "replica", "N_f": "floe"}[d] for d in shape)
        ds[k] = (dims, v)
        ds[k].attrs.update(units=units, long_name=long_name)
    if rep:
        R = next(iter(rep.values())).shape[0]
        ds = ds.assign_coords(replica=np.arange(R))
        ds["replica"].attrs.update(long_name="replica index of the ensemble")
    ds.attrs["hash"] = h
    return ds
