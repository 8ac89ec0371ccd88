"""The amplitude march of the attenuation iteration (eq. 20; docs/model.md §4 steps 4-6):
from the measured dissipation (:func:`march_amplitude`, :func:`march_rows`), and
self-consistent from per-floe dissipation coefficients c = S_sd / a^3
(:func:`march_coefficients`, compiled), with the coefficients of a window
(:func:`coefficients`, :func:`mean_coefficients`), the residual between two profiles and
when its history stopped falling (:func:`noise_floor_reached`).

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
:mod:`floewave.iteration.stationary`).

The compiled part calls no other kernel file, but takes its flags from
``floewave._jit.JIT``: it is one of ``floewave._jit.KERNEL_SOURCES``, so a change of the
flags (which numba's own key does not hold) recompiles it too.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ._jit import JIT

__all__ = ["march_coefficients", "march_amplitude", "march_rows", "residual",
           "noise_floor_reached", "coefficients", "mean_coefficients"]

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


def march_amplitude(cfg, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """Amplitudes from the ice edge (eqs. 12, 20, optionally 21), clipped at 0
    (:func:`march_rows`, which marches many profiles at once).

    a_1^2 = a0^2 + L_x S_1 / (rho_w g c_g);
    a_i^2 = a_{i-1}^2 + L_x (S_{i-1} + S_i) / (rho_w g c_g)
            [- 3 g^(1/2) h_ow,i-1^(5/2) / c_g with overwash,
             h_ow = c_ow max(k a_{i-1} - s_min, 0)].
    """
    return march_rows(cfg, np.asarray(S_sd, dtype=float), c_g, k)


def march_rows(cfg, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """:func:`march_amplitude` for every row of ``S_sd`` (..., N_f) at once
    (same operations per element, so the same bits as the one-row version)."""
    S = np.asarray(S_sd, dtype=float)
    fac = cfg.L_x / (cfg.rho_w * _G * c_g)
    a = np.empty_like(S)
    a2 = cfg.a0**2 + fac * S[..., 0]
    a[..., 0] = np.sqrt(np.maximum(a2, 0.0))
    for i in range(1, S.shape[-1]):
        prev = a[..., i - 1]
        a2 = prev * prev + fac * (S[..., i - 1] + S[..., i])
        if cfg.overwash:
            h_ow = cfg.c_ow * np.maximum(k * prev - cfg.s_min, 0.0)
            a2 = a2 - 3.0 * math.sqrt(_G) * h_ow**2.5 / c_g
        a[..., i] = np.sqrt(np.maximum(a2, 0.0))
    return a


def residual(a_old: np.ndarray, a_new: np.ndarray) -> float:
    """max_i |a_new - a_old| / a_old over floes with a_old > 0 (0 if there are none): the
    iteration's residual (docs/model.md §4 step 6)."""
    ok = a_old > 0
    if not ok.any():
        return 0.0
    return float(np.max(np.abs(a_new[ok] - a_old[ok]) / a_old[ok]))


def noise_floor_reached(history: list[float], window: int) -> bool:
    """True when the residual stopped decreasing: the median of the last ``window``
    residuals exceeds half the median of the ``window`` before them."""
    if window <= 0 or len(history) < 2 * window:
        return False
    last = float(np.median(history[-window:]))
    prev = float(np.median(history[-2 * window:-window]))
    return last > 0.5 * prev


def coefficients(S: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Dissipation coefficients c = S_sd / a^3 [W m^-5] of windows run with amplitudes
    ``A`` [m] (same shape); NaN where a = 0 (no wave reached the floe: c not measured)."""
    S = np.asarray(S, dtype=float)
    A = np.asarray(A, dtype=float)
    out = np.full(S.shape, np.nan)
    ok = A > 0
    out[ok] = S[ok] / (A[ok] * A[ok] * A[ok])
    return out


def mean_coefficients(C: np.ndarray, axis: int | tuple = 0) -> np.ndarray:
    """The mean of coefficients ``C`` over ``axis``, ignoring NaN (unmeasured); a floe
    never measured takes its upwave neighbour's value (0 at the ice edge)."""
    C = np.asarray(C, dtype=float)
    ok = np.isfinite(C)
    count = ok.sum(axis=axis)
    total = np.where(ok, C, 0.0).sum(axis=axis)
    m = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    m = np.array(m, dtype=float, ndmin=1)
    for i in range(m.shape[-1]):
        prev = m[..., i - 1] if i > 0 else 0.0
        m[..., i] = np.where(np.isfinite(m[..., i]), m[..., i], prev)
    return m
