"""Every error floewave raises, in one place.

Each carries :attr:`~FloewaveError.field` (the :class:`~floewave.ModelConfig` field at
fault, or ``None`` when no single field is) and :attr:`~FloewaveError.problem` (what is
wrong with that field's value, without the field and value; the whole message when no
field is at fault), so that callers such as ``sweep`` reword an error without parsing its
text. The message itself (``str(exc)``, ``exc.args``) is unchanged by these attributes.

They are also importable from where they were defined before (``floewave``,
``floewave.config``, ``floewave.dispersion``, ``floewave.model``).
"""
from __future__ import annotations

__all__ = ["FloewaveError", "ConfigError", "InvalidPointError", "DispersionError",
           "NumericalError"]


class FloewaveError(Exception):
    """Base class of every error raised by floewave.

    Parameters
    ----------
    *args : the exception's arguments (the message first), as for ``Exception``.
    field : the ModelConfig field at fault, if one is.
    problem : what is wrong with ``field``'s value (default: the whole message).
    """

    def __init__(self, *args: object, field: str | None = None,
                 problem: str | None = None) -> None:
        super().__init__(*args)
        self.field = field
        self.problem = str(args[0]) if problem is None and args else (problem or "")


class ConfigError(FloewaveError, ValueError):
    """A configuration value is malformed (wrong type, out of range, unknown name)."""


class InvalidPointError(FloewaveError, ValueError):
    """A well-formed configuration that describes a physically impossible point."""


class DispersionError(InvalidPointError):
    """Eq. 6 has no admissible root (e.g. ``ml`` beyond its mass-loading cutoff)."""


class NumericalError(FloewaveError, ArithmeticError):
    """The DEM diverged (non-finite state) or floes passed through each other."""
