"""What the stationary protocol's windows measured (:class:`Windows`), and when they are
stationary: the MSER truncation (White 1997, :func:`mser_truncation`) of replica-mean
series of window statistics, and a Geweke-like test of the windows after it
(:func:`halves_z`); :mod:`floewave.iteration.stationary` says how the protocol uses them."""
from __future__ import annotations

import numpy as np

from .._march import coefficients, march_coefficients, mean_coefficients
from ..config import ModelConfig
from .estimate import SE_FLOOR, Records
from .window import FIELDS

__all__ = ["Windows", "mser_truncation", "halves_z", "GEWEKE_Z"]


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


class Windows:
    """What the windows so far measured: per window j the dissipation S (R, N_f), the
    forcing a (R, N_f), the coefficients C = S / a^3 and the profiles they imply alone
    (the march of C, (R, N_f)), the Window statistics and zones of every replica."""

    def __init__(self) -> None:
        self.S: list[np.ndarray] = []
        self.A: list[np.ndarray] = []
        self.C: list[np.ndarray] = []
        self.implied: list[np.ndarray] = []
        self.windows: list[list] = []
        self.zones: list[list] = []
        self.series: list[np.ndarray] = []

    def add(self, cfg: ModelConfig, S, A, windows, zones, c_g: float, k: float) -> None:
        C = coefficients(S, A)
        self.S.append(S)
        self.A.append(A)
        self.C.append(C)
        self.windows.append(windows)
        self.zones.append(zones)
        implied = march_coefficients(cfg, mean_coefficients(C[None]), c_g, k)   # (R, N_f)
        self.implied.append(implied)
        compact = np.array([np.mean(np.asarray(w.gap_mean[:-1]) < cfg.gap_threshold)
                            for w in windows])
        # (3, R): per replica the sheet-mean and last-floe amplitude this window implies,
        # and its fraction of compact pairs
        self.series.append(np.array([implied.mean(axis=1), implied[:, -1], compact]))

    def __len__(self) -> int:
        return len(self.S)

    def truncation(self, cfg: ModelConfig, d_min: int) -> tuple[int, bool]:
        """(d, stationary): the windows before d are a transient. ``stationarity =
        "fixed"``: d = ``transient_min``. ``"mser"``: before ``n_average`` windows only
        the last counts (d = n - 1, not stationary); then the latest MSER truncation of
        the series, valid when at most n / 2, raised to at least ``d_min``
        (:func:`floewave.transient.transient_windows`); stationary when valid and the halves
        after it agree."""
        n = len(self)
        if cfg.stationarity == "fixed":
            d = min(cfg.transient_min, n - 1)
            return d, n > cfg.transient_min
        if n < cfg.n_average:
            return max(n - 1, 0), False
        Y = np.array(self.series)                                   # (n, 3, R)
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

    def records(self, d: int) -> Records:
        """The windows after d as :class:`floewave.iteration.estimate.Records`."""
        kept = range(d, len(self))
        profiles = {}
        for name in FIELDS:
            profiles[name] = np.mean([[getattr(w, name) for w in self.windows[j]]
                                      for j in kept], axis=0)
        return Records(np.array([self.S[j] for j in kept]),
                       np.array([self.A[j] for j in kept]), profiles,
                       np.array([[z.W_c for z in self.zones[j]] for j in kept]),
                       np.array([[z.compact_end for z in self.zones[j]] for j in kept]),
                       [[z.layout for z in self.zones[j]] for j in kept],
                       C=np.array([self.C[j] for j in kept]))
