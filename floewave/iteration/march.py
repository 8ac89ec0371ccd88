"""The update of the attenuation iteration (docs/model.md §4 steps 4-6): eq. 20 marched from
the measured dissipation (:func:`march_amplitude`, :func:`march_rows`), the dissipation
coefficients c = S_sd / a^3 that the self-consistent march
(:func:`floewave.march_coefficients`, compiled in :mod:`floewave._march`) takes, and the
residual between two amplitude profiles."""
from __future__ import annotations

import math

import numpy as np

from ..config import G, ModelConfig

__all__ = ["march_amplitude", "march_rows", "residual", "coefficients", "mean_coefficients"]


def march_amplitude(cfg: ModelConfig, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """Amplitudes from the ice edge (eqs. 12, 20, optionally 21), clipped at 0
    (:func:`march_rows`, which marches many profiles at once).

    a_1^2 = a0^2 + L_x S_1 / (rho_w g c_g);
    a_i^2 = a_{i-1}^2 + L_x (S_{i-1} + S_i) / (rho_w g c_g)
            [- 3 g^(1/2) h_ow,i-1^(5/2) / c_g with overwash,
             h_ow = c_ow max(k a_{i-1} - s_min, 0)].
    """
    return march_rows(cfg, np.asarray(S_sd, dtype=float), c_g, k)


def march_rows(cfg: ModelConfig, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """:func:`march_amplitude` for every row of ``S_sd`` (..., N_f) at once
    (same operations per element, so the same bits as the one-row version)."""
    S = np.asarray(S_sd, dtype=float)
    fac = cfg.L_x / (cfg.rho_w * G * c_g)
    a = np.empty_like(S)
    a2 = cfg.a0**2 + fac * S[..., 0]
    a[..., 0] = np.sqrt(np.maximum(a2, 0.0))
    for i in range(1, S.shape[-1]):
        prev = a[..., i - 1]
        a2 = prev * prev + fac * (S[..., i - 1] + S[..., i])
        if cfg.overwash:
            h_ow = cfg.c_ow * np.maximum(k * prev - cfg.s_min, 0.0)
            a2 = a2 - 3.0 * math.sqrt(G) * h_ow**2.5 / c_g
        a[..., i] = np.sqrt(np.maximum(a2, 0.0))
    return a


def residual(a_old: np.ndarray, a_new: np.ndarray) -> float:
    """max_i |a_new - a_old| / a_old over floes with a_old > 0 (0 if there are none): the
    iteration's residual (docs/model.md §4 step 6)."""
    ok = a_old > 0
    if not ok.any():
        return 0.0
    return float(np.max(np.abs(a_new[ok] - a_old[ok]) / a_old[ok]))


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
