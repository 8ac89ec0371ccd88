"""Reading a store: pandas table, xarray grid, per-point profiles.

Readers open the file read-only without HDF5 file locking, so they never block the
writer; only committed rows (below ``/table.attrs["n_rows"]``) are returned.
"""
from __future__ import annotations

import json
import os
import re
import time
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pandas as pd
import xarray as xr

from sweep.analysis.tables import (
    STATUS_ORDER,
    column_attrs,
    load_table,
    table_suffix,
    typed_table,
)
from sweep.errors import PointNotFoundError, StoreError, StoreUnreadableError
from sweep.identity import DIMENSIONS
from sweep.store import reader
from sweep.store.cells import text
from sweep.store.journal import journal_path
from sweep.store.schema import (
    COLUMNS,
    DERIVED,
    DERIVED_FROM,
    HISTORY_VAR,
    PROFILE_VARS,
    REPLICA_VARS,
    column,
)

__all__ = ["load", "load_table", "load_xarray", "load_profile", "load_profiles", "read_profiles",
           "store_attrs",
           "store_runs",
           "resolve_hash", "journal_points", "STATUS_ORDER", "PROFILE_LEADING_DIMS"]

#: Statuses without results: NaN in :func:`load_xarray` and :func:`load_profiles`.
NO_RESULT = ("failed", "invalid", "crashed", "timeout")
#: Names of a profile's leading axes when it has more than the floe axis (a profile of
#: shape (R, N_f) gets dimensions ("replica", "floe")).
PROFILE_LEADING_DIMS = ("replica",)

#: Columns that are bookkeeping, not results: left out of :func:`load_xarray`.
_NOT_RESULTS = {"hash", "message", "host", "rank", "pid", "start_time", "end_time", "run",
                "seq", "config_json", "provenance", "kernel_mode"}


def _open(path: str | Path) -> h5py.File:
    try:
        return reader.open_file(path)
    except (OSError, FileNotFoundError) as exc:
        why = reader.not_a_store(path)
        if why is not None:  # one line, no HDF5 message (exit status 3)
            raise StoreError(f"{path}: {why}") from None
        cls = StoreUnreadableError if Path(path).is_file() else StoreError
        raise cls(f"{path}: cannot open store: {exc}") from None


def store_attrs(path: str | Path) -> dict[str, Any]:
    """The root attributes of a store (strings decoded)."""
    def read() -> dict[str, Any]:
        with _open(path) as f:
            return reader.attrs_of(f)

    return _retried(read)


def store_runs(path: str | Path) -> list[dict[str, Any]]:
    """One dict per ``sweep run`` on the store (``/runs/<n>`` attributes, strings decoded,
    plus ``index``), oldest first."""
    def read() -> list[dict[str, Any]]:
        with _open(path) as f:
            if "runs" not in f:
                return []
            out = []
            for name in sorted(f["runs"], key=int):
                out.append({"index": int(name), **reader.attrs_of(f["runs"][name])})
            return out

    return _retried(read)


def journal_points(path: str | Path) -> int | None:
    """Distinct points recorded in the store's journal (``None`` without a journal).

    Counts what is durable even when the HDF5 file lags behind (a live run between its
    journal write and its HDF5 write, or a killed run whose next start writes them).
    A quick count: the hash of each record line, not its checksum.
    """
    jp = journal_path(os.path.realpath(path))  # beside the file, as the writer names it
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
            if not isinstance(exc, StoreUnreadableError) or attempt == READ_RETRIES:
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
    a read that fails while a live writer commits is tried again.

    ``path`` may also be a table ``sweep export`` wrote (``.csv``, ``.csv.gz``,
    ``.parquet``) or a directory of them (the shards of one campaign, e.g.
    ``results/herman2019``): :func:`load_table`."""
    if Path(path).is_dir() or table_suffix(path) is not None:
        return load_table(path)
    try:
        return _retried(lambda: _load(path))
    except KeyError as exc:
        raise StoreError(f"{path}: cannot read the store: {exc}") from None


def _load(path: str | Path) -> pd.DataFrame:
    """The per-point table as a DataFrame: one row per stored point.

    Columns are those of :data:`sweep.store.schema.COLUMNS` (swept values, status, message,
    scalar results and diagnostics, provenance); ``DataFrame.attrs`` holds ``units`` and
    ``long_name`` per column and the campaign JSON.
    """
    with _open(path) as f:
        if "table" not in f:
            raise StoreError(f"{path}: not a sweep store (no /table)")
        data = reader.table_columns(f)
        campaign = text(f.attrs.get("campaign_json", ""))
        # every row's config_json still hashes to its hash (StoreCorruptedError if not)
        reader.check_hashes(path, data["hash"], data["config_json"], reader.model_version(f),
                            data["provenance"],
                            {k: data[k] for k in DIMENSIONS if k in data})
    df = _with_derived(typed_table(pd.DataFrame(data)))
    df.attrs.update(column_attrs())         # shared, not deep-copied into every derived frame
    df.attrs["campaign"] = campaign
    return df


def _with_derived(df: pd.DataFrame) -> pd.DataFrame:
    """The :data:`sweep.store.schema.DERIVED` columns (``a_end_rel = a_end / a0`` and its standard
    error), each placed after the column it is computed from."""
    for col in DERIVED:
        num, den = DERIVED_FROM[col.name]
        values = df[num].astype(float) / df[den].astype(float)
        df.insert(df.columns.get_loc(num) + 1, col.name, values)
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
    keep = [c.name for c in (*COLUMNS, *DERIVED) if c.name not in _NOT_RESULTS
            and c.name not in dims
            and c.name not in ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")]
    bad = df["status"].isin(NO_RESULT)
    values = df[dims + keep].copy()
    for name in dims + keep:
        if isinstance(values[name].dtype, pd.CategoricalDtype):
            values[name] = values[name].astype(object)
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
        if col.kind == "int":  # integers stay integers: -1 where missing or failed
            ds[name] = ds[name].fillna(col.fill).astype(np.int64)
            ds[name].attrs.update(units=col.units, long_name=col.long_name,
                                  missing_value=col.fill)
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
        hint = ("" if matches else "; the stored hashes are in sweep.load(path)['hash'], or"
                " select by parameters with sweep.load_profiles(path, eps=..., ...)")
        raise PointNotFoundError(f"{path}: {len(matches)} stored points have a hash"
                                 f" starting with {prefix!r}{hint}", store=str(path),
                                 key=prefix)
    return matches[0]


def load_profile(path: str | Path, hash: str) -> xr.Dataset:
    """One point's profiles along the floe index (and residual history per iteration;
    for an ensemble stored with schema 3, the per-replica results along ``replica``).

    Reads only that point's group. ``hash`` may be a unique prefix (the short hash).
    """
    h = hash if len(hash) == 64 else resolve_hash(path, hash)

    def read() -> tuple[dict[str, Any], Any, dict[str, Any]] | None:
        with _open(path) as f:
            got = reader.profile_group(f, h)
            if got is None:
                return None
            profiles, history = got
            rep = {k: profiles[k] for k in REPLICA_VARS if k in profiles}
            return {k: profiles[k] for k in PROFILE_VARS}, history, rep

    got = _retried(read)
    if got is None:
        raise PointNotFoundError(f"{path}: no profiles stored for point {h[:12]} (missing,"
                                 " failed or invalid)", store=str(path), key=h)
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


def read_profiles(path: str | Path, hashes: list[str],
                  names: tuple[str, ...]) -> dict[str, dict[str, np.ndarray]]:
    """The profiles ``names`` of the points ``hashes`` that have all of them (hash ->
    name -> array), read in one open of the store."""
    def read() -> dict[str, dict[str, np.ndarray]]:
        out = {}
        with _open(path) as f:
            for h in hashes:
                got = reader.profile_group(f, h, names, history=False)
                if got is not None and all(k in got[0] for k in names):
                    out[h] = got[0]
        return out

    return _retried(read)


def _selected(df: pd.DataFrame, dims: list[str], selectors: dict[str, Any],
              path: str | Path) -> pd.DataFrame:
    """Rows of ``df`` whose swept values match ``selectors`` (a value or a list; floats
    compared with a relative tolerance of 1e-9)."""
    keep = np.ones(len(df), bool)
    for name, want in selectors.items():
        if name not in dims:
            raise PointNotFoundError(f"{path}: {name!r} is not a swept parameter of this"
                                     f" campaign (swept: {', '.join(dims)})", store=str(path),
                                     key=name)
        wanted = list(want) if isinstance(want, (list, tuple, np.ndarray)) else [want]
        col = df[name].astype(object)
        hit = np.zeros(len(df), bool)
        for w in wanted:
            if isinstance(w, str):
                hit |= (col == w).to_numpy()
            else:
                hit |= np.isclose(col.astype(float), float(w), rtol=1e-9, atol=0.0)
        keep &= hit
    return df[keep]


def load_profiles(path: str | Path, **selectors: Any) -> xr.Dataset:
    """Every point's profiles along the swept dimensions plus a floe dimension.

    ``sweep.load_profiles("demo.h5", eps=0.6, dispersion="ml")`` keeps the points with
    those values; a scalar selector drops its dimension (as ``Dataset.sel`` does), a list
    keeps it with those values. Every variable of :data:`sweep.store.schema.PROFILE_VARS`
    becomes a variable with dimensions (swept..., floe) -- or (swept..., replica, floe)
    for a profile stored with a leading axis (:data:`PROFILE_LEADING_DIMS`) -- with its
    ``units`` and ``long_name``. The floe axis is as long as the longest sheet (N_f
    differs with L_x): shorter profiles, missing points and points without results
    (failed, invalid, crashed, timeout) are NaN. ``status`` and ``hash`` per point, and
    ``x`` (the time-mean floe centre, a coordinate) come along, so
    ``ds.a.sel(L_x=0.5).plot(x="x", hue="eps")`` works.

    ``path`` may also be a profiles file ``sweep export --profiles`` wrote (``.nc``) or a
    directory of them (a campaign's shards, e.g. ``results/herman2019``): then the
    Dataset has dimensions (point, floe) as the file has
    (:func:`sweep.analysis.profiles_file.load_profiles_file`).

    Raises
    ------
    PointNotFoundError
        A selector names a parameter that is not swept, or no point matches.
    """
    if Path(path).is_dir() or Path(path).suffix == ".nc":
        from sweep.analysis.profiles_file import load_profiles_file  # lazy: cycle
        return load_profiles_file(path, **selectors)
    df = load(path)
    attrs = store_attrs(path)
    campaign = json.loads(attrs["campaign_json"])
    dims = list(json.loads(attrs["swept_fields"]))
    df = _selected(df, dims, selectors, path)
    if df.empty:
        raise PointNotFoundError(f"{path}: no stored point matches {selectors}",
                                 store=str(path), key=str(selectors))
    coords: dict[str, np.ndarray] = {}
    for d in dims:
        values = sorted(campaign["sweep"][d])
        if d in selectors:
            values = [v for v in values if not _selected(pd.DataFrame({d: [v]}), [d],
                                                         {d: selectors[d]}, path).empty]
        coords[d] = np.asarray(values)
    hashes = list(df["hash"])
    good = ~df["status"].isin(NO_RESULT).to_numpy()

    def read() -> dict[str, dict[str, np.ndarray]]:
        out: dict[str, dict[str, np.ndarray]] = {}
        with _open(path) as f:
            for h, ok in zip(hashes, good, strict=True):
                got = reader.profile_group(f, h, PROFILE_VARS, history=False) if ok else None
                if got is not None:
                    out[h] = {k: np.asarray(v, dtype=float) for k, v in got[0].items()}
        return out

    data = _retried(read)
    # the shape of each variable: the largest along every axis over the points
    shapes: dict[str, tuple[int, ...]] = {}
    for prof in data.values():
        for k, v in prof.items():
            old = shapes.get(k, (0,) * v.ndim)
            shapes[k] = tuple(max(a, b) for a, b in zip(old, v.shape, strict=True))
    n_floe = max((s[-1] for s in shapes.values()), default=0)
    grid_shape = tuple(len(coords[d]) for d in dims)
    index = {d: {v: i for i, v in enumerate(coords[d])} for d in dims}

    def where(row: Any) -> tuple[int, ...]:
        return tuple(index[d][_grid_value(coords[d], getattr(row, d))] for d in dims)

    ds = xr.Dataset(coords={**{d: coords[d] for d in dims}, "floe": np.arange(n_floe)})
    status = np.full(grid_shape, "missing", dtype=object)
    hash_ = np.full(grid_shape, "", dtype=object)
    for row in df.itertuples():
        status[where(row)] = str(row.status)
        hash_[where(row)] = row.hash
    for k, (units, long_name) in PROFILE_VARS.items():
        # a variable no selected point has (all failed): all NaN, still there
        lead = shapes.get(k, (n_floe,))[:-1]
        arr = np.full(grid_shape + lead + (n_floe,), np.nan)
        for row in df.itertuples():
            v = data.get(row.hash, {}).get(k)
            if v is not None:
                arr[where(row) + tuple(slice(0, m) for m in v.shape)] = v
        lead_dims = tuple(PROFILE_LEADING_DIMS[i] if i < len(PROFILE_LEADING_DIMS)
                          else f"{k}_dim{i}" for i in range(len(lead)))
        ds[k] = (tuple(dims) + lead_dims + ("floe",), arr)
        ds[k].attrs.update(units=units, long_name=long_name)
    ds["status"] = (tuple(dims), status)
    ds["status"].attrs["long_name"] = "point status ('missing': not stored)"
    ds["hash"] = (tuple(dims), hash_)
    ds["hash"].attrs["long_name"] = "point identity (SHA-256 of its configuration)"
    if "x_mean" in ds and ds["x_mean"].ndim == len(dims) + 1:
        ds = ds.assign_coords(x=ds["x_mean"])
        ds["x"].attrs.update(units="m", long_name="time-mean floe centre from the ice edge")
    ds["floe"].attrs.update(long_name="floe index from the ice edge")
    for d in dims:
        col = column(d)
        ds[d].attrs.update(units=col.units, long_name=col.long_name)
    scalar = {d: coords[d][0] for d in dims if d in selectors
              and not isinstance(selectors[d], (list, tuple, np.ndarray))}
    if scalar:
        ds = ds.isel({d: 0 for d in scalar})
    ds.attrs.update(campaign=attrs["campaign_json"], source=str(path),
                    schema_version=int(attrs["schema_version"]))
    return ds


def _grid_value(values: np.ndarray, v: Any) -> Any:
    """The campaign grid value equal to the stored ``v`` (floats to 1e-9 relative)."""
    if isinstance(v, str):
        return v
    return values[int(np.argmin(np.abs(values.astype(float) - float(v))))]
