"""Writing a store's table to a file (CSV, or Parquet when pyarrow or fastparquet is there),
and its profiles to a netCDF file (:mod:`sweep.analysis.profiles_file`)."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pandas as pd

from floewave.paths import output_file_problem
from sweep.analysis.load import load, read_profiles, store_attrs, store_runs
from sweep.analysis.profiles_file import (
    ENCODING,
    PARAMETERS,
    PROFILE_FILE_VARS,
    PROFILE_STORE_VARS,
    check_profiles_output,
    profiles_dataset,
)
from sweep.analysis.tables import table_suffix
from sweep.errors import ConfigError, StoreError

__all__ = ["export_table", "export_profiles", "parquet_engine"]


def export_table(store: str | Path, output: Path) -> int:
    """Write the table of ``store`` to ``output`` (``.csv``, ``.csv.gz`` or ``.parquet``);
    return the number of rows. :class:`ConfigError` for an output it cannot write (name, missing
    engine), :class:`StoreError` when the write fails (a full disk)."""
    suffix = table_suffix(output)
    if suffix is None:
        raise ConfigError(f"--output {output}: expected a .csv, .csv.gz or .parquet file"
                          " name")
    problem = output_file_problem(output, "--output")
    if problem:
        raise ConfigError(problem)
    if suffix == ".parquet" and not parquet_engine():
        raise ConfigError(f"--output {output}: Parquet needs pyarrow:"
                          " pip install 'floewave[parquet]' (or write .csv)")
    df = load(store)
    try:
        if suffix in (".csv", ".csv.gz"):
            # floats as their shortest round-trip text: read back bit for bit
            df.to_csv(output, index=False)
        else:
            df.to_parquet(output, index=False)
    except OSError as exc:  # a full disk (/dev/full), an I/O error
        raise StoreError(f"--output {output}: cannot be written:"
                         f" {exc.strerror or exc}") from None
    return len(df)


def parquet_engine() -> bool:
    """Whether pandas can write Parquet (pyarrow or fastparquet importable)."""
    return any(importlib.util.find_spec(m) is not None for m in ("pyarrow", "fastparquet"))


def export_profiles(store: str | Path, output: str | Path,
                    df: pd.DataFrame | None = None) -> int:
    """Write the profiles of ``store``'s points (those of ``df``, default every stored
    point, in its order; points without results have none) to ``output`` (``.nc``,
    :mod:`sweep.analysis.profiles_file`); return the number of points written.
    :class:`ConfigError` for an output it cannot write, :class:`StoreError` when the write
    fails."""
    output = Path(output)
    check_profiles_output(output)
    df = load(store) if df is None else df
    data = read_profiles(store, list(df["hash"]), PROFILE_STORE_VARS)
    if not data:
        raise StoreError(f"{store}: no point has profiles to write (all failed, invalid or"
                         " stored before profiles); nothing written")
    attrs = store_attrs(store)
    version = json.loads(attrs.get("campaign_json") or "{}").get("model_version", "unknown")
    commits = sorted({str(r.get("git_commit")) for r in store_runs(store)})
    swept = tuple(json.loads(attrs.get("swept_fields") or "[]")) or PARAMETERS
    parameters = tuple(dict.fromkeys((*PARAMETERS, *swept)))
    from sweep.provenance import git_state
    ds = profiles_dataset(df, data, str(version), commits,
                          str(attrs.get("campaign_hash", "")),
                          tuple(p for p in parameters if p in df),
                          f"commit {git_state()[0]}")
    enc = {k: dict(ENCODING, chunksizes=(min(512, max(ds.sizes["point"], 1)),
                                         max(ds.sizes["floe"], 1)))
           for k in (*PROFILE_FILE_VARS, "x")}
    tmp = output.with_name(output.name + ".part")
    try:
        ds.to_netcdf(tmp, engine="h5netcdf", encoding=enc)
        tmp.replace(output)
    except OSError as exc:
        raise StoreError(f"--profiles {output}: cannot be written:"
                         f" {exc.strerror or exc}") from None
    finally:
        tmp.unlink(missing_ok=True)
    return int(ds.sizes["point"])
