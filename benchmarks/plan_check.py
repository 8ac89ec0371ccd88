"""Check `sweep plan`'s projection against really running a random sample of grid points.

    python benchmarks/plan_check.py [CONFIG] [--n 24] [--seed 1] [--set drag_integration=exact]
    python benchmarks/plan_check.py --n 32 --seed 7 --baseline drag_every=1

Calibrates exactly as `sweep plan` does, predicts each sampled point's core-seconds
(expected floe-steps / calibrated rate of its kernel shape), runs the points in-process one
after another and prints predicted versus measured per point and in total (CPU seconds, as
the calibration), the measured mean iterations, and the whole-grid projection scaled by
measured/predicted on the sample.

``--baseline NAME=VALUE``: also the same check with those fields changed (e.g.
``drag_every=1``, the drag of every step), measured in the same run: both calibrations one
after the other, then the sample's points alternately with and without the change, so that
a shared machine's slow phases hit both alike; prints both projections and their ratio.
"""
from __future__ import annotations

import argparse
import copy
import random
import time

from floewave import run_point
from floewave.cli import config_from_sets
from sweep.config import load_campaign
from sweep.run.plan import calibrate, core_seconds, kernel_shape


def _overridden(campaign, sets: list[str]) -> list:
    """The campaign's points with the fields of ``sets`` (NAME=VALUE) changed, their costs
    recomputed."""
    over = {k: v for k, v in config_from_sets(sets).to_dict().items()
            if any(s.split("=")[0] == k for s in sets)}
    points = campaign.points()
    if over:
        points = [copy.copy(pt) for pt in points]
        for pt in points:
            object.__setattr__(pt, "config", pt.config.replace(**over))
            object.__setattr__(pt, "cost", float(pt.config.floe_steps_of(
                campaign.expected_iterations(pt.config))))
    return points


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("config", nargs="?", default="configs/herman2019.toml")
    p.add_argument("--n", type=int, default=24)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override base fields for the whole check (plan and sample)")
    p.add_argument("--baseline", action="append", default=[], metavar="NAME=VALUE",
                   help="also measure the check with these fields changed, in the same run")
    args = p.parse_args()
    campaign = load_campaign(args.config)
    cases = {"this": _overridden(campaign, args.set)}
    if args.baseline:
        cases["baseline"] = _overridden(campaign, args.set + args.baseline)
    plans = {}
    for name, points in cases.items():
        rates, how = calibrate(points)
        plans[name] = (rates, core_seconds(points, rates) / 3600)
        print(f"plan ({name}): {len(points)} points, {plans[name][1]:.2f} core-hours"
              f" projected ({how})")
    valid = [i for i, q in enumerate(cases["this"]) if not q.invalid]
    sample = random.Random(args.seed).sample(valid, args.n)
    tot = {name: [0.0, 0.0] for name in cases}
    its = {name: [] for name in cases}
    steps = {name: [] for name in cases}
    print(f"{'case':>9}{'L_x':>5}{'T':>5}{'a0':>7}{'C_sd':>6}{'eps':>5}{'d_f':>6}{'disp':>5}"
          f"{'it':>5}{'status':>17}{'pred[s]':>9}{'meas[s]':>9}")
    for i in sample:
        for name, points in cases.items():
            q = points[i]
            pred = q.cost / plans[name][0][kernel_shape(q.config)]
            t = time.process_time()        # core-seconds: CPU time (a shared machine's
            r = run_point(q.config)         # wall clock also counts other processes)
            meas = time.process_time() - t
            tot[name][0] += pred
            tot[name][1] += meas
            its[name].append(r.iterations)
            steps[name].append(r.floe_steps)
            c = q.config
            print(f"{name:>9}{c.L_x:>5}{c.T:>5}{c.a0:>7}{c.C_sd:>6}{c.eps:>5}{c.d_f:>6}"
                  f"{c.dispersion:>5}{r.iterations:>5}{r.status:>17}{pred:>9.2f}"
                  f"{meas:>9.2f}", flush=True)
    hours = {}
    for name in cases:
        pred, meas = tot[name]
        hours[name] = plans[name][1] * meas / pred
        print(f"{name}: sample of {args.n}: predicted {pred:.1f} s, measured {meas:.1f} s "
              f"(ratio {meas / pred:.2f}); mean iterations "
              f"{sum(its[name]) / len(its[name]):.1f}; mean replica-floe-steps per point "
              f"{sum(steps[name]) / len(steps[name]):.2e}")
        print(f"{name}: grid projection corrected by the sample ratio: "
              f"{hours[name]:.2f} core-hours")
    if "baseline" in hours:
        print(f"baseline / this: {hours['baseline'] / hours['this']:.2f} (projected grid);"
              f" {tot['baseline'][1] / tot['this'][1]:.2f} (measured sample)")


if __name__ == "__main__":
    main()
