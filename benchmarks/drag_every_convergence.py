"""Is the drag held over ``drag_every`` steps as good as the drag of every step? The measurement
behind the default.

``drag_every = K`` evaluates the ice-water drag and dissipation sums (eqs. 15, 19) every K time
steps and holds them in between (multiple time stepping: the contacts, which set dt, still run
every step; the floe-bottom sums cost most of a step). Like ``benchmarks/dt_convergence.py``
for the time step, this runs the Fig. 2 points and ``--random`` random grid points with
*matched run length* (:data:`floewave.honesty.MATCHED`: a fixed transient and a fixed number of
averaged windows, no early stop) at K = 1 and at each candidate, two seeds each, and per
quantity

    z = (x_K - x_1) / sqrt(se_K^2 + se_1^2)

(each seed of the candidate against the same seed of K = 1; ``drag_every`` is part of the
configuration, so the two start from independent arrangements). The band is the K = 1 runs'
two seeds against each other: a candidate passes when its RMS z stays within the band (both
near 1 with honest error bars and no change beyond them).

Deterministic check: points whose replicas agree to rounding (non-chaotic, mostly 3 m floes)
have no noise to hide a discretisation error, so their max_i |a_K - a_1| / a0 is the held
drag's own error; it is printed against the same difference between dt 1e-3 and dt 1e-4
(``--dt-reference``: the paper's dt, run with K = 1).

    python benchmarks/drag_every_convergence.py                     # K = 4, 8 + 40 points
    python benchmarks/drag_every_convergence.py --candidates 2 4 5 --random 12

The realised restitution of a two-floe collision has no drag (C_sd = 0), so K cannot change it.
Stochastic (chaotic runs): the machine and date belong beside any figure quoted. Results are
cached in ``--cache`` so a rerun only adds missing runs.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from floewave import ModelConfig
from floewave.honesty import MATCHED, SCALARS, compute_missing, floored, key_of, points, z_scores


def rms(z: np.ndarray) -> float:
    return math.sqrt(float(np.mean(z**2))) if z.size else math.nan


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--candidates", nargs="+", type=int, default=[4])
    ap.add_argument("--random", type=int, default=40, help="random grid points")
    ap.add_argument("--grid-seed", type=int, default=2020)
    ap.add_argument("--seeds", nargs=2, type=int, default=(1, 2))
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--cache", default="/tmp/floewave-drag-every.json")
    ap.add_argument("--dt-reference", action="store_true",
                    help="also run dt 1e-4 (K = 1) for the deterministic comparison")
    args = ap.parse_args(argv)
    pts = points(args.random, args.grid_seed)
    cache_path = Path(args.cache)
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    runs: dict[tuple, str] = {}
    tasks = []
    settings = [(1, 1e-3)] + [(K, 1e-3) for K in args.candidates]
    if args.dt_reference:
        settings.append((1, 1e-4))
    for i, p in enumerate(pts):
        for K, dt in settings:
            for seed in args.seeds:
                d = {**p, **MATCHED, "dt": dt, "drag_every": K, "seed": seed}
                if ModelConfig(**d).n_t % K:
                    continue
                runs[(i, K, dt, seed)] = key_of(d)
                tasks.append((d, key_of(d)))
    compute_missing(tasks, cache, cache_path, args.jobs, len(pts))

    def run(i, K, seed, dt=1e-3):
        return floored(cache[runs[(i, K, dt, seed)]], ModelConfig(**pts[i]).a0)

    s1, s2 = args.seeds
    names = ("a", *SCALARS)
    print(f"\nRMS z over {len(pts)} points (n: number of z values)")
    print(f"{'':>12s} " + " ".join(f"{n:>17s}" for n in names))
    band = [np.concatenate([z_scores(run(i, 1, s1), run(i, 1, s2), name)
                            for i in range(len(pts))]) for name in names]
    print(f"{'band K=1':>12s} " + " ".join(f"{rms(z):5.2f} (n {z.size:4d})" for z in band)
          + "   seed vs seed")
    for K in args.candidates:
        ok = [i for i in range(len(pts)) if (i, K, 1e-3, s1) in runs]
        zs = [np.concatenate([z_scores(run(i, K, s), run(i, 1, s), name)
                              for i in ok for s in (s1, s2)]) for name in names]
        print(f"{'K=' + str(K):>12s} " + " ".join(f"{rms(z):5.2f} (n {z.size:4d})"
                                               for z in zs) + "   vs K = 1, same seed")
        worst = max((float(np.max(np.abs(z))) for z in zs if z.size), default=math.nan)
        print(f"{'':>12s} max |z| {worst:.2f}")
        steps = np.mean([cache[runs[(i, 1, 1e-3, s1)]]["floe_steps"]
                         / cache[runs[(i, K, 1e-3, s1)]]["floe_steps"] for i in ok])
        wall = (sum(cache[runs[(i, 1, 1e-3, s)]]["wall"] for i in ok for s in (s1, s2))
                / sum(cache[runs[(i, K, 1e-3, s)]]["wall"] for i in ok for s in (s1, s2)))
        print(f"{'':>12s} floe-steps K=1 / K={K}: {steps:.2f} (same run length);"
              f" wall-clock ratio {wall:.2f} (a shared machine's, indicative only)")
        # deterministic points: replicas agree to rounding, so a difference is the held
        # drag's own discretisation error
        det = [i for i in ok
               if max(run(i, 1, s1)["a_end_stderr"], run(i, 1, s2)["a_end_stderr"])
               <= 1.01e-6 * ModelConfig(**pts[i]).a0]
        for i in det:
            a0 = ModelConfig(**pts[i]).a0
            dK = np.max(np.abs(np.subtract(run(i, K, s1)["a"], run(i, 1, s1)["a"]))) / a0
            line = f"  non-chaotic point {i} {pts[i]}: max|a_K - a_1|/a0 {dK:.2e}"
            if args.dt_reference and (i, 1, 1e-4, s1) in runs:
                dd = np.max(np.abs(np.subtract(run(i, 1, s1)["a"],
                                               run(i, 1, s1, 1e-4)["a"]))) / a0
                line += f"; dt 1e-3 vs 1e-4 (K = 1): {dd:.2e}"
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
