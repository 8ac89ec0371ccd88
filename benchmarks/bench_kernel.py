"""Kernel speed in floe-steps per second (one core), numba versus the numpy twin, same run.

    python benchmarks/bench_kernel.py [--steps 24000] [--repeat 5]

For each drag mode and floe size (L_x = 0.5, 1.5, 3.0 m at T = 1.2 s, the paper's lab
setup) it times the numba kernel (best of --repeat windows of --steps steps, after
compilation and a spin-up so contacts are active), both for spin-up steps and for steps
that accumulate the averaging-window statistics, and the plain vectorised-numpy
implementation of the same (spin-up) time step (floewave._reference, quadrature drag) for a
shorter window, and prints them and the numba/numpy ratio. Timings on a
shared machine are noisy: compare figures from the same run.
"""
from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from floewave import ModelConfig, solve_dispersion  # noqa: E402
from floewave import _reference as ref  # noqa: E402
from floewave.model import FloeChain  # noqa: E402


def _best(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def bench(cfg: ModelConfig, steps: int, repeat: int,
          numpy_steps: int) -> tuple[float, float, float]:
    """Floe-steps/s of (numba spin-up steps, numba steps accumulating the statistics,
    numpy twin of the spin-up step). With the default iteration (n0_warm = 0) all steps
    after the first iteration's n0 periods accumulate."""
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = np.full(cfg.n_floes, cfg.a0)
    stats = np.zeros((8, cfg.n_floes))
    chain.run(a, 2 * cfg.n_t)  # compile + spin-up
    chain.run(a, 10, stats)
    t_spin = _best(lambda: chain.run(a, steps), repeat)
    t_acc = _best(lambda: chain.run(a, steps, stats), repeat)
    x, u, acc = chain.x.copy(), chain.u.copy(), chain.acc.copy()
    best_np = _best(lambda: ref.advance(x, u, acc, a, chain.x0, chain.istep, numpy_steps,
                                        chain.P, chain.opts, chain.cxi, chain.sxi),
                         max(1, repeat // 2))
    fs = steps * cfg.n_floes
    return fs / t_spin, fs / t_acc, numpy_steps * cfg.n_floes / best_np


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=24000)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--numpy-steps", type=int, default=2000)
    args = p.parse_args()
    print(f"{'mode':<12}{'L_x':>5}{'N_f':>5}{'numba spin':>12}{'numba acc':>11}"
          f"{'numpy':>9}{'spin/numpy':>12}   [M floe-steps/s, one core]")
    for mode in ("quadrature", "exact"):
        for L_x in (0.5, 1.5, 3.0):
            cfg = ModelConfig(L_x=L_x, T=1.2, drag_integration=mode)
            spin, acc, npy = bench(cfg, args.steps, args.repeat, args.numpy_steps)
            print(f"{mode:<12}{L_x:>5}{cfg.n_floes:>5}{spin / 1e6:>12.2f}{acc / 1e6:>11.2f}"
                  f"{npy / 1e6:>9.3f}{spin / npy:>12.0f}")


if __name__ == "__main__":
    main()
