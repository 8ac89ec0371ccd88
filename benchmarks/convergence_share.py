"""How many random paper-grid points end ``not_converged``: single trajectories (R = 1,
uniform: the paper's model) against the default ensemble (R = 8), on the same points.

    python benchmarks/convergence_share.py --n 40 --grid-seed 11 --jobs 2

Prints the statuses of both per point and the shares, with a binomial standard error.
Stochastic (chaotic runs; another grid seed draws other points).
"""
from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import sys
import time
from collections import Counter

from floewave import ModelConfig, run_point
from floewave.honesty import points


def one(task):
    p, R = task
    extra = {"replicas": 1, "placement": "uniform"} if R == 1 else {"replicas": R}
    t = time.perf_counter()
    r = run_point(ModelConfig(**p, **extra))
    return p, R, r.status, r.iterations, r.floe_steps, time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--grid-seed", type=int, default=11)
    ap.add_argument("--replicas", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    pts = points(args.n, args.grid_seed)[8:]           # the random grid points only
    tasks = [(p, R) for p in pts for R in (1, args.replicas)]
    res = {}
    with mp.get_context("fork").Pool(args.jobs) as pool:
        for p, R, status, it, fs, _wall in pool.imap_unordered(one, tasks):
            res[tuple(sorted(p.items())), R] = (status, it, fs)
            print(f"  {len(res)}/{len(tasks)}", flush=True)
    for R in (1, args.replicas):
        st = Counter(res[tuple(sorted(p.items())), R][0] for p in pts)
        n = len(pts)
        k = st["not_converged"]
        share = k / n
        se = math.sqrt(share * (1 - share) / n)
        its = [res[tuple(sorted(p.items())), R][1] for p in pts]
        fs = [res[tuple(sorted(p.items())), R][2] for p in pts]
        print(f"R = {R}: {dict(st)}; not_converged {k}/{n} = {share:.3f} +- {se:.3f}; "
              f"mean iterations {sum(its) / n:.1f}; mean floe-steps {sum(fs) / n:.3g}")
    both = [p for p in pts if res[tuple(sorted(p.items())), 1][0] == "not_converged"]
    for p in both:
        print("single not_converged:", p, "-> ensemble",
              res[tuple(sorted(p.items())), args.replicas][0])
    return 0


if __name__ == "__main__":
    sys.exit(main())
