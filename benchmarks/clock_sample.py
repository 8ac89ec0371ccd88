"""How a numerics change moves the cost and the statuses of random paper-grid points: the
candidate (``--set``) against a baseline (``--baseline``, default: this checkout's
defaults), on the same points, measured in the same run.

    python benchmarks/clock_sample.py --n 200 --grid-seed 5 --jobs 2 \\
        --set integrator=respa --set drag_every=10

Each point runs once per configuration, in worker processes (``--jobs``), the two
configurations of a point one after the other in one task so that a shared machine's slow
phases hit both alike. Prints per configuration: the statuses with the not_converged share
and its binomial standard error, CPU seconds per point (median, 99th percentile, largest;
the slowest 1 % as a multiple of the median), the total and the mean windows; then the
ratio of the totals (the grid's cost scales with it). Stochastic (chaotic runs; another
grid seed draws other points); CPU seconds are a timing: name the machine with them.
"""
from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import sys
import time
from collections import Counter

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from floewave import ModelConfig, run_point  # noqa: E402
from floewave.cli import config_from_sets  # noqa: E402
from floewave.honesty import points  # noqa: E402


def _fields(sets: list[str]) -> dict:
    names = {s.split("=")[0] for s in sets}
    return {k: v for k, v in config_from_sets(sets).to_dict().items() if k in names}


def one(task):
    p, configs = task
    out = []
    for name, extra in configs:
        t = time.process_time()
        r = run_point(ModelConfig(**{**p, **extra}))
        out.append((name, r.status, r.iterations, r.floe_steps, time.process_time() - t))
    return p, out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--grid-seed", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--baseline", action="append", default=[], metavar="NAME=VALUE")
    args = ap.parse_args()
    pts = points(args.n, args.grid_seed)[8:]            # the random grid points only
    configs = [("baseline", _fields(args.baseline)), ("candidate", _fields(args.set))]
    print(f"baseline {configs[0][1] or 'defaults'}; candidate {configs[1][1]}; "
          f"{len(pts)} points, grid seed {args.grid_seed}", flush=True)
    run_point(ModelConfig(L_x=3.0, n0=1, nT=1, max_iterations=2, **configs[0][1]))  # compile
    run_point(ModelConfig(L_x=3.0, n0=1, nT=1, max_iterations=2, **configs[1][1]))
    res: dict[str, list] = {name: [] for name, _ in configs}
    with mp.get_context("fork").Pool(args.jobs) as pool:
        for i, (p, out) in enumerate(pool.imap_unordered(one, [(p, configs) for p in pts])):
            for name, *rest in out:
                res[name].append((p, *rest))
            if (i + 1) % 20 == 0:
                print(f"  {i + 1}/{len(pts)}", flush=True)
    totals = {}
    for name, rows in res.items():
        n = len(rows)
        st = Counter(r[1] for r in rows)
        k = st["not_converged"]
        share = k / n
        se = math.sqrt(share * (1 - share) / n)
        cpu = np.array([r[4] for r in rows])
        med = float(np.median(cpu))
        p99 = float(np.quantile(cpu, 0.99))
        its = np.array([r[2] for r in rows])
        totals[name] = cpu.sum()
        print(f"{name}: {dict(st)}; not_converged {k}/{n} = {share:.3f} +- {se:.3f}; CPU s "
              f"per point median {med:.3f}, 99th percentile {p99:.3f} ({p99 / med:.1f}x), "
              f"largest {cpu.max():.3f} ({cpu.max() / med:.1f}x); total {cpu.sum():.1f}; "
              f"windows median {np.median(its):.0f}, mean {its.mean():.1f}, "
              f"at the cap {int((its >= rows[0][0].get('max_iterations', 100)).sum())}")
        slow = sorted(rows, key=lambda r: -r[4])[:max(2, n // 100)]
        for r in slow:
            print(f"    slowest: {r[4]:.2f} s {r[1]} {r[2]} windows {r[0]}")
    print(f"candidate / baseline total CPU: {totals['candidate'] / totals['baseline']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
