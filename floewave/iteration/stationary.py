"""The stationary iteration protocol (``protocol = "stationary"``, the default): when the
floe state is stationary, and what the point then reports.

The legacy protocol (``"noise_floor"``, :mod:`floewave.iteration.noise_floor`) stops iterating
when the residual stops falling and averages the next windows. That signal cannot see a floe
arrangement that is still relaxing (W_c drifting 36 -> 27 -> 19 m over the first 50 periods
at Fig. 2's ``ep`` eps 0.8 point), so it averaged a transient. This protocol:

1. **starts from the confined-ice profile** a = 1 / (alpha_c x + 1/a0) (eq. 25), a function
   of the configuration alone, and spins the floes up for ``n0`` periods under it;
2. runs windows of ``nT`` periods; after each it measures every floe's dissipation
   coefficient c = S_sd / a^3 and **updates a by the self-consistent march**
   (:func:`floewave.march_coefficients`, a Newton-like step: exact in one window for
   fixed floes), at first from the last window's c; once the transient's bound (the
   windows never averaged, :func:`floewave.transient.transient_windows`) has passed, from
   the mean c of the windows after it, and from window ``n_average`` on from the mean c of
   the windows after the current truncation point (model version 9; version 8 marched
   from the last window's c until window ``n_average``, so the first windows of the
   average ran at profiles carrying one window's noise, and the estimate a bias the
   replicas share: docs/convergence.md, "An iteration that settles");
3. **tests stationarity** with MSER (White 1997, *Simulation* 69, 323; White, Cobb & Spratt
   2000): on replica-mean series of window statistics (the sheet-mean and last-floe
   amplitude implied by the window alone, and the fraction of compact pairs) the truncation
   d minimising sum_{j>d} (y_j - ybar_d)^2 / (n - d)^2 is found; the series counts as
   stationary after d when d <= n / 2 (MSER's own validity rule) and, on the windows after
   d, the first and second halves agree (:func:`~floewave.iteration.stationarity.halves_z`, a
   Geweke test with the independent replicas as samples: MSER alone, on 12-20 windows,
   let slow drifts through);
   only windows after d are ever averaged (never the first ``transient_min``);
4. **stops** when the run is stationary, at least ``n_average`` windows are averaged and
   SE(a) <= ``target_stderr`` a0 and SE(W_c) <= ``target_W_c_stderr`` (status
   ``converged_noisy``); ``converged`` when the update stops changing a (residual <
   ``delta``: the deterministic confined limit) and the targets hold; ``not_converged``
   when ``max_average`` windows are averaged with the targets still unmet (model version
   9: a stationary run whose error bars more windows would not bring to their targets in
   reasonable time, e.g. a zone whose replicas sit in different layouts, reported with the
   estimate of those windows and the error bars it has, ``iterations`` below
   ``max_iterations``), or at ``max_iterations`` windows (never stationary, or
   ``max_average = 0``), reporting the estimate from the windows after the truncation (or
   the last half when no stationary stretch was found) with its error bars. (A run with
   ``max_iterations`` below its transient plus ``max_average`` windows, e.g.
   configs/demo.toml's 30, can reach ``max_iterations`` while stationary, too.)

The estimate (:func:`floewave.iteration.estimate.estimate_point` with coefficients) is the march of
the mean coefficient, never a mean of marched, clipped profiles. With ``coupling =
"independent"`` (the default) every replica marches its own a(x), so the replicas are
independent runs (but for the shared truncation point d, which decides which windows
feed every replica's update) and the jackknife over them includes the iteration noise of
a(x).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._march import march_coefficients, mean_coefficients, residual
from ..config import ModelConfig
from ..errors import NumericalError
from ..transient import drag_time, transient_windows
from .estimate import SE_FLOOR, targets_met, windows_estimate
from .result import Estimate, Iteration
from .stationarity import truncation
from .window import run_window
from .windows import Windows

__all__ = ["confined_profile", "iterate_stationary", "SE_FLOOR", "drag_time",
           "transient_windows"]


def confined_profile(cfg: ModelConfig, x: np.ndarray, alpha_c: float) -> np.ndarray:
    """Eq. 25, a(x) = 1 / (alpha_c x + 1/a0) [m], at floe centres ``x`` [m]."""
    return 1.0 / (alpha_c * np.asarray(x, dtype=float) + 1.0 / cfg.a0)


def iterate_stationary(cfg: ModelConfig, chain, x0s: np.ndarray, k: float, c_g: float,
                       alpha_c: float,
                       progress: Callable[[int, float, str], None] | None = None
                       ) -> Iteration:
    """Run the protocol (module docstring) on ``chain`` (R replicas): the
    :class:`~floewave.iteration.result.Iteration` whose estimate is
    :func:`floewave.iteration.estimate.estimate_point` of the averaged windows (with R = 1
    ``a_stderr`` the autocorrelation-corrected standard error over windows), its history
    the update's residual per window, its noise the median residual of the averaged
    windows and its truncation the windows discarded as transient."""
    R = cfg.n_chains
    a = np.tile(confined_profile(cfg, x0s[0] - x0s[0, 0] + 0.5 * cfg.L_x, alpha_c), (R, 1))
    wins = Windows()
    d_min = transient_windows(cfg, k)
    history: list[float] = []
    status = "not_converged"
    d, stationary, bounded = 0, False, False
    est: Estimate | None = None
    for it in range(1, cfg.max_iterations + 1):
        windows, S = run_window(cfg, chain, x0s, a, it == 1)
        zones = [w.zone for w in windows]
        wins.add(cfg, S, np.array(a), windows, zones, c_g, k)
        d, stationary = truncation(cfg, wins.series, d_min)
        C_avg = mean_coefficients(np.array(wins.C[d:]))                 # (R, N_f)
        if cfg.coupling == "mean":
            C_avg = np.broadcast_to(mean_coefficients(C_avg), C_avg.shape)
        a_new = march_coefficients(cfg, C_avg, c_g, k)
        if not np.all(np.isfinite(a_new)):
            raise NumericalError(f"non-finite amplitude at iteration {it}")
        res = max(residual(a[r], a_new[r]) for r in range(R))
        history.append(res)
        if progress is not None:
            progress(it, res, "average" if stationary else "iterate")
        a = a_new
        # the update stopped changing a: exact only for fixed floes (chaos otherwise)
        deterministic = cfg.confined and res < cfg.delta and len(wins) >= 2
        if deterministic or (stationary and len(wins) - d >= cfg.n_average):
            d_use = len(wins) - 1 if deterministic else d
            est = windows_estimate(cfg, wins, d_use, c_g, k, a_new)
            if deterministic and R == 1:        # a fixed point reached exactly
                est.a_stderr = np.abs(a_new[0] - wins.A[-1][0])
                est.a_end_stderr = float(est.a_stderr[-1])
            if (deterministic and R == 1) or targets_met(cfg, est):
                status = "converged" if deterministic else "converged_noisy"
                d = d_use
                break
            if 0 < cfg.max_average <= len(wins) - d_use:   # stationary, targets out of reach
                d, bounded = d_use, True
                break
    if status == "not_converged" and not bounded:
        if not stationary:            # the last half, never inside the transient's bound
            d = max(len(wins) // 2, min(d_min, len(wins) - 1))
        est = windows_estimate(cfg, wins, d, c_g, k, a)
    assert est is not None
    averaged = history[d:] if d < len(history) else history[-1:]
    return Iteration(status, est, history,
                     0.0 if status == "converged" else float(np.median(averaged)), d)
