"""When the stationary protocol's windows are stationary: the MSER truncation (White 1997,
*Simulation* 69, 323; :func:`mser_truncation`) of replica-mean series of window
statistics, valid when at most half of the windows, and a Geweke-like test of the windows
after it (:func:`halves_z`): :func:`truncation`. :mod:`floewave.iteration.stationary` says
how the protocol uses them."""
from __future__ import annotations

import numpy as np

from ..config import ModelConfig
from .estimate import SE_FLOOR

__all__ = ["truncation", "mser_truncation", "halves_z", "GEWEKE_Z"]


def mser_truncation(y: np.ndarray, n_min: int) -> int:
    """MSER truncation point d of the series ``y`` (White 1997): argmin over d in
    [0, n - n_min] of sum_{j >= d} (y_j - mean(y[d:]))^2 / (n - d)^2, the first minimum
    within rounding (values within 1e-12 of the series' variance are ties: a constant tail
    would otherwise be truncated wherever rounding puts its smallest value). A constant
    series gives 0."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    last = max(n - max(n_min, 1), 0)
    tol = 1e-12 * (float(np.var(y)) + 1e-300)
    best, d_best = np.inf, 0
    for d in range(last + 1):
        tail = y[d:]
        m = tail.mean()
        v = float(((tail - m) ** 2).sum()) / (n - d) ** 2
        if v < best - tol:
            best, d_best = v, d
    return d_best


#: the largest |z| of the half-difference test (:func:`halves_z`) that counts as stationary
GEWEKE_Z = 2.5


def halves_z(Y: np.ndarray, floor: float) -> float:
    """A Geweke-like drift test with the replicas as independent samples: per replica
    (columns of ``Y``, (n, R)) the mean of the first half of the windows minus that of the
    second; z = mean over replicas / its standard error (Geweke 1992, with independent
    replicas in place of a spectral variance). ``floor`` bounds the standard error from
    below (replicas of a non-chaotic point agree to rounding)."""
    n, R = Y.shape
    h = n // 2
    if h < 1:
        return 0.0
    D = Y[:h].mean(axis=0) - Y[n - h:].mean(axis=0)
    se = float(D.std(ddof=1) / np.sqrt(R)) if R > 1 else 0.0
    return float(D.mean() / max(se, floor))


def _rounded(y: np.ndarray, resolution: float) -> np.ndarray:
    """``y`` rounded to multiples of ``resolution`` (unchanged for 0)."""
    return np.round(y / resolution) * resolution if resolution > 0 else y


def truncation(cfg: ModelConfig, series: list[np.ndarray], d_min: int) -> tuple[int, bool]:
    """(d, stationary) of the windows whose ``series`` (per window (3, R): the sheet-mean
    and last-floe amplitude each implies, its fraction of compact pairs) is given: the
    windows before d are a transient. ``stationarity =
    "fixed"``: d = ``transient_min``. ``"mser"``: before ``n_average`` windows, only
    the last counts (d = n - 1) until the transient's bound ``d_min``
    (:func:`floewave.transient.transient_windows`) has passed, then the windows after it
    (d = ``d_min``; model version 9: every window the average will hold but the first
    two runs at a profile marched from a pooled coefficient, not from one window's noise,
    whose bias the replicas share), not stationary; then the latest MSER truncation of
    the series, valid when at most n / 2, raised to at least ``d_min``; stationary when
    valid and the halves after it agree."""
    n = len(series)
    if cfg.stationarity == "fixed":
        d = min(cfg.transient_min, n - 1)
        return d, n > cfg.transient_min
    if n < cfg.n_average:
        return (d_min if n > d_min else max(n - 1, 0)), False
    Y = np.array(series)                                   # (n, 3, R)
    # MSER on the replica means, rounded to the resolution of a reported amplitude
    # (SE_FLOOR a0): a non-chaotic point's creep by 1e-10 a0 is not a transient (MSER
    # would truncate it at the end of the run for ever)
    res = (SE_FLOOR * cfg.a0, SE_FLOOR * cfg.a0, 0.0)
    d = max(mser_truncation(_rounded(Y[:, s].mean(axis=1), res[s]), cfg.n_average)
            for s in range(Y.shape[1]))
    valid = d <= n // 2             # MSER's own validity rule, on its own truncation
    d = max(d, min(d_min, n - 1))   # the physical lower bound needs no such rule
    if not valid or n - d < cfg.n_average:
        return d, False
    floors = (1e-3 * cfg.a0, 1e-3 * cfg.a0, 1e-2)
    return d, all(abs(halves_z(Y[d:, s], floors[s])) <= GEWEKE_Z
                  for s in range(Y.shape[1]))
