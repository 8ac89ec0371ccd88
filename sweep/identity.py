"""Point identity: the SHA-256 of a point's fully resolved configuration.

The hash input is the canonical JSON (:func:`canonical_json`) of::

    {"config": <every ModelConfig field>, "model_version": floewave.MODEL_VERSION}

Canonical means: keys sorted, no whitespace (separators ``","`` and ``":"``), ASCII
only, and every number that belongs to a float field written as a float by Python's
``repr`` (shortest round-trip form), so ``1`` and ``1.0`` hash alike; ``-0.0`` is written
as ``0.0``; NaN and infinities are refused. The hash is the lower-case hex SHA-256 of the
UTF-8 bytes (64 characters); :func:`short_hash` shows its first 12. Same physics gives
the same hash on any machine; any change of a field or of the model version gives a new
one. The definition is pinned by tests of known values (``tests/sweep/test_identity.py``)
and documented in ``results_schema/``.
"""
from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from typing import Any

import floewave
from floewave import ModelConfig

__all__ = ["canonical_json", "point_hash", "short_hash", "sha256_hex", "HASH_LENGTH",
           "SHORT_LENGTH", "config_hashes_to", "DIMENSIONS"]

#: The fields a campaign may sweep, in grid order: floewave's swept parameters
#: (:data:`floewave.SWEPT_FIELDS`), then the ensemble ``seed`` (a point's seed is part of
#: its configuration, so of its hash, whether swept or set in ``[base]``). Seed comes last:
#: the grid's last dimension varies fastest, so a point's seeds are neighbours in the
#: grid, in ``load_xarray``'s last axis and in a seed-by-seed ``--extend``, and a campaign
#: that sweeps no seed keeps its grid order.
DIMENSIONS: tuple[str, ...] = (*floewave.SWEPT_FIELDS, "seed")

HASH_LENGTH = 64
SHORT_LENGTH = 12


def _normalise(value: Any) -> Any:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot hash non-finite number {value!r}")
        return 0.0 if value == 0.0 else value
    if isinstance(value, int):
        return value
    if isinstance(value, Mapping):
        return {str(k): _normalise(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_normalise(v) for v in value]
    if hasattr(value, "item"):  # numpy scalar
        return _normalise(value.item())
    raise TypeError(f"cannot hash value of type {type(value).__name__}: {value!r}")


def canonical_json(data: Any) -> str:
    """Canonical JSON text: sorted keys, no whitespace, ASCII, floats by ``repr``."""
    return json.dumps(_normalise(data), sort_keys=True, separators=(",", ":"),
                      ensure_ascii=True, allow_nan=False)


def sha256_hex(text: str) -> str:
    """Lower-case hex SHA-256 of the UTF-8 encoding of ``text``."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def point_hash(config: ModelConfig | Mapping[str, Any],
               model_version: str | None = None) -> str:
    """The identity of one point (64 hex characters).

    Parameters
    ----------
    config : a :class:`floewave.ModelConfig` or a mapping of its fields (a mapping is
        resolved through ``ModelConfig.from_dict`` first, so missing fields take their
        defaults and ints given for float fields become floats).
    model_version : defaults to :data:`floewave.MODEL_VERSION`.
    """
    if not isinstance(config, ModelConfig):
        config = ModelConfig.from_dict(dict(config))
    version = floewave.MODEL_VERSION if model_version is None else model_version
    return sha256_hex(canonical_json({"config": config.to_dict(),
                                      "model_version": str(version)}))


def short_hash(h: str) -> str:
    """The display prefix of a hash."""
    return h[:SHORT_LENGTH]


def config_hashes_to(config_json: str, h: str, model_version: Any) -> bool:
    """Whether a stored point's ``config_json`` still gives its hash ``h`` under
    ``model_version`` (the text as stored, and failing that the config resolved fully:
    text that is not canonical but means the same point)."""
    text = '{"config":' + config_json + ',"model_version":' + json.dumps(model_version) + "}"
    if sha256_hex(text) == h:
        return True
    try:
        return point_hash(json.loads(config_json), model_version) == h
    except Exception:  # noqa: BLE001 - any failure means it does not re-hash
        return False
