"""The legacy protocol (``protocol = "noise_floor"``, docs/convergence.md): iterate
a <- a + relax (a_new - a) from a = a0 with a_new marched from each window's dissipation
(eq. 20), until

- ``converged``: residual max_i |a_new - a| / a < delta; reports the last a_new;
- ``converged_noisy``: the residual reached its noise floor
  (:func:`floewave._march.noise_floor_reached`); a is the mean of a_new over
  ``n_average`` further iterations (or until the error-bar targets hold), ``a_stderr``
  its standard error (autocorrelation-corrected) and ``noise`` the median residual over
  that window;
- ``not_converged``: ``max_iterations`` reached first (mean of any averaged iterations,
  else the last a_new).
"""
from __future__ import annotations

import numpy as np

from .._march import march_amplitude, march_rows, noise_floor_reached, residual
from ..config import ModelConfig
from ..errorbars import stderr
from ..errors import NumericalError
from .estimate import estimate_point, precise_enough, samples_records
from .result import Estimate, Iteration
from .window import run_window

__all__ = ["iterate_noise_floor"]


def iterate_noise_floor(cfg: ModelConfig, chain, x0s: np.ndarray, k: float, c_g: float,
                        progress) -> Iteration:
    """The ``noise_floor`` protocol (module docstring) on ``chain``."""
    R = cfg.n_chains
    n = cfg.n_floes
    a = np.full((R, n), cfg.a0)          # per replica (rows equal under coupling "mean")
    history: list[float] = []
    samples: list[tuple] = []        # per averaging iteration: (S, a_new, windows, zones)
    recent: list[tuple] = []
    phase = "iterate"
    status = "not_converged"
    last: tuple | None = None
    stop_est: Estimate | None = None
    a_new = a
    a_prev = a
    for it in range(1, cfg.max_iterations + 1):
        windows, S = run_window(cfg, chain, x0s, a, it == 1)
        zones = [w.zone for w in windows]      # the compact zone of each replica's window
        if cfg.coupling == "mean":
            a_new = np.broadcast_to(march_amplitude(cfg, S.mean(axis=0), c_g, k), (R, n))
        else:
            a_new = march_rows(cfg, S, c_g, k)
        if not np.all(np.isfinite(a_new)):
            raise NumericalError(f"non-finite amplitude at iteration {it}")
        # (coupling "mean": every row is the same profile, one residual says it)
        rows = range(1) if cfg.coupling == "mean" else range(R)
        res = max(residual(a[r], a_new[r]) for r in rows)
        history.append(res)
        last = (S, np.array(a_new), windows, zones)
        if phase == "average":
            samples.append(last)
        elif cfg.reuse_floor and cfg.noise_window > 0:
            recent = (recent + [last])[-cfg.noise_window:]
        if progress is not None:
            progress(it, res, phase)
        a_prev = a
        if phase == "iterate" and res < cfg.delta:
            status = "converged"
            break
        a = a + cfg.relax * (a_new - a)
        if phase == "iterate" and noise_floor_reached(history, cfg.noise_window):
            phase = "average"
            # the last noise_window iterations were already at the noise floor: their
            # samples start the average
            samples.extend(recent)
        elif phase == "average" and len(samples) >= cfg.n_average:
            enough, stop_est = precise_enough(cfg, samples, c_g, k)
            if enough:
                status = "converged_noisy"
                break
    assert last is not None

    kept = samples if samples else [last]
    # the estimate that ended the averaging is the point's (same samples): not recomputed
    est = (stop_est if status == "converged_noisy" and stop_est is not None
           else estimate_point(cfg, samples_records(kept), c_g, k))
    if R == 1:   # one trajectory: the iteration standard error (as the paper's model)
        if samples:
            est.a_stderr = (stderr([s[1][0] for s in samples]) if len(samples) > 1
                               else np.full(n, np.nan))
        else:
            est.a_stderr = np.abs(a_new[0] - a_prev[0])
        est.a_end_stderr = float(est.a_stderr[-1])
    elif not samples:
        # the last iteration alone (converged, or stopped before any averaging): its
        # replica spread and, in quadrature, how far it was from the fixed point (the
        # single trajectory's error of such a point)
        conv = np.abs(np.mean(a_new - a_prev, axis=0))
        est.a_stderr = np.sqrt(est.a_stderr ** 2 + conv**2)
        est.a_end_stderr = float(est.a_stderr[-1])
    if samples:
        noise = float(np.median(history[-len(samples):]))
    else:
        noise = 0.0 if status == "converged" else float(history[-1])
    return Iteration(status, est, history, noise)
