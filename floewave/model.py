"""The coupled DEM-wave attenuation iteration (docs/model.md §4, paper §2.4) and ``run_point``."""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

import numpy as np

from . import _kernels as K
from .config import ModelConfig
from .dispersion import alpha_confined
from .ensemble import (
    Iteration,
    Records,
    estimate_point,
    initial_positions,
    march_rows,
    residual,
    stderr,
    zone_of,
)
from .errors import NumericalError
from .forces import cell_offsets
from .protocol import iterate_stationary
from .results import PointResult
from .window import Window, dissipation, run_window

__all__ = ["FloeChain", "NumericalError", "march_amplitude", "dissipation", "residual",
           "run_point", "Window"]


class FloeChain:
    """State of the 1-D floe chain (docs/model.md §1), or of R chains in lockstep (an ensemble:
    one row of ``x0`` per replica), and the compiled time loop around it.

    The R chains share every coefficient and differ only in state; one call of the kernel
    advances them all (:func:`floewave._kernels.make_advance`), replica by replica the same
    numbers whatever R is.
    """

    def __init__(self, cfg: ModelConfig, k: float, x0: np.ndarray | None = None):
        self.cfg = cfg
        self.k = k
        self.P = K.kernel_params(cfg, k)
        xi = cell_offsets(cfg)
        self.cxi = np.cos(k * xi)
        self.sxi = np.sin(k * xi)
        n = cfg.n_floes
        # x_1 = L_x / 2, x_{i+1} = x_i + L_x + d_f: the ice edge is x = 0 (uniform
        # placement; an ensemble passes each replica's own arrangement as a row)
        if x0 is None:
            x0 = cfg.L_x / 2.0 + np.arange(n) * (cfg.L_x + cfg.d_f)
        self.x0 = np.ascontiguousarray(x0, dtype=float)
        if self.x0.ndim not in (1, 2) or self.x0.shape[-1] < 2:
            raise ValueError(f"x0 must be (N_f,) or (R, N_f) with N_f >= 2, not"
                             f" {self.x0.shape}")
        self.n = self.x0.shape[-1]
        self.replicas = self.x0.size // self.n
        self.work = K.new_work(self.x0.size)
        # the tables' moments for the drag mode the loop runs (prefix_sums reads either)
        self.opts = K.kernel_options(cfg, False)
        self.mom = (K.exact_tables(self.P.geom) if self.opts.drag == K.DRAG_EXACT
                    else K.drag_tables(self.cxi, self.sxi, self.P))
        self.idx = np.zeros(self.x0.size, np.int64)
        self._spin = K.make_advance(self.opts)
        self._average = K.make_advance(K.kernel_options(cfg, True))
        self.reset()

    def reset(self) -> None:
        """Back to the initial state: floes at rest at x0, t = 0."""
        self.x = self.x0.copy()
        self.u = np.zeros_like(self.x0)
        self.acc = np.zeros_like(self.x0)
        self.in_contact = np.zeros(self.x0.shape, dtype=np.int8)
        self.istep = 0
        self._acc_ready = False
        self._acc_a = np.zeros(0)

    def _loop(self, fn, a, nsteps, stats, init) -> None:
        self.istep = fn(self.x.ravel(), self.u.ravel(), self.acc.ravel(), a.ravel(),
                        self.x0.ravel(), self.in_contact.ravel(), self.istep, nsteps, self.n,
                        self.P, self.cxi, self.sxi, self.mom, stats, self.work,
                        self.idx, init)

    def run(self, a: np.ndarray, nsteps: int, stats: np.ndarray | None = None) -> None:
        """Advance ``nsteps`` steps with amplitudes ``a`` (shape of ``x0``, or one profile
        for every replica); accumulate into ``stats`` if given ((N_STATS, N_f) for one
        chain, (N_STATS, R, N_f) or (N_STATS, R N_f) for R).

        The first half-kick uses the acceleration of the current state *with these
        amplitudes*: it is recomputed whenever ``a`` differs from the amplitudes it was
        computed with (a new iteration), not carried over from the previous iteration's
        amplitudes (issue *trust*: that carried the old wave force into one step per
        iteration).
        """
        a = np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float), self.x0.shape))
        if not self._acc_ready or not np.array_equal(a, self._acc_a):
            # the kernel re-evaluates every replica; a replica whose amplitudes did not
            # change keeps its acceleration (as it would run alone: replica r's numbers
            # must not depend on the others)
            keep = (np.all(a == self._acc_a, axis=-1) if self._acc_ready
                    else np.zeros(a.shape[:-1], dtype=bool))
            saved = self.acc.copy()
            # the drag sums held between evaluations (``drag_every`` > 1), likewise
            held = [h.copy() for h in self._held_rows()]
            self._loop(self._spin, a, 0, np.zeros((K.N_STATS, 0)), True)
            self.acc[keep] = saved[keep]
            for h, old in zip(self._held_rows(), held, strict=True):
                h[keep] = old[keep]
            self._acc_a = a.copy()
            self._acc_ready = True
        if stats is None:
            self._loop(self._spin, a, nsteps, np.zeros((K.N_STATS, 0)), False)
        else:
            every = self.cfg.drag_every
            if every > 1 and (nsteps % every or self.istep % every):
                # each drag evaluation's dissipation stands for drag_every steps: a window of
                # other bounds would hold another number of steps than it divides by
                raise ValueError(f"statistics over {nsteps} steps from step {self.istep}:"
                                 f" both must be multiples of drag_every = {every}")
            flat = stats.reshape(K.N_STATS, self.x0.size)
            if not np.shares_memory(flat, stats):
                raise ValueError("stats must be a contiguous (N_STATS, ...) array")
            self._loop(self._average, a, nsteps, flat, False)

    def _held_drag(self) -> np.ndarray:
        """The drag sums the time loop holds between evaluations, (R, N_f) view."""
        return self.work[K.W_SC + K.SC_S2, :self.x0.size].reshape(self.x0.shape)

    def _held_rows(self) -> list[np.ndarray]:
        """Every row of scratch a held drag carries from step to step ((R, N_f) views):
        the sums held, and for ``drag_hold = "linear"`` the last evaluation, its slope and
        its step."""
        rows = [K.W_SC + K.SC_S2, K.W_D0, K.W_DS, K.W_DI]
        return [self.work[r, :self.x0.size].reshape(self.x0.shape) for r in rows]

    def check(self) -> None:
        """Raise :class:`NumericalError` on a non-finite state or floes out of order."""
        if not (np.all(np.isfinite(self.x)) and np.all(np.isfinite(self.u))):
            raise NumericalError(f"DEM diverged: non-finite state at step {self.istep}")
        d = np.diff(self.x, axis=-1).reshape(self.replicas, -1)
        if np.any(d <= 0.0):
            r, i = np.unravel_index(int(np.argmin(d)), d.shape)
            where = f" (replica {r})" if self.replicas > 1 else ""
            raise NumericalError(f"floes {i + 1} and {i + 2} passed through each other at"
                                 f" step {self.istep}{where}")


def march_amplitude(cfg: ModelConfig, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """Amplitudes from the ice edge (eqs. 12, 20, optionally 21), clipped at 0
    (:func:`floewave.ensemble.march_rows`, which marches many profiles at once).

    a_1^2 = a0^2 + L_x S_1 / (rho_w g c_g);
    a_i^2 = a_{i-1}^2 + L_x (S_{i-1} + S_i) / (rho_w g c_g)
            [- 3 g^(1/2) h_ow,i-1^(5/2) / c_g with overwash,
             h_ow = c_ow max(k a_{i-1} - s_min, 0)].
    """
    return march_rows(cfg, np.asarray(S_sd, dtype=float), c_g, k)


def noise_floor_reached(history: list[float], window: int) -> bool:
    """True when the residual stopped decreasing: the median of the last ``window``
    residuals exceeds half the median of the ``window`` before them."""
    if window <= 0 or len(history) < 2 * window:
        return False
    last = float(np.median(history[-window:]))
    prev = float(np.median(history[-2 * window:-window]))
    return last > 0.5 * prev


def max_stderr(samples: list[np.ndarray]) -> float:
    """max_i of :func:`stderr` [m]."""
    return float(np.max(stderr(samples)))


def kernel_mode(cfg: ModelConfig) -> str:
    """Which kernel ran, e.g. ``numba/quadrature/predictor`` or ``numba/confined``."""
    if cfg.confined:
        return f"numba/{cfg.drag_integration}/confined"
    return f"numba/{cfg.drag_integration}/{cfg.integrator}"


def run_point(cfg: ModelConfig,
              progress: Callable[[int, float, str], None] | None = None) -> PointResult:
    """Run the attenuation iteration for one point (docs/model.md §4) and fit the results (§6).

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
    k, c_g = cfg.check_physics()          # the one solve of the dispersion relation
    alpha_c = alpha_confined(cfg, k, c_g)
    R = cfg.n_chains
    x0s = np.array(initial_positions(cfg))
    chain = FloeChain(cfg, k, x0s)         # the R replicas in one kernel
    if cfg.protocol == "stationary":
        out = iterate_stationary(cfg, chain, x0s, k, c_g, alpha_c, progress)
    else:
        out = _iterate_noise_floor(cfg, chain, x0s, k, c_g, progress)
    status, est, history, noise = out.status, out.estimate, out.history, out.noise
    iterations = len(history)
    n = cfg.n_floes
    wall = time.perf_counter() - t_start
    declared = {f.name for f in dataclasses.fields(PointResult)}
    return PointResult(
        **{name: value for name, value in est.items() if name in declared},
        n_floes=n, alpha_c=alpha_c, k=k, c_g=c_g, status=status, noise=noise,
        iterations=iterations, residual=float(history[-1]),
        floe_steps=cfg.floe_steps_of(iterations), wall_time=wall,
        kernel_mode=kernel_mode(cfg), a0=cfg.a0, residual_history=np.array(history),
        replicas=R)


def _iterate_noise_floor(cfg: ModelConfig, chain: FloeChain, x0s: np.ndarray, k: float,
                         c_g: float, progress) -> Iteration:
    """The ``noise_floor`` protocol (:func:`run_point`'s docstring) on ``chain``."""
    R = cfg.n_chains
    n = cfg.n_floes
    a = np.full((R, n), cfg.a0)          # per replica (rows equal under coupling "mean")
    history: list[float] = []
    samples: list[tuple] = []        # per averaging iteration: (S, a_new, windows, zones)
    recent: list[tuple] = []
    phase = "iterate"
    status = "not_converged"
    last: tuple | None = None
    stop_est: dict | None = None
    a_new = a
    a_prev = a
    for it in range(1, cfg.max_iterations + 1):
        windows, S = run_window(cfg, chain, x0s, a, it == 1)
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
        # the paper's W_c is a property of one averaging window: found per window and replica
        zones = [zone_of(cfg, w.x_mean, w.gap_mean) for w in windows]
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
            enough, stop_est = _precise_enough(cfg, samples, c_g, k)
            if enough:
                status = "converged_noisy"
                break
    assert last is not None

    kept = samples if samples else [last]
    # the estimate that ended the averaging is the point's (same samples): not recomputed
    est = (stop_est if status == "converged_noisy" and stop_est is not None
           else estimate_point(cfg, _records(kept), c_g, k))
    if R == 1:   # one trajectory: the iteration standard error (as the paper's model)
        if samples:
            est["a_stderr"] = (stderr([s[1][0] for s in samples]) if len(samples) > 1
                               else np.full(n, np.nan))
        else:
            est["a_stderr"] = np.abs(a_new[0] - a_prev[0])
        est["a_end_stderr"] = float(est["a_stderr"][-1])
    elif not samples:
        # the last iteration alone (converged, or stopped before any averaging): its
        # replica spread and, in quadrature, how far it was from the fixed point (the
        # single trajectory's error of such a point)
        conv = np.abs(np.mean(a_new - a_prev, axis=0))
        est["a_stderr"] = np.sqrt(est["a_stderr"] ** 2 + conv**2)
        est["a_end_stderr"] = float(est["a_stderr"][-1])
    if samples:
        noise = float(np.median(history[-len(samples):]))
    else:
        noise = 0.0 if status == "converged" else float(history[-1])
    return Iteration(status, est, history, noise)


def _records(kept: list[tuple]) -> Records:
    """The averaging window's samples as :class:`floewave.ensemble.Records`."""
    S = np.array([s[0] for s in kept])
    a_new = np.array([s[1] for s in kept])
    profiles = {}
    for name in Window.FIELDS:
        total = 0.0
        for sample in kept:
            total = total + np.array([getattr(w, name) for w in sample[2]])
        profiles[name] = total / len(kept)
    zones = [sample[3] for sample in kept]
    return Records(S, a_new, profiles,
                   np.array([[z.W_c for z in row] for row in zones]),
                   np.array([[z.compact_end for z in row] for row in zones]),
                   [[z.layout for z in row] for row in zones])


def _precise_enough(cfg: ModelConfig, samples: list, c_g: float,
                    k: float) -> tuple[bool, dict | None]:
    """May the averaging stop? max_i SE(a_i) <= ``target_stderr`` a0 (the iteration
    standard error for one trajectory, the jackknife over replicas for an ensemble) and,
    for an ensemble with a compact zone in at least two replicas, SE(W_c) <=
    ``target_W_c_stderr``. A target <= 0 is no condition. Also returns the ensemble's
    estimate when it was computed (the point's, if the averaging stops here)."""
    if cfg.n_chains == 1:
        return (cfg.target_stderr <= 0
                or max_stderr([s[1][0] for s in samples]) <= cfg.target_stderr * cfg.a0), None
    if cfg.target_stderr <= 0 and cfg.target_W_c_stderr <= 0:
        return True, None
    est = estimate_point(cfg, _records(samples), c_g, k)
    if cfg.target_stderr > 0 and float(np.max(est["a_stderr"])) > cfg.target_stderr * cfg.a0:
        return False, est
    se_w = est["W_c_stderr"]
    return (cfg.target_W_c_stderr <= 0 or not math.isfinite(se_w)
            or se_w <= cfg.target_W_c_stderr), est
