"""The model point: :func:`run_point` runs the attenuation iteration (docs/model.md §4,
paper §2.4; :mod:`floewave.iteration`) on an ensemble of floe chains and reports its
:class:`~floewave.results.PointResult`."""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from .chain import FloeChain
from .config import ModelConfig
from .dispersion import alpha_confined
from .ensemble import initial_positions
from .errors import NumericalError
from .iteration.noise_floor import iterate_noise_floor
from .iteration.stationary import iterate_stationary
from .results import PointResult

__all__ = ["FloeChain", "NumericalError", "run_point", "kernel_mode"]


def kernel_mode(cfg: ModelConfig) -> str:
    """Which kernel ran, e.g. ``numba/quadrature/predictor`` or ``numba/confined``."""
    if cfg.confined:
        return f"numba/{cfg.drag_integration}/confined"
    return f"numba/{cfg.drag_integration}/{cfg.integrator}"


def run_point(cfg: ModelConfig,
              progress: Callable[[int, float, str], None] | None = None) -> PointResult:
    """Run the attenuation iteration for one point (docs/model.md §4) and fit the results (§6).

    The replicas start from :func:`floewave.ensemble.initial_positions` and run in one
    :class:`~floewave.chain.FloeChain`; the iteration is ``cfg.protocol``'s
    (:mod:`floewave.iteration`: the stationary protocol, or the legacy noise floor), its
    :class:`~floewave.iteration.result.Estimate` the point's outputs but those of the run
    itself (:data:`floewave.iteration.result.OF_THE_RUN`).

    ``progress(iteration, residual, phase)`` is called after every iteration.
    Deterministic: the same ``cfg`` gives the same numbers bit for bit on one machine.
    """
    t_start = time.perf_counter()
    mode = kernel_mode(cfg)
    k, c_g = cfg.check_physics()          # the one solve of the dispersion relation
    alpha_c = alpha_confined(cfg, k, c_g)
    R = cfg.n_chains
    x0s = np.array(initial_positions(cfg))
    chain = FloeChain(cfg, k, x0s)         # the R replicas in one kernel
    if cfg.protocol == "stationary":
        out = iterate_stationary(cfg, chain, x0s, k, c_g, alpha_c, progress)
    else:
        out = iterate_noise_floor(cfg, chain, x0s, k, c_g, progress)
    status, est, history, noise = out.status, out.estimate, out.history, out.noise
    iterations = len(history)
    n = cfg.n_floes
    wall = time.perf_counter() - t_start
    return PointResult(
        **est.outputs(),
        n_floes=n, alpha_c=alpha_c, k=k, c_g=c_g, status=status, noise=noise,
        iterations=iterations, residual=float(history[-1]),
        floe_steps=cfg.floe_steps_of(iterations), wall_time=wall,
        kernel_mode=mode, a0=cfg.a0, residual_history=np.array(history),
        replicas=R)
