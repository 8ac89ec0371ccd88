"""The normal contact law between neighbouring floes (docs/model.md §3): the force and the
stiffness k_n at an overlap.

Flags and why: :mod:`floewave._jit`.
"""
from __future__ import annotations

import math

from numba import njit

from ._jit import JITN
from ._layout import CONTACT_LINEAR, DAMPING_LIGGGHTS

__all__ = ["contact_law", "contact_stiffness"]


@njit(**JITN)
def contact_law(delta, v_n, P, contact, damping, clip):
    """Normal contact force [N] pushing a pair apart at overlap ``delta`` > 0:
    F = k_n delta - gamma_n v_n, ``v_n = u_{i+1} - u_i`` (positive while separating).

    k_n: ``hertz_disk`` f(s) (docs/model.md §3) or ``linear``; gamma_n = -beta sqrt(5 k_n m*)
    (liggghts) or -2 beta sqrt(k_n m*) (exact); clipped at 0 if ``clip``. The option codes
    are arguments so that a caller with constant options (the built time loop) gets them
    folded away.
    """
    kn = _stiffness(delta, P, contact)
    if damping == DAMPING_LIGGGHTS:
        gamma = -P.beta * math.sqrt(5.0 * kn * P.m_star)
    else:
        gamma = -2.0 * P.beta * math.sqrt(kn * P.m_star)
    F = kn * delta - gamma * v_n
    if clip == 1 and F < 0.0:
        F = 0.0
    return F


@njit(**JITN)
def _stiffness(delta, P, contact):
    """k_n [N m^-1] at overlap ``delta``: ``hertz_disk`` f(s) (docs/model.md §3) or ``linear``."""
    if contact == CONTACT_LINEAR:
        return P.kn_lin
    s = delta * P.s_scale
    return P.kn_disk * ((0.9117 * s * s + 0.2722 * s + 0.003324)
                        / (s * s + 1.524 * s + 0.03159))


@njit(**JITN)
def contact_stiffness(delta, P, contact):
    """k_n for overlap ``delta`` [N m^-1] (the stiffness of :func:`contact_law`) under the
    contact law ``contact`` (``CONTACT_*``)."""
    return _stiffness(delta, P, contact)
