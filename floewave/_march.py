"""The self-consistent amplitude march (eq. 20 with S_sd = c a^3 per floe), compiled.

Eq. 20 marches a_i^2 = a_{i-1}^2 + L_x (S_{i-1} + S_i) / (rho_w g c_g) from the ice edge with
S measured under the amplitudes of the iteration. The skin-drag dissipation of eq. 19 is
-rho_w C_sd <|u_rel|^3>, and u_rel scales with a: S_i = c_i a_i^3 exactly for fixed floes
(the confined limit, §3) and approximately for free ones. With a per-floe coefficient c_i =
S_i / a_i^3 measured in a window, eq. 20 becomes an equation for a_i alone,

    a_i^2 + q_i a_i^3 = a_{i-1}^2 - q_{i-1} a_{i-1}^3 [- overwash of floe i-1],
    q_i = -L_x c_i / (rho_w g c_g) >= 0,

whose left side increases with a_i >= 0: one root, 0 when the right side is <= 0 (the wave
has died out). It is solved by Newton's method from sqrt(right side), an upper bound from
which Newton on this convex function descends monotonically. Its fixed point is eq. 20's:
where c is the dissipation coefficient at the converged profile the march returns that
profile. Used as the iteration's update (a Newton-like step for the fixed point) and as the
estimator (the march of the mean coefficient, not the mean of marched profiles:
:mod:`floewave.protocol`).

It calls no other kernel file, but takes its flags from ``floewave._jit.JIT``: it is one of
``floewave._jit.KERNEL_SOURCES``, so a change of the flags (which numba's own key does not
hold) recompiles it too.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ._jit import JIT

__all__ = ["march_coefficients"]

_G = 9.81  # [m s^-2] (floewave.dispersion.G; repeated: this file imports no other)


@nb.njit(**JIT)
def _root(q: float, b: float) -> float:
    """The root a >= 0 of a^2 + q a^3 = b (q >= 0); 0 when b <= 0."""
    if b <= 0.0:
        return 0.0
    a = math.sqrt(b)
    if q <= 0.0:
        return a
    # both sqrt(b) and cbrt(b / q) bound the root from above (a^2 <= b, q a^3 <= b):
    # starting at the smaller keeps Newton's monotone descent and needs few steps where
    # the cubic term dominates (from sqrt(b) alone each step shrank a by only 1.5x)
    a = min(a, (b / q) ** (1.0 / 3.0))
    for _ in range(100):
        f = a * a + q * a * a * a - b
        step = f / (2.0 * a + 3.0 * q * a * a)
        a_next = a - step
        if a_next <= 0.0:             # cannot happen from the right of a convex root
            a_next = 0.5 * a
        if abs(a_next - a) <= 1e-15 * a:
            return a_next
        a = a_next
    return a


@nb.njit(**JIT)
def _march(c: np.ndarray, a0: float, fac: float, overwash: bool, k: float, c_ow: float,
           s_min: float, c_g: float, out: np.ndarray) -> None:
    rows, n = c.shape
    for r in range(rows):
        a_prev = _root(-fac * c[r, 0], a0 * a0)
        out[r, 0] = a_prev
        for i in range(1, n):
            b = a_prev * a_prev + fac * c[r, i - 1] * a_prev * a_prev * a_prev
            if overwash:
                h_ow = c_ow * max(k * a_prev - s_min, 0.0)
                b -= 3.0 * math.sqrt(_G) * h_ow ** 2.5 / c_g
            a_prev = _root(-fac * c[r, i], b)
            out[r, i] = a_prev


def march_coefficients(cfg, c: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """Amplitudes [m] (shape of ``c``) of the self-consistent march for dissipation
    coefficients ``c`` = S_sd / a^3 [W m^-5] (<= 0), every row from a = ``cfg.a0`` at the
    ice edge (eqs. 12, 20, optionally 21)."""
    c = np.asarray(c, dtype=float)
    flat = np.ascontiguousarray(c.reshape(-1, c.shape[-1]))
    out = np.empty_like(flat)
    fac = cfg.L_x / (cfg.rho_w * _G * c_g)
    _march(flat, float(cfg.a0), fac, bool(cfg.overwash), float(k), float(cfg.c_ow),
           float(cfg.s_min), float(c_g), out)
    return out.reshape(c.shape)
