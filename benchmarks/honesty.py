"""Are the ensemble's error bars honest? Two independent ensembles per point, z-scores.

For every point (the paper's 8 Fig. 2 points plus ``--random`` points of the paper's grid,
docs/model.md §7, drawn with a fixed seed) run two ensembles that differ only in ``seed`` (or
in ``placement``, with ``--placements uniform random``) and compute, per quantity,

    z = (x1 - x2) / sqrt(se1^2 + se2^2)

for a(x) per floe, W_c, alpha_inner, alpha_all (and alpha_edge, alpha_exp, a_end).
Honest standard errors give an RMS z near 1 (too small: error bars too wide; too large:
too narrow or the two ensembles differ systematically). Also prints the cost per point in
floe-steps (summed over replicas) against a single trajectory (R = 1, uniform: the paper's
model) at the same SE(a): single-trajectory floe-steps x (SE_1 / SE_R)^2 (the iteration
standard error falls as 1/sqrt(iterations averaged)).

    python benchmarks/honesty.py                       # R = 8, coupling mean, 8 + 8 points
    python benchmarks/honesty.py --coupling independent
    python benchmarks/honesty.py --placements uniform random --random 0   # §4.1's claim
    python benchmarks/honesty.py --set nT=3 --replicas 4 --jobs 2
    python benchmarks/honesty.py --reference --random 24     # against long reference runs
    python benchmarks/honesty.py --reference --capped 24 --references /tmp/refs.json

``--capped N``: instead of the Fig. 2 and random points, N points drawn (``--grid-seed``)
from those model version 8's grid (``results/herman2019-v8``) ended ``not_converged``
(all at that version's cap of 100 windows): the points a stopping rule for a
stationary noisy state acts on.

``--reference``: two runs of one protocol share its biases, so the between-seed z cannot see
them. Each point is also run as a long reference (:data:`REFERENCE`: the stationary protocol
with a fixed transient of 85 periods or :data:`REFERENCE_DRAG_TIMES` drag relaxation times,
whichever is longer, and 150 periods averaged per replica, no early stop),
with two seeds; the references are kept in ``benchmarks/data/references.json`` (computed
once, reused) and each of the two production runs is compared with the mean of the two
references, z = (x - x_ref) / sqrt(se^2 + se_ref^2). Target: RMS z in [0.8, 1.25] for a(x),
a_end, W_c and every alpha, no |z| > 4.

Stochastic: the figures change with the seeds drawn; they are statistics of chaotic
runs. Results are cached in ``--cache`` (JSON per run) so a rerun only adds missing runs.
"""
from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

import numpy as np

from floewave import ModelConfig
from floewave.honesty import (
    REFERENCE,
    REFERENCE_SEEDS,
    REFERENCE_VERSIONS,
    SCALARS,
    SE_FLOOR,
    ZONE_QUANTITIES,
    combine,
    floored,
    key_of,
    points,
    reference_config,
    run_one,
    z_scores,
)

REFERENCE_FILE = Path(__file__).parent / "data" / "references.json"


def capped(n: int, seed: int) -> list[dict]:
    """``n`` grid points drawn (``seed``) from model version 8's grid's ``not_converged``
    rows (``results/herman2019-v8``: the points docs/convergence.md's check was made on)."""
    import sweep
    df = sweep.load(REFERENCE_FILE.parents[2] / "results" / "herman2019-v8")
    rows = df[df["status"] == "not_converged"].sample(n, random_state=seed)
    axes = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
    return [{k: (str(r[k]) if k == "dispersion" else float(r[k])) for k in axes}
            for _, r in rows.iterrows()]


def reference_table(pts: list, ens: list, cache: dict, refs: dict, replicas: int) -> None:
    """z of every production run against the mean of its point's two references."""
    zs: dict[str, list[np.ndarray]] = {"a": [], **{s: [] for s in SCALARS}}
    above: dict[str, list[np.ndarray]] = {"a": [], "a_end": []}   # SE above the floor
    print(f"\nagainst the references ({len(REFERENCE_SEEDS)} seeds each, {REFERENCE}):")
    print(f"{'point':44s} {'W_c ref':>13s} {'z_Wc':>11s} {'a_end/a0 ref':>14s} "
          f"{'z_aend':>11s} {'rms z_a':>8s}")
    for p, (k1, k2), _ in ens:
        a0 = ModelConfig(**p).a0
        rr = [floored(refs[key_of(reference_config(p, replicas, s))], a0)
              for s in REFERENCE_SEEDS]
        ref = combine(*rr)
        row = []
        for k in (k1, k2):
            for name in zs:
                zs[name].append(z_scores(cache[k], ref, name))
            for name in above:      # the z of values whose own SE is above the floor
                fl = floored(cache[k], a0)
                se = np.atleast_1d(np.asarray(fl[name + "_stderr"], float))
                x = np.atleast_1d(np.asarray(fl[name], float))
                keep = np.isfinite(x) & (se > 1.01 * SE_FLOOR * a0)
                sub = {name: x[keep], name + "_stderr": se[keep]}
                refsub = {name: np.atleast_1d(np.asarray(ref[name], float))[keep],
                          name + "_stderr": np.atleast_1d(
                              np.asarray(ref[name + "_stderr"], float))[keep]}
                above[name].append(z_scores(sub, refsub, name))
            row.append((z_scores(cache[k], ref, "W_c"), z_scores(cache[k], ref, "a_end"),
                        z_scores(cache[k], ref, "a")))
        name = ",".join(f"{k}={v}" for k, v in p.items() if k != "dispersion") + \
            f",{p['dispersion']}"

        def f(z):
            return f"{z[0]:5.2f}" if z.size else "  nan"
        print(f"{name:44s} {ref['W_c']:6.2f}+-{ref['W_c_stderr']:4.2f} "
              f"{f(row[0][0])}/{f(row[1][0])} {ref['a_end'] / a0:7.4f}+-"
              f"{ref['a_end_stderr'] / a0:5.4f} {f(row[0][1])}/{f(row[1][1])} "
              f"{math.sqrt(np.mean(np.concatenate([row[0][2], row[1][2]]) ** 2)):8.2f}")
    print("\nRMS z against the references (target 0.8-1.25, no |z| > 4):")
    for name, parts in zs.items():
        z = np.concatenate(parts) if parts else np.zeros(0)
        rms = math.sqrt(np.mean(z**2)) if z.size else math.nan
        print(f"  {name:12s} RMS z = {rms:5.2f}  n = {z.size:4d}  |z|>4: "
              f"{int((abs(z) > 4).sum())}  max |z| = {np.max(np.abs(z)) if z.size else 0:.2f}")
    print(f"only values whose SE is above the floor ({SE_FLOOR:g} a0; at the floor a"
          " non-chaotic point's z is about 0):")
    for name, parts in above.items():
        z = np.concatenate(parts) if parts else np.zeros(0)
        total = sum(p.size for p in zs[name])
        rms = math.sqrt(np.mean(z**2)) if z.size else math.nan
        print(f"  {name:12s} RMS z = {rms:5.2f}  n = {z.size:4d} ({total - z.size} at the"
              " floor left out)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--replicas", type=int, default=8)
    ap.add_argument("--coupling", default="independent", choices=("mean", "independent"))
    ap.add_argument("--placements", nargs=2, default=("random", "random"))
    ap.add_argument("--seeds", nargs=2, type=int, default=(1, 2))
    ap.add_argument("--random", type=int, default=8, help="random grid points (>= 8)")
    ap.add_argument("--grid-seed", type=int, default=2019)
    ap.add_argument("--capped", type=int, default=0,
                    help="N of the shipped grid's not_converged points instead (docstring)")
    ap.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--no-single", action="store_true", help="skip the R = 1 baseline")
    ap.add_argument("--cache", default="/tmp/floewave-honesty.json")
    ap.add_argument("--reference", action="store_true",
                    help="also compare each run with long reference runs (module docstring)")
    ap.add_argument("--references", default=str(REFERENCE_FILE),
                    help="JSON file of the reference runs (computed where missing)")
    args = ap.parse_args(argv)
    extra = {}
    for item in args.set:
        k, v = item.split("=", 1)
        try:
            extra[k] = json.loads(v)            # numbers, true/false, "quoted" strings
        except json.JSONDecodeError:
            extra[k] = v                        # a bare string (protocol=noise_floor)
    pts = capped(args.capped, args.grid_seed) if args.capped else points(args.random,
                                                                         args.grid_seed)
    cache_path = Path(args.cache)
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    ens = []
    tasks = []
    for p in pts:
        pair = []
        for placement, seed in zip(args.placements, args.seeds, strict=True):
            d = {**p, **extra, "replicas": args.replicas, "seed": seed,
                 "placement": placement, "coupling": args.coupling}
            pair.append(key_of(d))
            tasks.append((d, key_of(d)))
        single = {**p, **extra, "replicas": 1, "placement": "uniform"}
        if not args.no_single:
            tasks.append((single, key_of(single)))
        ens.append((p, pair, key_of(single)))
    refs: dict = {}
    ref_path = Path(args.references)
    if args.reference:
        refs = json.loads(ref_path.read_text()) if ref_path.exists() else {}
        for p in pts:
            for seed in REFERENCE_SEEDS:
                d = reference_config(p, args.replicas, seed)
                old = refs.get(key_of(d))
                if old is None or old.get("model_version") not in REFERENCE_VERSIONS:
                    refs.pop(key_of(d), None)
                    tasks.append((d, key_of(d), True))
    todo = [t for t in tasks if t[1] not in cache and t[1] not in refs]
    todo = list({t[1]: t for t in todo}.values())
    print(f"{len(pts)} points, {len(tasks)} runs ({len(todo)} to compute), R = "
          f"{args.replicas}, coupling {args.coupling}, placements {args.placements}, "
          f"seeds {args.seeds}, extra {extra}", flush=True)
    t0 = time.perf_counter()
    with mp.get_context("fork").Pool(args.jobs) as pool:
        for i, (key, rec) in enumerate(pool.imap_unordered(run_one, todo), 1):
            if rec.get("reference"):
                refs[key] = rec
                ref_path.parent.mkdir(parents=True, exist_ok=True)
                ref_path.write_text(json.dumps(refs, indent=0, sort_keys=True))
            else:
                cache[key] = rec
                cache_path.write_text(json.dumps(cache))
            print(f"  {i}/{len(todo)} done ({time.perf_counter() - t0:.0f} s)", flush=True)

    zs: dict[str, list[np.ndarray]] = {"a": [], **{s: [] for s in SCALARS}}
    print(f"\n{'point':44s} {'W_c 1 +- se':>15s} {'W_c 2 +- se':>15s} {'z_Wc':>6s} "
          f"{'rms z_a':>7s} {'SE(a)/a0':>8s} {'iters':>7s} status")
    cost_R, cost_1, cost_eq, se_R, se_1 = [], [], [], [], []
    statuses = []
    for p, (k1, k2), ks in ens:
        r1, r2 = cache[k1], cache[k2]
        za = z_scores(r1, r2, "a")
        zs["a"].append(za)
        for s in SCALARS:
            zs[s].append(z_scores(r1, r2, s))
        zw = z_scores(r1, r2, "W_c")
        name = ",".join(f"{k}={v}" for k, v in p.items() if k != "dispersion") + \
            f",{p['dispersion']}"
        se_a = np.nanmax(r1["a_stderr"]) / ModelConfig(**p).a0
        print(f"{name:44s} {r1['W_c']:7.2f}+-{r1['W_c_stderr']:5.2f} "
              f"{r2['W_c']:7.2f}+-{r2['W_c_stderr']:5.2f} "
              f"{(zw[0] if zw.size else math.nan):6.2f} "
              f"{math.sqrt(np.mean(za**2)) if za.size else math.nan:7.2f} {se_a:8.4f} "
              f"{r1['iterations']:3d}/{r2['iterations']:<3d} {r1['status']}/{r2['status']}")
        statuses += [r1["status"], r2["status"]]
        if ks in cache and cache[ks]["status"] == r1["status"] == "converged_noisy":
            # both averaged at a noise floor: their standard errors are comparable
            rs = cache[ks]
            med_R = np.nanmedian(r1["a_stderr"])
            med_1 = np.nanmedian(rs["a_stderr"])
            cost_R.append(r1["floe_steps"])
            cost_1.append(rs["floe_steps"])
            se_R.append(med_R / ModelConfig(**p).a0)
            se_1.append(med_1 / ModelConfig(**p).a0)
            if med_R > 0 and np.isfinite(med_1):
                cost_eq.append((r1["floe_steps"], rs["floe_steps"] * (med_1 / med_R) ** 2))
    print("\nRMS z (target 0.6-1.5; n = number of z values):")
    for name, parts in zs.items():
        z = np.concatenate(parts) if parts else np.zeros(0)
        rms = math.sqrt(np.mean(z**2)) if z.size else math.nan
        print(f"  {name:12s} RMS z = {rms:5.2f}  n = {z.size:4d}  |z|>3: {int((abs(z) > 3).sum())}")
    if args.reference:
        reference_table(pts, ens, cache, refs, args.replicas)
    differ = sum(cache[k1].get("layout") != cache[k2].get("layout") for _, (k1, k2), _ in ens)
    print(f"\nlayout differs between the two seeds at {differ} of {len(ens)} points (their"
          f" {', '.join(ZONE_QUANTITIES)} are not compared)")
    nc = sum(s == "not_converged" for s in statuses)
    print(f"\nnot_converged: {nc} of {len(statuses)} ensemble runs")
    if cost_R:
        ratios = [e / c for e, c in cost_eq]
        print(f"cost on the {len(cost_R)} points where the single trajectory and the first "
              "ensemble both ended converged_noisy (medians over points): floe-steps "
              f"ensemble {np.median(cost_R):.3g}, single trajectory {np.median(cost_1):.3g}; "
              f"median SE(a)/a0 ensemble {np.median(se_R):.4f}, single {np.median(se_1):.4f};"
              f" single trajectory run to the ensemble's SE(a) (SE ~ 1/sqrt(iterations)) "
              f"{np.median([c for _, c in cost_eq]):.3g}: ensemble / that = "
              f"{np.median(ratios):.2f} (range {min(ratios):.2f}-{max(ratios):.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
