"""Kernel speed of the contact clock (``integrator = "respa"`` / ``"mts"``) against the
default's loop, measured in the same run, at a few points of the paper's grid.

    python benchmarks/bench_clock.py [--configs predictor:4 respa:10 respa:5] [--repeat 5]
    python benchmarks/bench_clock.py --clusters          # the share of floes sub-stepped

For each point (T 1.2-1.6 s, from a compact zone to sparse floes) every configuration
(``integrator:drag_every``) gets a chain of 8 replicas from the point's random arrangement,
spun up for 10 periods; then windows of two periods accumulating statistics are timed
*alternately* across the configurations, ``--repeat`` times, and the best kept. Prints
replica-floe-steps per second per core and the ratio to the first configuration (one
process, NUMBA_NUM_THREADS=1: a timing, run it on an idle machine and name the CPU).

``--clusters``: instead, for ``respa`` at M = 10, the mean share over two periods of the
pairs whose gap closes within an outer step (at constant velocities) and of the floes in
such a pair: an estimate, from the state at the outer steps, of the floes the kernel
sub-steps (it also sub-steps the two edge floes and re-takes steps a push reaches).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import floewave  # noqa: E402
from floewave import _kernels as K  # noqa: E402
from floewave.ensemble import initial_positions  # noqa: E402
from floewave.model import FloeChain  # noqa: E402

POINTS = [dict(L_x=0.5, T=1.2, C_sd=0.05, eps=0.6, d_f=0.005),
          dict(L_x=0.5, T=1.6, C_sd=0.1, eps=0.4, d_f=0.02),
          dict(L_x=1.5, T=1.5, C_sd=0.05, eps=0.6, d_f=0.01),
          dict(L_x=3.0, T=1.2, C_sd=0.05, eps=0.6, d_f=0.05)]


def chain_of(p: dict, integrator: str, M: int):
    cfg = floewave.ModelConfig(**p, integrator=integrator, drag_every=M)
    k, _ = cfg.check_physics()
    x0 = np.array(initial_positions(cfg))
    ch = FloeChain(cfg, k, x0)
    a = np.full(x0.shape, cfg.a0)
    ch.run(a, 10 * cfg.n_t)
    st = np.zeros((K.N_STATS, *x0.shape))
    ch.run(a, cfg.n_t, st)                          # compiled, spun up
    return ch, a, st, cfg


def speed(configs: list[tuple[str, int]], repeat: int) -> None:
    print("replica-floe-steps/s per core, best of", repeat, "alternating two-period windows")
    for p in POINTS:
        cells = {c: chain_of(p, *c) for c in configs}
        best: dict = {}
        for _ in range(repeat):
            for c, (ch, a, st, cfg) in cells.items():
                n = 2 * cfg.n_t
                t = time.perf_counter()
                ch.run(a, n, st)
                best[c] = min(best.get(c, np.inf), (time.perf_counter() - t) / (n * ch.x.size))
        base = best[configs[0]]
        print(p, "  ".join(f"{i}:{M} {1e-6 / v:6.1f} M ({base / v:4.2f}x)"
                           for (i, M), v in best.items()), flush=True)


def clusters() -> None:
    M = 10
    for p in POINTS:
        ch, a, _, cfg = chain_of(p, "respa", M)
        Dt = M * cfg.dt
        pairs, floes = [], []
        for _ in range(2 * cfg.n_t // M):
            ch.run(a, M)
            g0 = np.diff(ch.x, axis=1) - cfg.L_x
            act = (g0 < 0) | (g0 + Dt * np.diff(ch.u, axis=1) < 0)
            inc = np.zeros(ch.x.shape, bool)
            inc[:, :-1] |= act
            inc[:, 1:] |= act
            pairs.append(act.mean())
            floes.append(inc.mean())
        print(p, f"pairs closing within 10 ms {np.mean(pairs):.3f}, floes in them "
              f"{np.mean(floes):.3f}", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="+", default=["predictor:4", "respa:10", "respa:5"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--clusters", action="store_true")
    args = ap.parse_args()
    if args.clusters:
        clusters()
    else:
        speed([(c.split(":")[0], int(c.split(":")[1])) for c in args.configs], args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
