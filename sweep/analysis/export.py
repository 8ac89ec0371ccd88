"""Writing a store's table to a file: CSV, or Parquet when pyarrow (or fastparquet) is there."""
from __future__ import annotations

import importlib.util
from pathlib import Path

from floewave.paths import output_file_problem
from sweep.analysis.load import load
from sweep.analysis.tables import table_suffix
from sweep.errors import ConfigError, StoreError

__all__ = ["export_table", "parquet_engine"]


def export_table(store: str | Path, output: Path) -> int:
    """Write the table of ``store`` to ``output`` (``.csv``, ``.csv.gz`` or ``.parquet``); return the
    number of rows. :class:`ConfigError` for an output it cannot write (name, missing
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
