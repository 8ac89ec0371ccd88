"""Time series of selected floes (the paper's Fig. 4): position, velocity, instantaneous
skin-drag dissipation S_sd and contact force, recorded every ``every`` time steps.

Opt-in and separate from :func:`floewave.run_point`, which it does not touch (off by
default, free when off). A trace runs a :class:`floewave.chain.FloeChain` with a *fixed*
amplitude profile a(x) taken from a converged :class:`~floewave.PointResult` (the
converged state of the attenuation iteration; docs/model.md §4): from the initial state it
spins up ``spin_up`` periods (default ``cfg.n0``), then records ``periods`` periods
(default ``cfg.nT``, the length of the final averaging window) in chunks of ``every``
steps (``chain.run(a, every)``), and evaluates at each recorded state, in numpy:

- S_sd,i(t) = -rho_w C_sd (1/n_x) sum_j |u_rel,ij|^3  [W m^-2] — eq. 19 without its
  time mean, on the floe's n_x drag cells, with
  u_rel,ij = a_i (omega / tanh kh) cos(k (x_i + xi_j) - omega t) - u_i (docs/model.md §2, §3);
- F_c,i(t): the net contact force on floe i [N] (positive towards +x), from the
  contact law of docs/model.md §3 with the pair's overlap and relative velocity.

The velocity is the end-of-step state velocity u_i; the kernel's own statistics use the
predicted velocity u + dt acc (``integrator = "predictor"``), which differs by O(dt acc):
with ``drag_every = 1`` the time mean of S_sd,i(t) agrees with the kernel's eq. 19 average
to that order (tested). With the default ``drag_every = 4`` the kernel samples eq. 19 on
every 4th step at an extrapolated state: per period and floe within about 1.5 % of the
trace's mean, and on average 0.17 % above it (docs/model.md §3).
The trajectory is a new one (chaotic collisions): a sample of the converged state, not a
replay of the run that produced a(x).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _kernels as K
from ._reference import contact_force
from .chain import FloeChain
from .config import ConfigError, ModelConfig
from .forces import cell_offsets
from .model import run_point

__all__ = ["Trace", "trace_point", "floes_at", "instantaneous", "PAPER_DISTANCES"]

#: The floes of the paper's Fig. 4: 3, 12 and 30 m from the ice edge [m].
PAPER_DISTANCES = (3.0, 12.0, 30.0)


@dataclass(frozen=True)
class Trace:
    """Recorded time series of selected floes.

    t [s] (n_t,); floes: indices (n_f,), distance [m]: their mean centre from the ice
    edge in the converged result; x [m], u [m s^-1], S_sd [W m^-2] (negative: a
    dissipation), F_c [N] with shape (n_t, n_f); every: steps between samples; T [s].
    """

    t: np.ndarray
    floes: np.ndarray
    distance: np.ndarray
    x: np.ndarray
    u: np.ndarray
    S_sd: np.ndarray
    F_c: np.ndarray
    every: int
    T: float

    def to_dict(self) -> dict[str, Any]:
        """Plain lists (JSON): every field."""
        return {"t": self.t.tolist(), "floes": self.floes.tolist(),
                "distance": self.distance.tolist(), "x": self.x.tolist(),
                "u": self.u.tolist(), "S_sd": self.S_sd.tolist(), "F_c": self.F_c.tolist(),
                "every": self.every, "T": self.T,
                "units": {"t": "s", "distance": "m", "x": "m", "u": "m s-1",
                          "S_sd": "W m-2", "F_c": "N"}}


def floes_at(x_mean: np.ndarray, distances: Sequence[float]) -> np.ndarray:
    """Indices of the floes whose mean centres are nearest to ``distances`` [m]."""
    x = np.asarray(x_mean, dtype=float)
    return np.array([int(np.argmin(np.abs(x - d))) for d in distances], dtype=np.int64)


def instantaneous(x: np.ndarray, u: np.ndarray, a: np.ndarray, wt: float, P: K.KernelParams,
                  cfg: ModelConfig, xi: np.ndarray, only: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(S_sd, F_c) of every floe at one state (see the module docstring).

    ``wt`` = omega t [rad] (taken modulo 2 pi as the kernel does); ``xi`` the cell
    midpoints relative to the floe centre (:func:`floewave.forces.cell_offsets`).
    ``only``: indices of the floes whose S_sd is wanted (the others are NaN; each floe's
    value is the same number either way: the cells of one floe are one row).
    """
    S_sd = np.full(x.shape, np.nan)
    rows = np.arange(len(x)) if only is None else np.asarray(only)
    th = P.k * (x[rows, None] + xi[None, :]) - wt
    u_rel = (a[rows] * P.u_amp)[:, None] * np.cos(th) - u[rows, None]
    S_sd[rows] = -cfg.rho_w * cfg.C_sd * np.mean(np.abs(u_rel) ** 3, axis=1)
    pair = contact_force(x, u, P, K.kernel_options(cfg, False))
    F_c = np.zeros_like(x)
    F_c[:-1] -= pair
    F_c[1:] += pair
    return S_sd, F_c


def trace_point(cfg: ModelConfig, result: Any = None, *,
                distances: Sequence[float] = PAPER_DISTANCES, floes: Sequence[int] | None = None,
                every: int = 10, periods: int | None = None,
                spin_up: int | None = None) -> Trace:
    """Record selected floes over ``periods`` wave periods with the converged a(x).

    Parameters
    ----------
    cfg : the point.
    result : its :class:`~floewave.PointResult` (``run_point(cfg)`` if ``None``): a(x),
        k and the mean floe positions come from it.
    distances : pick the floes nearest to these distances from the ice edge [m]
        (ignored when ``floes`` gives indices).
    every : time steps between samples (decimation; 10 steps = 1 ms at dt = 1e-4 s).
    periods : recorded periods (default ``cfg.nT``); spin_up : periods before recording
        (default ``cfg.n0``).
    """
    if cfg.confined:
        raise ConfigError("trace: a confined point has no floe motion to trace")
    if every < 1:
        raise ConfigError(f"trace: every = {every}: must be at least 1 time step")
    if result is None:
        result = run_point(cfg)

    a = np.asarray(result.a, dtype=float)
    sel = (np.asarray(floes, dtype=np.int64) if floes is not None
           else floes_at(result.x_mean, distances))
    if np.any(sel < 0) or np.any(sel >= cfg.n_floes):
        raise ConfigError(f"trace: floe indices {sel.tolist()} outside 0..{cfg.n_floes - 1}")
    periods = cfg.nT if periods is None else int(periods)
    spin_up = cfg.n0 if spin_up is None else int(spin_up)
    chain = FloeChain(cfg, float(result.k))
    if spin_up:
        chain.run(a, spin_up * cfg.n_t)
    P = chain.P
    xi = cell_offsets(cfg)
    n_samples = periods * cfg.n_t // every
    t = np.empty(n_samples)
    shape = (n_samples, sel.shape[0])
    x, u, S, F = (np.empty(shape) for _ in range(4))
    two_pi_nt = 2.0 * math.pi / cfg.n_t
    for n in range(n_samples):
        chain.run(a, every)
        wt = two_pi_nt * (chain.istep % cfg.n_t)
        S_all, F_all = instantaneous(chain.x, chain.u, a, wt, P, cfg, xi, only=sel)
        t[n] = chain.istep * cfg.dt
        x[n], u[n] = chain.x[sel], chain.u[sel]
        S[n], F[n] = S_all[sel], F_all[sel]
    chain.check()
    return Trace(t=t, floes=sel, distance=np.asarray(result.x_mean)[sel], x=x, u=u, S_sd=S,
                 F_c=F, every=every, T=cfg.T)
