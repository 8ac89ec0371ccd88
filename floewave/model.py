"""The coupled DEM-wave attenuation iteration (MODEL.md §4, paper §2.4) and ``run_point``."""
from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from . import _kernels as K
from .config import FloewaveError, G, ModelConfig
from .dispersion import alpha_confined, solve_dispersion
from .forces import cell_offsets, kernel_params
from .results import PointResult, compact_zones, fit_exponential, fit_inverse, zone_fits

__all__ = ["FloeChain", "NumericalError", "march_amplitude", "dissipation", "residual",
           "run_point", "Window"]


class NumericalError(FloewaveError, ArithmeticError):
    """The DEM diverged (non-finite state) or floes passed through each other."""


class FloeChain:
    """State of the 1-D floe chain (MODEL.md §1) and the compiled time loop around it."""

    def __init__(self, cfg: ModelConfig, k: float):
        self.cfg = cfg
        self.k = k
        self.P = kernel_params(cfg, k)
        xi = cell_offsets(cfg)
        self.cxi = np.cos(k * xi)
        self.sxi = np.sin(k * xi)
        n = cfg.n_floes
        # x_1 = L_x / 2, x_{i+1} = x_i + L_x + d_f: the ice edge is x = 0
        self.x0 = cfg.L_x / 2.0 + np.arange(n) * (cfg.L_x + cfg.d_f)
        self.work = K.new_work(n)
        self.mom = K.drag_tables(self.cxi, self.sxi, self.P)
        self.idx = np.zeros(n, np.int64)
        self.reset()

    def reset(self) -> None:
        """Back to the initial state: floes at rest at x0, t = 0."""
        n = self.x0.shape[0]
        self.x = self.x0.copy()
        self.u = np.zeros(n)
        self.acc = np.zeros(n)
        self.in_contact = np.zeros(n, dtype=np.int8)
        self.istep = 0
        self._acc_ready = False
        self._acc_a = np.zeros(0)

    def run(self, a: np.ndarray, nsteps: int, stats: np.ndarray | None = None) -> None:
        """Advance ``nsteps`` steps with amplitudes ``a``; accumulate into ``stats`` if given.

        The first half-kick uses the acceleration of the current state *with these
        amplitudes*: it is recomputed whenever ``a`` differs from the amplitudes it was
        computed with (a new iteration), not carried over from the previous iteration's
        amplitudes (issue *trust*: that carried the old wave force into one step per
        iteration).
        """
        if not self._acc_ready or not np.array_equal(a, self._acc_a):
            K.initial_acceleration(self.x, self.u, a, self.x0, self.istep, self.P, self.cxi,
                                   self.sxi, self.acc, self.in_contact)
            self._acc_a = np.array(a, dtype=float)
            self._acc_ready = True
        acc_on = stats is not None
        if stats is None:
            stats = np.zeros((K.N_STATS, 0))
        self.istep = K.advance(self.x, self.u, self.acc, a, self.x0, self.in_contact,
                               self.istep, nsteps, acc_on, self.P, self.cxi, self.sxi, stats,
                               self.work, self.mom, self.idx)

    def check(self) -> None:
        """Raise :class:`NumericalError` on a non-finite state or floes out of order."""
        if not (np.all(np.isfinite(self.x)) and np.all(np.isfinite(self.u))):
            raise NumericalError(f"DEM diverged: non-finite state at step {self.istep}")
        if self.x.shape[0] > 1 and np.any(np.diff(self.x) <= 0.0):
            i = int(np.argmin(np.diff(self.x)))
            raise NumericalError(f"floes {i + 1} and {i + 2} passed through each other at"
                                 f" step {self.istep}")


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


def dissipation(cfg: ModelConfig, s3_mean: np.ndarray) -> np.ndarray:
    """Eq. 19: S_sd,i = -rho_w C_sd <|u_rel|^3>_i  [W m^-2]."""
    return -cfg.rho_w * cfg.C_sd * s3_mean


def march_amplitude(cfg: ModelConfig, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """Amplitudes from the ice edge (eqs. 12, 20, optionally 21), clipped at 0.

    a_1^2 = a0^2 + L_x S_1 / (rho_w g c_g);
    a_i^2 = a_{i-1}^2 + L_x (S_{i-1} + S_i) / (rho_w g c_g)
            [- 3 g^(1/2) h_ow,i-1^(5/2) / c_g with overwash,
             h_ow = c_ow max(k a_{i-1} - s_min, 0)].
    """
    fac = cfg.L_x / (cfg.rho_w * G * c_g)
    n = S_sd.shape[0]
    a = np.empty(n)
    a2 = cfg.a0**2 + fac * S_sd[0]
    a[0] = math.sqrt(max(a2, 0.0))
    for i in range(1, n):
        a2 = a[i - 1] ** 2 + fac * (S_sd[i - 1] + S_sd[i])
        if cfg.overwash:
            h_ow = cfg.c_ow * max(k * a[i - 1] - cfg.s_min, 0.0)
            a2 -= 3.0 * math.sqrt(G) * h_ow**2.5 / c_g
        a[i] = math.sqrt(max(a2, 0.0))
    return a


def residual(a_old: np.ndarray, a_new: np.ndarray) -> float:
    """max_i |a_new - a_old| / a_old over floes with a_old > 0 (0 if there are none)."""
    ok = a_old > 0
    if not ok.any():
        return 0.0
    return float(np.max(np.abs(a_new[ok] - a_old[ok]) / a_old[ok]))


def noise_floor_reached(history: list[float], window: int) -> bool:
    """True when the residual stopped decreasing: the median of the last ``window``
    residuals exceeds half the median of the ``window`` before them."""
    if window <= 0 or len(history) < 2 * window:
        return False
    last = float(np.median(history[-window:]))
    prev = float(np.median(history[-2 * window:-window]))
    return last > 0.5 * prev


def effective_sample_size(samples: np.ndarray) -> float:
    """n (1 - rho1) / (1 + rho1) with rho1 the lag-1 autocorrelation pooled over floes."""
    n = samples.shape[0]
    if n < 3:
        return float(n)
    d = samples - samples.mean(axis=0)
    var = (d * d).sum(axis=0)
    ok = var > 0
    if not ok.any():
        return float(n)
    rho = float(np.mean((d[1:, ok] * d[:-1, ok]).sum(axis=0) / var[ok]))
    rho = min(max(rho, 0.0), 0.95)
    return max(n * (1.0 - rho) / (1.0 + rho), 2.0)


def stderr(samples: list[np.ndarray]) -> np.ndarray:
    """Per-floe standard error of the mean of iteration samples (autocorrelation-corrected)."""
    S = np.asarray(samples)
    return S.std(axis=0, ddof=1) / math.sqrt(effective_sample_size(S))


def max_stderr(samples: list[np.ndarray]) -> float:
    """max_i of :func:`stderr` [m]."""
    return float(np.max(stderr(samples)))


def _add_sample(samples: list[np.ndarray], win_sum: dict[str, np.ndarray],
                a_new: np.ndarray, window: Window) -> None:
    """Add one iteration to the average: its amplitudes and its window statistics."""
    samples.append(a_new)
    for name in Window.FIELDS:
        win_sum[name] = win_sum.get(name, 0.0) + getattr(window, name)


def kernel_mode(cfg: ModelConfig) -> str:
    """Which kernel ran, e.g. ``numba/quadrature/predictor`` or ``numba/confined``."""
    if cfg.confined:
        return f"numba/{cfg.drag_integration}/confined"
    return f"numba/{cfg.drag_integration}/{cfg.integrator}"


def run_point(cfg: ModelConfig,
              progress: Callable[[int, float, str], None] | None = None) -> PointResult:
    """Run the attenuation iteration for one point (MODEL.md §4) and fit the results (§6).

    Iteration: start with a_i = a0; per iteration run n0 periods (spin-up, DEM state carried
    over when ``warm_start``) and nT periods accumulating eq. 19; march eq. 20; relax
    a <- a + relax (a_new - a). Stops with status

    - ``converged``: residual max_i |a_new - a| / a < delta; reports the last a_new;
    - ``converged_noisy``: the residual reached its noise floor (see
      :func:`noise_floor_reached`); a is the mean of a_new over ``n_average`` further
      iterations, ``a_stderr`` its standard error (autocorrelation-corrected) and
      ``noise`` the median residual over that window;
    - ``not_converged``: ``max_iterations`` reached first (mean of any averaged
      iterations, else the last a_new).

    ``progress(iteration, residual, phase)`` is called after every iteration.
    Deterministic: the same ``cfg`` gives the same numbers bit for bit on one machine.
    """
    t_start = time.perf_counter()
    cfg.check_physics()
    k, c_g = solve_dispersion(cfg)
    alpha_c = alpha_confined(cfg)
    chain = FloeChain(cfg, k)
    n = cfg.n_floes
    n_t = cfg.n_t
    a = np.full(n, cfg.a0)
    history: list[float] = []
    samples: list[np.ndarray] = []
    win_sum: dict[str, np.ndarray] = {}
    recent: list[tuple[np.ndarray, Window]] = []
    phase = "iterate"
    status = "not_converged"
    last_window: Window | None = None
    a_new = a
    a_prev = a
    for it in range(1, cfg.max_iterations + 1):
        stats = K.new_stats(n)
        if cfg.confined:
            K.confined_window(chain.x0, a, cfg.nT * n_t, chain.P, chain.cxi, chain.sxi, stats)
        else:
            if not cfg.warm_start:
                chain.reset()
            n0 = cfg.n0 if (it == 1 or not cfg.warm_start) else cfg.n0_warm
            chain.run(a, n0 * n_t)
            chain.run(a, cfg.nT * n_t, stats)
            chain.check()
        window = Window(cfg, stats, cfg.nT * n_t, chain.x0)
        last_window = window
        S_sd = dissipation(cfg, window.s3_mean)
        a_new = march_amplitude(cfg, S_sd, c_g, k)
        if not np.all(np.isfinite(a_new)):
            raise NumericalError(f"non-finite amplitude at iteration {it}")
        res = residual(a, a_new)
        history.append(res)
        if phase == "average":
            _add_sample(samples, win_sum, a_new, window)
        elif cfg.reuse_floor and cfg.noise_window > 0:
            recent = (recent + [(a_new, window)])[-cfg.noise_window:]
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
            for a_s, win in recent:
                _add_sample(samples, win_sum, a_s, win)
        elif phase == "average" and len(samples) >= cfg.n_average:
            if cfg.target_stderr <= 0 or max_stderr(samples) <= cfg.target_stderr * cfg.a0:
                status = "converged_noisy"
                break
    iterations = len(history)

    if samples:
        a_out = np.mean(samples, axis=0)
        a_stderr = stderr(samples) if len(samples) > 1 else np.full(n, np.nan)
        prof = {name: win_sum[name] / len(samples) for name in Window.FIELDS}
        noise = float(np.median(history[-len(samples):]))
    else:
        a_out = a_new
        a_stderr = np.abs(a_new - a_prev)
        prof = {name: getattr(last_window, name) for name in Window.FIELDS}
        noise = 0.0 if status == "converged" else float(history[-1])

    x = prof["x_mean"]
    zones = compact_zones(x, prof["gap_mean"], cfg.L_x, gap_threshold=cfg.gap_threshold,
                          min_pairs=cfg.compact_min_pairs, min_length=cfg.compact_min_length,
                          bridge=cfg.compact_bridge, bridge_gap=cfg.compact_bridge_gap)
    alpha_all, r_all = fit_inverse(x, a_out, cfg.a0)
    alpha_edge, r_edge, alpha_inner, r_inner = zone_fits(
        x, a_out, cfg.a0, zones, min_floes=cfg.fit_min_floes, min_length=cfg.fit_min_length)
    alpha_exp, r_exp = fit_exponential(x, a_out, cfg.a0)
    wall = time.perf_counter() - t_start
    return PointResult(
        x_mean=x, a=a_out, a_stderr=a_stderr, S_sd=dissipation(cfg, prof["s3_mean"]),
        gap_mean=prof["gap_mean"], contact_fraction=prof["contact_fraction"],
        collisions=prof["collisions"], F_w_mean=prof["F_w_mean"], F_c_mean=prof["F_c_mean"],
        F_d_mean=prof["F_d_mean"], n_floes=n, W_c=zones.W_c, compact_zone=zones.layout,
        compact_end=zones.compact_end, ice_extent=zones.ice_extent,
        alpha_all=alpha_all, alpha_all_resid=r_all, alpha_edge=alpha_edge,
        alpha_edge_resid=r_edge, alpha_inner=alpha_inner, alpha_inner_resid=r_inner,
        alpha_exp=alpha_exp, alpha_exp_resid=r_exp, alpha_c=alpha_c, k=k, c_g=c_g,
        status=status, noise=noise, iterations=iterations, residual=float(history[-1]),
        floe_steps=cfg.floe_steps_of(iterations), wall_time=wall,
        kernel_mode=kernel_mode(cfg), a_end=float(a_out[-1]), a0=cfg.a0,
        residual_history=np.array(history),
    )
