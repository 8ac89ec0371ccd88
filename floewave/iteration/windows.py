"""What the stationary protocol's windows measured (:class:`Windows`): per window the
dissipation, forcing and coefficients of every replica, the profiles they imply, and the
series whose stationarity :mod:`floewave.iteration.stationarity` tests."""
from __future__ import annotations

import numpy as np

from .._march import coefficients, march_coefficients, mean_coefficients
from ..config import ModelConfig
from .estimate import Records
from .window import FIELDS

__all__ = ["Windows"]


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
