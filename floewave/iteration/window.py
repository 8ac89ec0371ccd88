"""One averaging window of the attenuation iteration (docs/model.md §4 steps 2-3): running it on
the R chains, its statistics per floe (§6) from the kernel's accumulators, and its compact
zone."""
from __future__ import annotations

import numpy as np

from .. import _kernels as K
from ..collision_stats import zone_of
from ..config import ModelConfig

__all__ = ["Window", "dissipation", "run_window"]


class Window:
    """Statistics of one nT-period averaging window, normalised to per-step means, and its
    compact zone (``zone``: the paper's W_c is a property of one window,
    :func:`floewave.collision_stats.zone_of` of its mean positions and gaps)."""

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
        self.zone = zone_of(cfg, self.x_mean, self.gap_mean)

    FIELDS = ("s3_mean", "x_mean", "gap_mean", "contact_fraction", "collisions", "F_w_mean",
              "F_c_mean", "F_d_mean")


#: the Window fields that are per-floe profiles
FIELDS = Window.FIELDS


def dissipation(cfg: ModelConfig, s3_mean: np.ndarray) -> np.ndarray:
    """Eq. 19: S_sd,i = -rho_w C_sd <|u_rel|^3>_i  [W m^-2]."""
    return -cfg.rho_w * cfg.C_sd * s3_mean


def run_window(cfg: ModelConfig, chain, x0s: np.ndarray, a: np.ndarray,
               first: bool) -> tuple[list[Window], np.ndarray]:
    """One iteration's DEM run with amplitudes ``a`` (R, N_f): the spin-up (``n0`` periods
    on the ``first`` window or without ``warm_start``, else ``n0_warm``) and ``nT`` periods
    accumulating; fixed floes (``confined``) run the confined kernel instead. Returns the R
    replicas' :class:`Window` and their dissipation S (R, N_f) (eq. 19)."""
    n_t = cfg.n_t
    R, n = a.shape
    stats = np.zeros((K.N_STATS, R, n))
    if cfg.confined:
        confined_window = K.make_confined_window(chain.opts.drag)
        for r in range(R):
            confined_window(x0s[r], a[r], cfg.nT * n_t, chain.P, chain.cxi, chain.sxi,
                            stats[:, r, :])
    else:
        if not cfg.warm_start:
            chain.reset()
        n0 = cfg.n0 if (first or not cfg.warm_start) else cfg.n0_warm
        chain.window(a, n0 * n_t, cfg.nT * n_t, stats)
    windows = [Window(cfg, stats[:, r, :], cfg.nT * n_t, x0s[r]) for r in range(R)]
    return windows, np.array([dissipation(cfg, w.s3_mean) for w in windows])
