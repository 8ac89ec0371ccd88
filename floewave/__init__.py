"""floewave: wave attenuation in fields of colliding ice floes.

A numba implementation of the coupled discrete-element / wave-energy model of
Herman, Cheng & Shen (2019, The Cryosphere 13, 2887). Public API:

- :class:`ModelConfig` — every parameter of the model (frozen, validated)
- :func:`solve_dispersion` — k and c_g (eqs. 6, 7)
- :func:`alpha_confined` — the confined-ice attenuation rate (eq. 24)
- :func:`run_point` — the attenuation iteration for one point -> :class:`PointResult`
- :func:`march_coefficients` — the self-consistent amplitude march (eq. 20) of measured
  per-floe dissipation coefficients

Public modules beside these: :mod:`floewave.paths` (output paths checked before any work,
stdout quieted when its reader has gone), :mod:`floewave.help` (help text from
:class:`ModelConfig`, suggestions for a misspelt field).
"""
import importlib

from .config import SWEPT_FIELDS, ModelConfig
from .dispersion import alpha_confined, solve_dispersion
from .errors import ConfigError, DispersionError, FloewaveError, InvalidPointError, NumericalError
from .results import PointResult

__version__ = "1.0.0"

#: Changes only when results can change (not with the package version): part of every
#: point's identity hash in ``sweep``.
MODEL_VERSION = "9"

__all__ = ["ModelConfig", "PointResult", "run_point", "march_coefficients",
           "solve_dispersion", "alpha_confined",
           "FloewaveError", "ConfigError", "InvalidPointError", "DispersionError",
           "NumericalError",
           "SWEPT_FIELDS", "MODEL_VERSION", "__version__"]

#: Imported on first use: they import numba (0.3 s of ``import floewave``, measured with
#: ``python -X importtime``), which ``sweep``'s commands mostly never need. name -> module.
_LAZY = {"run_point": ".model", "march_coefficients": "._march"}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(name)
