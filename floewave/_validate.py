"""Field checks of :class:`floewave.config.ModelConfig`: one field's type (:func:`coerce`),
a field-local rule (:func:`require`) and an integral ratio (:func:`require_integral`).
"""
from __future__ import annotations

import math
from typing import Any

from .errors import ConfigError, InvalidPointError

__all__ = ["require", "require_integral", "coerce"]


def require(cfg: Any, name: str, ok: bool, what: str) -> None:
    """Raise :class:`ConfigError` naming ``cfg.name`` and its value unless ``ok``."""
    if not ok:
        raise ConfigError(f"ModelConfig.{name} = {getattr(cfg, name)!r} {what}", field=name,
                          problem=what)


def require_integral(name: str, value: float, step: float, step_name: str) -> None:
    """Raise :class:`InvalidPointError` unless ``value / step`` is a positive integer."""
    n = value / step
    if round(n) < 1 or abs(n - round(n)) > 1e-9 * max(1.0, abs(n)):
        raise InvalidPointError(
            f"{name} / {step_name} = {value!r} / {step!r} = {n!r} is not an integer",
            field=name)


def coerce(name: str, type_name: Any, value: Any) -> Any:
    """Check one field's type; ints are accepted for floats (1 == 1.0)."""
    type_name = type_name if isinstance(type_name, str) else type_name.__name__

    def bad() -> ConfigError:      # built only when raised (this runs for every field)
        return ConfigError(f"ModelConfig.{name} = {value!r}: expected {type_name}",
                           field=name, problem=f"expected {type_name}")

    if type_name == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad()
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"ModelConfig.{name} = {value!r}: must be finite", field=name,
                              problem="must be finite")
        return value
    if type_name == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                return int(value)
            raise bad()
        return int(value)
    if type_name == "bool":
        if not isinstance(value, bool):
            raise bad()
        return value
    if type_name == "str":
        if not isinstance(value, str):
            raise bad()
        return value
    raise TypeError(f"unhandled field type {type_name!r}")
