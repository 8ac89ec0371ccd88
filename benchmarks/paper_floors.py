"""Measure the floors paper-check uses where a store gives no standard error.

The time-mean force profiles (F_w_mean, F_c_mean, F_d_mean) carry no per-replica spread,
so the SE of a median log10 force ratio over a zone is measured here from two independent
ensembles (two seeds) of the Fig. 2 campaign: sigma = RMS(difference) / sqrt(2) over the
points, for each ratio and zone. ``herman2019.points.FLOORS["log10_force"]`` states the
result, rounded up.

    python benchmarks/paper_floors.py paper --seeds 0 1

(the two seeds' rows of ``paper/fig2.h5``, the store of ``herman2019 check --run --seeds
0 1 --stores paper``, its seeds swept).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import sweep
from herman2019.points import force_decades

RATIOS = (("F_w/F_d compact", "compact", "F_w_mean", "F_d_mean"),
          ("F_w/F_d collisional", "collisional", "F_w_mean", "F_d_mean"),
          ("F_c/F_w compact", "compact", "F_c_mean", "F_w_mean"))


def measures(store: Path, seed: int) -> dict[tuple[str, str, float], float]:
    """{(ratio, dispersion, eps): median log10 ratio} of seed ``seed``'s rows of the Fig. 2
    store in ``store``."""
    path = store / "fig2.h5"
    df = sweep.load(path)
    df = df[df["seed"] == seed]
    out = {}
    for _, row in df.iterrows():
        for name, zone, num, den in RATIOS:
            e = force_decades(row, "", lambda n, h: sweep.load_profile(path, h), "fig2",
                              zone, num=num, den=den)
            out[name, str(row["dispersion"]), float(row["eps"])] = e.value
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("stores", type=Path, help="the paper-check store dir (its fig2.h5)")
    ap.add_argument("--seeds", type=int, nargs=2, default=(0, 1), metavar="S",
                    help="the two seeds compared (default 0 1)")
    args = ap.parse_args()
    a, b = (measures(args.stores, s) for s in args.seeds)
    print(f"{'ratio':24s} {'points':>6s} {'sigma [decade]':>15s} {'max |diff|':>11s}")
    for name, *_ in RATIOS:
        d = np.array([a[k] - b[k] for k in a if k[0] == name
                      and math.isfinite(a[k]) and math.isfinite(b.get(k, math.nan))])
        print(f"{name:24s} {len(d):6d} {math.sqrt(np.mean(d ** 2) / 2):15.4f}"
              f" {np.max(np.abs(d)):11.4f}")


if __name__ == "__main__":
    main()
