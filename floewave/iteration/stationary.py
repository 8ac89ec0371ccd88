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
   fixed floes), at first from the last window's c, from window ``n_average`` on from the
   mean c of the windows after the current truncation point;
3. **tests stationarity** with MSER (White 1997, *Simulation* 69, 323; White, Cobb & Spratt
   2000): on replica-mean series of window statistics (the sheet-mean and last-floe
   amplitude implied by the window alone, and the fraction of compact pairs) the truncation
   d minimising sum_{j>d} (y_j - ybar_d)^2 / (n - d)^2 is found; the series counts as
   stationary after d when d <= n / 2 (MSER's own validity rule) and, on the windows after
   d, the first and second halves agree (:func:`halves_z`, a Geweke test with the
   independent replicas as samples: MSER alone, on 12-20 windows, let slow drifts through);
   only windows after d are ever averaged (never the first ``transient_min``);
4. **stops** when the run is stationary, at least ``n_average`` windows are averaged and
   SE(a) <= ``target_stderr`` a0 and SE(W_c) <= ``target_W_c_stderr`` (status
   ``converged_noisy``); ``converged`` when the update stops changing a (residual <
   ``delta``: the deterministic confined limit) and the targets hold; ``not_converged``
   at ``max_iterations`` windows, reporting the estimate from the windows after the
   truncation (or the last half when no stationary stretch was found) with its error bars.

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

from .._march import march_coefficients
from ..collision_stats import zone_of
from ..config import ModelConfig
from ..errors import NumericalError
from ..transient import drag_time, transient_windows
from .estimate import Records, estimate_point, stderr
from .march import coefficients, mean_coefficients, residual
from .result import Estimate, Iteration
from .window import FIELDS, run_window

__all__ = ["confined_profile", "mser_truncation", "iterate_stationary", "drag_time",
           "transient_windows"]


def confined_profile(cfg: ModelConfig, x: np.ndarray, alpha_c: float) -> np.ndarray:
    """Eq. 25, a(x) = 1 / (alpha_c x + 1/a0) [m], at floe centres ``x`` [m]."""
    return 1.0 / (alpha_c * np.asarray(x, dtype=float) + 1.0 / cfg.a0)


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


class _Windows:
    """What the windows so far measured: per window j the dissipation S (R, N_f), the
    forcing a (R, N_f), the Window statistics and zones of every replica."""

    def __init__(self) -> None:
        self.S: list[np.ndarray] = []
        self.A: list[np.ndarray] = []
        self.C: list[np.ndarray] = []
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
        (:func:`transient_windows`); stationary when valid and the halves after it agree."""
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


def _targets_met(cfg: ModelConfig, est: Estimate) -> bool:
    if cfg.target_stderr > 0:
        se = np.asarray(est.a_stderr, dtype=float)
        if not np.all(np.isfinite(se)) or float(np.max(se)) > cfg.target_stderr * cfg.a0:
            return False
    se_w = est.W_c_stderr
    if cfg.target_W_c_stderr > 0 and est.compact_zone != "none" and est.W_c_n >= 2:
        return bool(np.isfinite(se_w) and se_w <= cfg.target_W_c_stderr)
    return True


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
    wins = _Windows()
    d_min = transient_windows(cfg, k)
    history: list[float] = []
    status = "not_converged"
    d, stationary = 0, False
    est: Estimate | None = None
    for it in range(1, cfg.max_iterations + 1):
        windows, S = run_window(cfg, chain, x0s, a, it == 1)
        zones = [zone_of(cfg, w.x_mean, w.gap_mean) for w in windows]
        wins.add(cfg, S, np.array(a), windows, zones, c_g, k)
        d, stationary = wins.truncation(cfg, d_min)
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
            est = _with_convergence(cfg, _estimate(cfg, wins, d_use, c_g, k), a_new,
                                    wins.A[-1])
            if deterministic and R == 1:        # a fixed point reached exactly
                est.a_stderr = np.abs(a_new[0] - wins.A[-1][0])
                est.a_end_stderr = float(est.a_stderr[-1])
            if (deterministic and R == 1) or _targets_met(cfg, est):
                status = "converged" if deterministic else "converged_noisy"
                d = d_use
                break
    if status == "not_converged":
        if not stationary:            # the last half, never inside the transient's bound
            d = max(len(wins) // 2, min(d_min, len(wins) - 1))
        est = _with_convergence(cfg, _estimate(cfg, wins, d, c_g, k), a, wins.A[-1])
    assert est is not None
    averaged = history[d:] if d < len(history) else history[-1:]
    return Iteration(status, est, history,
                     0.0 if status == "converged" else float(np.median(averaged)), d)


#: the smallest standard error of a reported, as a fraction of a0: below it two runs of a
#: non-chaotic point (replicas agreeing to rounding) differ by more than their jackknife
#: says (measured: 1e-9 a0 apart with standard errors of 1e-11 to 1e-10 a0)
SE_FLOOR = 1e-6


def _with_convergence(cfg: ModelConfig, est: Estimate, a_new: np.ndarray,
                      a_old: np.ndarray) -> Estimate:
    """An ensemble's SE(a) with the change of the replica-mean forcing in the last update,
    |mean_r (a_new - a)|, in quadrature (signed changes of single replicas cancel: it is how
    far the pooled estimate was still moving, which the jackknife alone does not see) and
    at least :data:`SE_FLOOR` a0."""
    if cfg.n_chains < 2:
        return est
    conv = np.abs(np.mean(a_new - a_old, axis=0))
    se = np.sqrt(np.asarray(est.a_stderr, dtype=float) ** 2 + conv**2)
    est.a_stderr = np.maximum(se, SE_FLOOR * cfg.a0)
    est.a_end_stderr = float(est.a_stderr[-1])
    return est


def _estimate(cfg: ModelConfig, wins: _Windows, d: int, c_g: float, k: float) -> Estimate:
    est = estimate_point(cfg, wins.records(d), c_g, k)
    if cfg.n_chains == 1:
        # one trajectory: the windows' implied profiles, autocorrelation-corrected
        per = [march_coefficients(cfg, mean_coefficients(C[None]), c_g, k)[0]
               for C in wins.C[d:]]
        est.a_stderr = (stderr(per) if len(per) > 1
                           else np.full(cfg.n_floes, np.nan))
        est.a_end_stderr = float(est.a_stderr[-1])
    return est
