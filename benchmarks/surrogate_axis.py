"""The surrogate's error along one axis alone: the other five parameters at grid nodes.

    python benchmarks/surrogate_axis.py --axis L_x [--n 24] [--seed 0] [--jobs 2]
        [--out /tmp/surrogate_axis]

Draws ``--n`` grid nodes of the other five axes and the dispersion relation (``--seed``),
and runs the model (released defaults, seed 0) at each with the axis at values between its
levels (:data:`VALUES`; resumable, ``OUT/AXIS/runs.csv.gz``). Along the axis only, then,
the surrogate interpolates; its error there is printed per value of the axis: the median
and 90th percentile of |q_surrogate / q_model - 1| and the RMS z of the surrogate's
stated SE, for alpha_all, alpha_edge and a_end/a0; and the same for the linear reading
along L_x when the surrogate reads it as a quadratic. Stochastic (8-replica ensembles);
name the machine.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: Off-node values per axis (on the model's lattices: T a multiple of 4 ms, L_x of 1 cm).
VALUES = {"L_x": [0.6, 0.75, 1.0, 1.25, 2.0, 2.5, 2.75],
          "T": [1.152, 1.252, 1.3, 1.452, 1.7, 1.9],
          "a0": [0.0135, 0.0175, 0.0225],
          "C_sd": [0.0075, 0.025, 0.075, 0.125, 0.175],
          "eps": [0.3, 0.5, 0.7],
          "d_f": [0.007, 0.014, 0.035]}
QS = ("alpha_all", "alpha_edge", "a_end_rel")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axis", required=True, choices=sorted(VALUES))
    ap.add_argument("--n", type=int, default=24)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--file", default=None, help="the surrogate (default: the shipped one)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/surrogate_axis"))
    args = ap.parse_args()
    from herman2019.calibration import run_sample
    from herman2019.numbers import machine
    from herman2019.surrogate import AXES, Surrogate
    from herman2019.surrogate.validate import compare, model_table
    sur = Surrogate.load(args.file)
    rng = np.random.default_rng(args.seed)
    rows = []
    for _ in range(args.n):
        base = {a: float(rng.choice(sur.levels[a])) for a in AXES if a != args.axis}
        d = str(rng.choice(["ep", "ow", "ml"]))
        rows += [{**base, args.axis: v, "dispersion": d, "group": "axis"}
                 for v in VALUES[args.axis]]
    pts = pd.DataFrame(rows)[[*AXES, "dispersion", "group"]]
    runs = run_sample(pts, [0], args.out / args.axis, args.jobs, progress=lambda m: None)
    model = model_table(runs)
    print(f"[machine] {machine()}")
    print(f"along {args.axis}: {args.n} nodes of the other axes x {len(VALUES[args.axis])}"
          f" values; per value: median |rel. error| / 90th pct / RMS z")
    readings = [("surrogate", sur)]
    if any(args.axis in sur.quadratic_axes(q) for q in QS):
        quad = {q: [a for a in sur.quadratic_axes(q) if a != args.axis] for q in (*QS, "W_c")}
        line = Surrogate(sur.levels, sur.fields, sur.names, dict(sur.scale),
                         {**sur.meta, "quadratic": quad})
        readings.append((f"linear along {args.axis}", line))
    for name, s in readings:
        cmp = compare(s, model)
        print(f"-- {name}")
        print(f"{args.axis:>8s} " + " ".join(f"{q:>24s}" for q in QS))
        for v in VALUES[args.axis]:
            m = np.isclose(cmp[args.axis], v)
            cells = []
            for q in QS:
                rel = np.abs(cmp.loc[m, q + "_sur"] / cmp.loc[m, q] - 1)
                z = cmp.loc[m, q + "_z"]
                cells.append(f"{100 * rel.median():6.1f}% {100 * rel.quantile(0.9):6.1f}%"
                             f" {np.sqrt(np.nanmean(z**2)):6.2f}")
            print(f"{v:8g} " + " ".join(f"{c:>24s}" for c in cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
