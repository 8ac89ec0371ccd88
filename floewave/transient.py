"""How long a point's transient lasts at least: the drag relaxation time of a floe
(:mod:`floewave.iteration.stationary`'s lower bound on the windows it discards; also the campaign
runner's cost estimate). Imports no kernel."""
from __future__ import annotations

import numpy as np

from .config import ModelConfig

__all__ = ["drag_time", "transient_windows"]


def drag_time(cfg: ModelConfig, k: float) -> float:
    """tau_d = (1 + C_m) m / (rho_w C_sd L_y L_x u_w0) [s]: the time in which skin drag
    (eq. 15, linearised about the orbital velocity u_w0 = a0 omega / tanh kh) relaxes a
    floe's drift. The slowest transients seen are of this order (C_sd 0.005: tau_d about
    80 s, a far-end amplitude still swinging by 0.05 a0 over the first 75 periods);
    inf without drag."""
    u_w0 = cfg.a0 * cfg.omega / np.tanh(k * cfg.h)
    rate = cfg.rho_w * cfg.C_sd * cfg.L_y * cfg.L_x * u_w0
    return float((1.0 + cfg.C_m) * cfg.mass / rate) if rate > 0 else float("inf")


def transient_windows(cfg: ModelConfig, k: float) -> int:
    """The fewest windows discarded as transient: ``transient_min``, or
    ``transient_drag_times`` tau_d (:func:`drag_time`) when longer, at most half of
    ``max_iterations`` (a function of the configuration alone)."""
    n = cfg.transient_min
    if cfg.transient_drag_times == 0.0:
        return int(min(n, cfg.max_iterations // 2))
    tau = drag_time(cfg, k) * cfg.transient_drag_times
    if np.isfinite(tau):
        n = max(n, int(np.ceil(tau / (cfg.nT * cfg.T))))
    else:
        n = cfg.max_iterations
    return int(min(n, cfg.max_iterations // 2))
