"""The released grid as a function (issue 48): alpha_all, alpha_edge, a_end/a0, the
probability of a compact zone and W_c where one forms, anywhere in the grid's box, each
with a standard error (:mod:`.model`).

    from herman2019.surrogate import surrogate
    surrogate(L_x=1.0, T=1.3, a0=0.02, C_sd=0.05, eps=0.5, d_f=0.01, dispersion="ml")
"""
from __future__ import annotations

from herman2019.surrogate.grid import AXES, DISPERSIONS, OutsideBox
from herman2019.surrogate.model import QUANTITIES, SHIPPED, Surrogate

__all__ = ["AXES", "DISPERSIONS", "QUANTITIES", "SHIPPED", "OutsideBox", "Surrogate",
           "surrogate"]

_LOADED: dict[str, Surrogate] = {}


def surrogate(dispersion="ml", path=None, detail: bool = False, **params):
    """The shipped surrogate (or the one at ``path``) at the points ``params`` (L_x, T, a0,
    C_sd, eps, d_f: scalars or arrays, broadcast; ``dispersion`` a name or an array of
    names): a DataFrame, one row per point (:meth:`Surrogate.predict`). Loaded once."""
    key = str(path)
    if key not in _LOADED:
        _LOADED[key] = Surrogate.load(path)
    return _LOADED[key].predict(dispersion, detail=detail, **params)
