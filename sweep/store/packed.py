"""A journal record's arrays, packed (journal version 3): ``{"f8": "<base64>", "shape":
[...]}``, the base64 of the array's float64 values, little-endian, in C order: exact to
the bit (NaN payloads included), about 11 bytes a value against about 20 as JSON
numbers, and written about six times faster (docs/cluster.md). Records of journal
version 2 and before hold JSON lists, which :func:`unpack_array` passes through.
"""
from __future__ import annotations

import base64
import binascii
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from sweep.errors import BadJournalLineError

__all__ = ["pack_array", "unpack_array", "packed", "unpack_record"]

#: the JSON member of a packed array that holds its base64 bytes
_F8 = "f8"


def pack_array(value: Any) -> dict[str, Any]:
    """A float64 array as a journal record holds it since version 3: ``{"f8": base64 of
    its little-endian bytes in C order, "shape": [...]}``."""
    arr = np.asarray(value, dtype="<f8")
    return {_F8: base64.b64encode(arr.tobytes()).decode("ascii"), "shape": list(arr.shape)}


def unpack_array(value: Any) -> Any:
    """The array of :func:`pack_array`'s form (float64); any other value as it is (a JSON
    list of a record of before version 3).

    Raises
    ------
    BadJournalLineError
        A packed array whose bytes are not base64 or do not fill its shape.
    """
    if not isinstance(value, Mapping) or _F8 not in value:
        return value
    try:
        raw = base64.b64decode(value[_F8], validate=True)
    except (binascii.Error, TypeError, ValueError) as exc:
        raise BadJournalLineError(f"unreadable packed array: {exc}") from None
    shape = value.get("shape")
    if not isinstance(shape, list) or len(shape) > 8 or not all(
            isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape) \
            or 8 * math.prod(shape) != len(raw):
        raise BadJournalLineError(f"unreadable packed array: shape {str(shape)[:40]} does"
                                  f" not hold its {len(raw)} bytes")
    return np.frombuffer(raw, dtype="<f8").astype(np.float64).reshape(shape)


def unpack_record(obj: dict[str, Any]) -> None:
    """Turn a point record's packed arrays into arrays, in place."""
    profiles = obj.get("profiles")
    if isinstance(profiles, dict):
        for name, value in profiles.items():
            profiles[name] = unpack_array(value)
    if "residual_history" in obj:
        obj["residual_history"] = unpack_array(obj["residual_history"])


def packed(value: Any) -> Any:
    """``json.dumps``'s fallback: an array is packed (:func:`pack_array`)."""
    if isinstance(value, np.ndarray):
        return pack_array(value)
    raise TypeError(f"Object of type {type(value).__name__} is not JSON serializable")
