"""Values converted to and from the store's cells: records normalised, stored text decoded.

A record is normalised (:func:`normalise_record`) *before* it is journaled, so a record
that reaches the journal can be written; :class:`sweep.errors.UnstorableError` names a
value that cannot. HDF5 gives strings back as ``bytes`` or ``str``: :func:`text` and
:func:`texts` decode them.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from sweep.errors import UnstorableError
from sweep.store.schema import COLUMNS, FROM_CONFIG, PROFILE_VARS, REPLICA_VARS, config_values

__all__ = ["normalise_record", "check_profiles", "text", "texts", "NO_PROFILES"]

_STORED = {c.name: c for c in COLUMNS}

_I64 = (-(2 ** 63), 2 ** 63 - 1)
#: Statuses stored without profiles (every other status has each of PROFILE_VARS, of
#: length n_floes: what `sweep validate` checks).
NO_PROFILES = ("failed", "invalid", "crashed", "timeout")


def _clean_str(value: Any) -> str:
    """A string HDF5 can store as UTF-8: lone surrogates and NULs escaped."""
    s = value.decode("utf-8", "backslashreplace") if isinstance(value, bytes) else str(value)
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        s = s.encode("utf-8", "backslashreplace").decode("utf-8")
    return s.replace("\x00", "\\x00")


def _convert(kind: str, name: str, value: Any) -> Any:
    if kind == "str":
        return _clean_str(value)
    if isinstance(value, (str, bytes)) or isinstance(value, (list, dict, tuple)):
        raise UnstorableError(f"{name} = {str(value)[:60]!r} is not a number")
    try:
        if kind == "float":
            return float(value)
        if isinstance(value, float) and math.isnan(value):
            return -1  # missing
        if isinstance(value, float) and math.isinf(value):
            raise UnstorableError(f"{name} = {value!r} is not a finite integer")
        v = int(value)
    except (TypeError, ValueError, OverflowError) as exc:
        raise UnstorableError(f"{name} = {str(value)[:60]!r}: {exc}") from None
    if not _I64[0] <= v <= _I64[1]:
        raise UnstorableError(f"{name} = {value!r} does not fit a 64-bit integer")
    return v


def normalise_record(record: dict[str, Any]) -> dict[str, Any]:
    """The record as it will be journaled and stored: known columns only, each converted
    to its kind (str / float / int64), profiles and history as float64 arrays.

    Raises
    ------
    UnstorableError
        When a value cannot be converted (text in a float column, an integer beyond
        64 bits, a profile that is not a 1-D array of numbers (2-D for the per-replica
        profiles)...).
    """
    row_in = record.get("row")
    if not isinstance(row_in, dict):
        raise UnstorableError("no 'row'")
    row = {}
    for name, value in row_in.items():
        col = _STORED.get(name)
        if col is None:     # not a stored column (derived ones included): dropped
            continue
        row[name] = col.fill if value is None else _convert(col.kind, name, value)
    for name in FROM_CONFIG:  # a record of an older schema (a journal line) lacks it
        if name not in row and "config_json" in row:
            row[name] = _convert(_STORED[name].kind, name,
                                 config_values(name, [row["config_json"]])[0])
    profiles = {}
    for name, value in (record.get("profiles") or {}).items():
        if np.iscomplexobj(value):
            raise UnstorableError(f"profile {name}: complex values (the schema holds real"
                             " numbers)")
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError, OverflowError) as exc:
            raise UnstorableError(f"profile {name}: {exc}") from None
        if name in REPLICA_VARS:
            # exactly the schema's shape, (R,) or (R, N_f), as `sweep validate` checks it
            dims = REPLICA_VARS[name][2]
            sizes = {"R": row.get("replicas"), "N_f": row.get("n_floes")}
            want = tuple(sizes[d] for d in dims)
            if arr.ndim != len(dims) or any(w is None or w < 1 for w in want) \
                    or arr.shape != want:
                raise UnstorableError(f"profile {name}: shape {arr.shape}, expected"
                                 f" {'x'.join(dims)} = {want} (columns replicas, n_floes)")
            profiles[str(name)] = arr
            continue
        if arr.ndim > 1:
            raise UnstorableError(f"profile {name}: {arr.ndim}-D, expected 1-D")
        profiles[str(name)] = arr.reshape(-1)

    if np.iscomplexobj(record.get("residual_history", ())):
        raise UnstorableError("residual_history: complex values")
    try:
        hist = np.asarray(record.get("residual_history", ()), dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError) as exc:
        raise UnstorableError(f"residual_history: {exc}") from None
    return {"row": row, "profiles": profiles, "residual_history": hist}


def check_profiles(row: dict[str, Any], profiles: dict[str, np.ndarray]) -> None:
    """Refuse (:class:`UnstorableError`) a point whose status has profiles (all but failed,
    invalid, crashed, timeout) without each of PROFILE_VARS of length ``n_floes``: what
    ``sweep validate`` checks of a stored point."""
    if row.get("status") in NO_PROFILES:
        return
    n = row.get("n_floes")
    for name in PROFILE_VARS:
        if name not in profiles:
            raise UnstorableError(f"profile {name}: missing (a {row.get('status')} point has"
                             " every profile)")
        if not (isinstance(n, int) and n >= 1) or profiles[name].shape != (n,):
            raise UnstorableError(f"profile {name}: {profiles[name].size} values, expected"
                             f" n_floes = {n}")




def text(value: Any) -> str:
    """A stored string: HDF5 gives ``bytes`` (variable-length UTF-8) or ``str``."""
    return value.decode() if isinstance(value, bytes) else str(value)


def texts(values: np.ndarray) -> np.ndarray:
    """A stored column decoded: strings as an object array of ``str``; numbers as they
    are."""
    if values.dtype.kind in "OS":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in values],
                        dtype=object)
    return values
