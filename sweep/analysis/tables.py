"""Exported tables (``sweep export``: ``.csv``, ``.csv.gz``, ``.parquet``) read back as a
store's table is read (:func:`sweep.load` of a table or of a directory of them), and the
typing both share."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from floewave.config import DISPERSIONS
from sweep.errors import StoreError
from sweep.identity import DIMENSIONS
from sweep.store import reader
from sweep.store.schema import COLUMNS, DERIVED, FROM_CONFIG, config_values

__all__ = ["load_table", "table_suffix", "typed_table", "column_attrs", "SharedAttr",
           "TABLE_SUFFIXES", "STATUS_ORDER"]


class SharedAttr(dict):
    """A read-only dict that ``copy.deepcopy`` returns as itself. pandas deep-copies a
    DataFrame's ``attrs`` into every frame derived from it (each column taken, each
    groupby group): with the units and long names as plain dicts that was 27 of the 86 s
    of ``sweep report`` on 3,050 points (9 million deepcopy calls)."""

    def __deepcopy__(self, memo: dict) -> SharedAttr:
        return self

    def _read_only(self, *args, **kwargs):
        raise TypeError("a table's units and long names are shared by every frame derived"
                        " from it: copy them (dict(df.attrs['units'])) to change them")

    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = _read_only


def column_attrs() -> dict[str, SharedAttr]:
    """``units`` and ``long_name`` per column, as :func:`sweep.load` puts them in
    ``DataFrame.attrs``."""
    return {"units": _UNITS, "long_name": _LONG_NAMES}

#: Every status a point can have, in the order of the ``status`` categorical.
STATUS_ORDER = ("converged", "converged_noisy", "not_converged", "failed", "invalid",
                "crashed", "timeout")

#: the file names an exported table may have (what :func:`sweep.load` reads as a table)
TABLE_SUFFIXES = (".csv.gz", ".csv", ".parquet")


def table_suffix(path: str | Path) -> str | None:
    """The table kind of ``path`` by its name (one of :data:`TABLE_SUFFIXES`), or None."""
    name = str(path).lower()
    return next((s for s in TABLE_SUFFIXES if name.endswith(s)), None)


def load_table(path: str | Path) -> pd.DataFrame:
    """The per-point table from exported tables (``sweep export``): one ``.csv``,
    ``.csv.gz`` or ``.parquet`` file, or every such file in a directory (sorted by name),
    concatenated (a table exported before schema 5 gets its ``seed`` column from each
    row's ``config_json``). Typed as :func:`load` types a store's table; every row's
    ``config_json`` must hash to its ``hash`` under its provenance's model version and no
    point may appear twice (:class:`StoreError` naming the point and its files)."""
    p = Path(path)
    files = (sorted(f for f in p.iterdir() if table_suffix(f) is not None) if p.is_dir()
             else [p])
    if not files:
        raise StoreError(f"{path}: no exported table (.csv, .csv.gz, .parquet) in it")
    frames = []
    for f in files:
        if not f.is_file():
            raise StoreError(f"{f}: no such table")
        try:
            if table_suffix(f) == ".parquet":
                frame = pd.read_parquet(f)
            else:       # strings stay strings (a hash of digits is not a number)
                frame = pd.read_csv(f, dtype={c: str for c in _TEXT_COLUMNS})
                for c in _TEXT_COLUMNS & set(frame.columns):
                    frame[c] = frame[c].fillna("")      # an empty text cell is ""
        except (OSError, ValueError) as exc:
            raise StoreError(f"{f}: cannot read the table: {exc}") from None
        frame["_file"] = f.name
        frames.append(frame)
    df = pd.concat(frames, ignore_index=True)
    for c in FROM_CONFIG:       # a table exported before schema 5: from each config_json
        if c not in df and "config_json" in df:
            at = df.columns.get_loc("dispersion") + 1 if "dispersion" in df else len(df.columns)
            df.insert(at, c, pd.array(config_values(c, df["config_json"].astype(str)),
                                      dtype="int64"))
    missing = [c for c in ("hash", "config_json", "status", *DIMENSIONS)
               if c not in df]
    if missing:
        raise StoreError(f"{path}: not a sweep table (no column {missing[0]})")
    dup = df["hash"].duplicated(keep=False)
    if dup.any():
        h = df.loc[dup, "hash"].iloc[0]
        where = ", ".join(sorted(set(df.loc[df["hash"] == h, "_file"])))
        raise StoreError(f"{path}: point {h} appears {int((df['hash'] == h).sum())} times"
                         f" ({where}): a campaign's tables hold each point once")
    prov = df["provenance"].astype(str) if "provenance" in df else None
    swept = {k: df[k].to_numpy() for k in DIMENSIONS}
    swept["dispersion"] = df["dispersion"].astype(str).to_numpy()
    reader.check_hashes(path, df["hash"].astype(str), df["config_json"].astype(str), None,
                        prov, swept)
    df = typed_table(df.drop(columns="_file"))
    df.attrs.update(column_attrs())
    df.attrs["files"] = tuple(f.name for f in files)
    return df


#: text columns of a table (read as strings from CSV, never parsed as numbers)
_TEXT_COLUMNS = {"hash", "status", "message", "dispersion", "compact_zone", "kernel_mode",
                 "host", "start_time", "end_time", "config_json", "provenance"}



def typed_table(df: pd.DataFrame) -> pd.DataFrame:
    """Times as UTC datetimes (NaT where unset), status and dispersion as categoricals
    (statuses in :data:`STATUS_ORDER`; dispersions: ep, ml, ow, whatever the store holds)."""
    for name in ("start_time", "end_time"):
        df[name] = pd.to_datetime(df[name].replace("", None), utc=True, format="ISO8601")
    extra = sorted(set(df["status"]) - set(STATUS_ORDER))
    df["status"] = pd.Categorical(df["status"], categories=list(STATUS_ORDER) + extra)
    # every dispersion relation floewave knows, so tables of two stores concatenate as
    # categoricals (categories taken from each store's data would differ)
    df["dispersion"] = pd.Categorical(
        df["dispersion"], categories=sorted(set(DISPERSIONS) | set(df["dispersion"])))
    return df


_UNITS = SharedAttr((c.name, c.units) for c in (*COLUMNS, *DERIVED))
_LONG_NAMES = SharedAttr((c.name, c.long_name) for c in (*COLUMNS, *DERIVED))
