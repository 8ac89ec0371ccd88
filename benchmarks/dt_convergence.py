"""Is a larger time step as good as the paper's dt = 1e-4 s? The measurement behind the default.

Two checks (docs/model.md §3: a larger default dt is allowed where a convergence record shows
no change beyond the error bars):

1. **Restitution.** The realised restitution of an isolated head-on collision of two lab-ice
   floes (L_x = 0.5 m, 0.05 m/s, no drag, springs or added mass) at every nominal eps and
   contact law of the model's table, at dt 1e-4 and each candidate; the table's tolerance
   is +-0.01. Also the contact duration in steps (steps per binary contact).
2. **The answers.** The Fig. 2 points and ``--random`` random grid points run at dt 1e-4
   and at the candidate with *matched run length* (:data:`MATCHED`: the stationary protocol
   with a fixed transient and a fixed number of averaged windows, no early stop, so both
   average the same periods), and a second candidate run with another seed. Per quantity,
   z = (x_cand - x_1e-4) / sqrt(se^2 + se^2); the between-seed z of the two candidate runs
   is the band that dt's z must stay within (RMS z of both near 1 when the error bars are
   honest and dt changes nothing beyond them).

    python benchmarks/dt_convergence.py                     # dt 1e-3 against 1e-4, 8 + 40 points
    python benchmarks/dt_convergence.py --candidates 1e-3 2e-3 --random 12

Stochastic (part 2): chaotic runs, marked as such; the machine and date belong beside any
figure quoted. Results are cached in ``--cache`` so a rerun only adds missing runs.
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
from floewave.model import FloeChain

LAWS = (("hertz_disk", "liggghts", False), ("linear", "liggghts", False),
        ("linear", "exact", False), ("hertz_disk", "liggghts", True))


def restitution(dt: float, eps: float, contact: str, damping: str, clip: bool,
                v: float = 0.05) -> tuple[float, int]:
    """(realised restitution, steps in contact) of two free lab-ice floes colliding at v."""
    cfg = ModelConfig(L_x=0.5, L_sheet=1.0, a0=0.0125, C_sd=0.0, k_s=0.0, C_m=0.0,
                      d_f=0.001, dispersion="ow", dt=dt, T=1.2, eps=eps, contact=contact,
                      damping=damping, clip_attraction=clip)
    chain = FloeChain(cfg, 1.0)
    chain.u[:] = [0.5 * v, -0.5 * v]
    a = np.zeros(2)
    touched, steps = False, 0
    for _ in range(10_000_000):
        chain.run(a, 1)
        gap = chain.x[1] - chain.x[0] - cfg.L_x
        if gap < 0:
            touched, steps = True, steps + 1
        elif touched and chain.u[1] - chain.u[0] > 0:
            break
    return float((chain.u[1] - chain.u[0]) / v), steps


def restitution_table(dts: list[float]) -> bool:
    print("realised restitution (two lab-ice floes, 0.05 m/s); steps in contact in brackets")
    ok = True
    for law in LAWS:
        for eps in (0.2, 0.4, 0.6, 0.8):
            vals = [restitution(dt, eps, *law) for dt in dts]
            ref = vals[0][0]
            worst = max(abs(e - ref) for e, _ in vals[1:])
            ok &= worst <= 0.01
            cells = "  ".join(f"{e:.4f} ({n:5d})" for e, n in vals)
            print(f"  {'+'.join(str(x) for x in law):28s} eps {eps}: {cells}"
                  f"   max |e - e(1e-4)| = {worst:.4f}")
    return ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--candidates", nargs="+", type=float, default=[1e-3])
    ap.add_argument("--random", type=int, default=40, help="random grid points")
    ap.add_argument("--grid-seed", type=int, default=2020)
    ap.add_argument("--seeds", nargs=2, type=int, default=(1, 2))
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--cache", default="/tmp/floewave-dt.json")
    ap.add_argument("--skip-restitution", action="store_true")
    args = ap.parse_args(argv)
    dts = [1e-4, *args.candidates]
    if not args.skip_restitution:
        rest_ok = restitution_table(dts)
        print(f"restitution within +-0.01 of dt 1e-4 for every law and eps: {rest_ok}\n")
    pts = points(args.random, args.grid_seed)
    cache_path = Path(args.cache)
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    runs = {}
    tasks = []
    for i, p in enumerate(pts):
        for dt in dts:
            for seed in (args.seeds if dt != 1e-4 else args.seeds[:1]):
                d = {**p, **MATCHED, "dt": dt, "seed": seed}
                runs[(i, dt, seed)] = key_of(d)
                tasks.append((d, key_of(d)))
    compute_missing(tasks, cache, cache_path, args.jobs, len(pts))
    s1, s2 = args.seeds
    names = ("a", *SCALARS)
    print(f"\nRMS z over {len(pts)} points (n: number of z values; band: the candidate's two"
          " seeds against each other)")
    print(f"{'dt':>8s} " + " ".join(f"{n:>17s}" for n in names))
    def run(i, dt, seed):
        return floored(cache[runs[(i, dt, seed)]], ModelConfig(**pts[i]).a0)

    for dt in args.candidates:
        row_dt, row_seed = [], []
        for name in names:
            z_dt = np.concatenate([z_scores(run(i, dt, s1), run(i, 1e-4, s1), name)
                                   for i in range(len(pts))])
            z_sd = np.concatenate([z_scores(run(i, dt, s1), run(i, dt, s2), name)
                                   for i in range(len(pts))])

            def rms(z):
                return math.sqrt(np.mean(z**2)) if z.size else math.nan
            row_dt.append(f"{rms(z_dt):5.2f} (n {z_dt.size:4d})")
            row_seed.append(f"{rms(z_sd):5.2f} (n {z_sd.size:4d})")
        print(f"{dt:8.0e} " + " ".join(f"{c:>17s}" for c in row_dt) + "   vs dt 1e-4")
        print(f"{'band':>8s} " + " ".join(f"{c:>17s}" for c in row_seed) + "   seed vs seed")
        mean_ratio = np.mean([cache[runs[(i, 1e-4, s1)]]["floe_steps"]
                              / cache[runs[(i, dt, s1)]]["floe_steps"] for i in range(len(pts))])
        print(f"floe-steps per point, dt 1e-4 / dt {dt:g}: {mean_ratio:.2f}")
        da = [np.max(np.abs(np.subtract(run(i, dt, s1)["a"], run(i, 1e-4, s1)["a"])))
              / ModelConfig(**pts[i]).a0 for i in range(len(pts))]
        ds = [np.max(np.abs(np.subtract(run(i, dt, s1)["a"], run(i, dt, s2)["a"])))
              / ModelConfig(**pts[i]).a0 for i in range(len(pts))]
        print(f"max_i |a_i - a_i'| / a0, median (max) over points: dt {dt:g} vs 1e-4"
              f" {np.median(da):.2e} ({np.max(da):.2e}); seed vs seed {np.median(ds):.2e}"
              f" ({np.max(ds):.2e})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
