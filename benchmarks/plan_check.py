"""Check `sweep plan`'s projection against really running a random sample of grid points.

    python benchmarks/plan_check.py [CONFIG] [--n 24] [--seed 1] [--set drag_integration=exact]

Calibrates exactly as `sweep plan` does, predicts each sampled point's core-seconds
(expected floe-steps / calibrated rate of its kernel shape), runs the points in-process one
after another and prints predicted versus measured per point and in total (CPU seconds, as
the calibration), the measured mean iterations, and the whole-grid projection scaled by
measured/predicted on the sample.
"""
from __future__ import annotations

import argparse
import random
import time

from floewave import run_point
from floewave.cli import config_from_sets
from sweep.config import load_campaign
from sweep.run.plan import calibrate, core_seconds, kernel_shape


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("config", nargs="?", default="configs/herman2019.toml")
    p.add_argument("--n", type=int, default=24)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override base fields for the whole check (plan and sample)")
    args = p.parse_args()
    campaign = load_campaign(args.config)
    over = {k: v for k, v in config_from_sets(args.set).to_dict().items()
            if any(s.split("=")[0] == k for s in args.set)}
    points = campaign.points()
    if over:
        for pt in points:
            object.__setattr__(pt, "config", pt.config.replace(**over))
            object.__setattr__(pt, "cost", float(pt.config.floe_steps_of(
                campaign.expected_iterations(pt.config))))
    rates, how = calibrate(points)
    grid_hours = core_seconds(points, rates) / 3600
    print(f"plan: {len(points)} points, {grid_hours:.2f} core-hours projected ({how})")
    sample = random.Random(args.seed).sample([q for q in points if not q.invalid], args.n)
    tot_pred = tot_meas = 0.0
    its = []
    print(f"{'L_x':>4}{'T':>5}{'a0':>7}{'C_sd':>6}{'eps':>5}{'d_f':>6}{'disp':>5}"
          f"{'it':>5}{'status':>17}{'pred[s]':>9}{'meas[s]':>9}")
    for q in sample:
        pred = q.cost / rates[kernel_shape(q.config)]
        t = time.process_time()        # core-seconds: CPU time (a shared machine's
        r = run_point(q.config)         # wall clock also counts other processes)
        meas = time.process_time() - t
        tot_pred += pred
        tot_meas += meas
        its.append(r.iterations)
        c = q.config
        print(f"{c.L_x:>4}{c.T:>5}{c.a0:>7}{c.C_sd:>6}{c.eps:>5}{c.d_f:>6}{c.dispersion:>5}"
              f"{r.iterations:>5}{r.status:>17}{pred:>9.2f}{meas:>9.2f}", flush=True)
    print(f"sample of {args.n}: predicted {tot_pred:.1f} s, measured {tot_meas:.1f} s "
          f"(ratio {tot_meas / tot_pred:.2f}); mean iterations {sum(its) / len(its):.1f}")
    print(f"grid projection corrected by the sample ratio: "
          f"{grid_hours * tot_meas / tot_pred:.2f} core-hours")


if __name__ == "__main__":
    main()
