"""One averaging window's statistics per floe (MODEL.md §4 step 3, §6), from the kernel's
accumulators."""
from __future__ import annotations

import numpy as np

from . import _kernels as K
from .config import ModelConfig

__all__ = ["Window"]


class Window:
    """Statistics of one nT-period averaging window, normalised to per-step means."""

    def __init__(self, cfg: ModelConfig, stats: np.ndarray, nsteps: int, x0: np.ndarray):
        n = stats.shape[1]
        rows = stats / nsteps
        self.s3_mean = rows[K.ST_S3] / cfg.n_x      # <|u_rel|^3> over steps and cells
        self.x_mean = rows[K.ST_X]
        nan = np.full(1, np.nan)
        if cfg.confined:
            self.gap_mean = np.concatenate([np.diff(x0) - cfg.L_x, nan])
            self.contact_fraction = np.concatenate([np.zeros(n - 1), nan])
            self.collisions = np.concatenate([np.zeros(n - 1), nan])
        else:
            self.gap_mean = np.concatenate([rows[K.ST_GAP, :-1], nan])
            self.contact_fraction = np.concatenate([rows[K.ST_CONTACT, :-1], nan])
            self.collisions = np.concatenate([stats[K.ST_COLL, :-1], nan])
        self.F_w_mean = rows[K.ST_FW]
        self.F_c_mean = rows[K.ST_FC]
        self.F_d_mean = rows[K.ST_FD]

    FIELDS = ("s3_mean", "x_mean", "gap_mean", "contact_fraction", "collisions", "F_w_mean",
              "F_c_mean", "F_d_mean")


#: the Window fields that are per-floe profiles
FIELDS = Window.FIELDS
