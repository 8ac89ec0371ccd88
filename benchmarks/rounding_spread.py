"""How far does a rounding-level change move a point? The Fig. 2 points, each run with
d_f and with d_f changed so that the floe spacing L_x + d_f is one ulp larger (1 ulp of d_f
alone would vanish in L_x + d_f): a different chaotic trajectory of the same physics.

    python benchmarks/rounding_spread.py [--config configs/fig2.toml] [--jobs 2]

Prints per point W_c and layout of both runs, and the RMS over floes of
z = (a1 - a2) / sqrt(se1^2 + se2^2) (near 1 if the standard errors describe the scatter of
a(x) between trajectories; well above 1 if they understate it). Single trajectories: the
numbers are one sample of the chaotic spread (the *ensemble* issue replaces them with
replica statistics).
"""
from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _run(cfg_dict: dict):
    from floewave import ModelConfig, run_point
    r = run_point(ModelConfig(**cfg_dict))
    return r.W_c, r.compact_zone, r.a, r.a_stderr, r.status


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", type=Path, default=ROOT / "configs" / "fig2.toml")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    import sweep

    campaign = sweep.load_campaign(args.config)
    points = [p.config.to_dict() for p in campaign.points()]
    bumped = [dict(c, d_f=math.nextafter(c["L_x"] + c["d_f"], math.inf) - c["L_x"])
              for c in points]
    with ProcessPoolExecutor(args.jobs) as pool:
        res = list(pool.map(_run, points + bumped))
    one, two = res[:len(points)], res[len(points):]
    print(f"{args.config.name}: floe spacing L_x + d_f and 1 ulp more (single trajectories)")
    dW = []
    for c, r1, r2 in zip(points, one, two, strict=True):
        z = (r1[2] - r2[2]) / np.sqrt(r1[3] ** 2 + r2[3] ** 2)
        rms = float(np.sqrt(np.nanmean(z ** 2)))
        if np.isfinite(r1[0]) and np.isfinite(r2[0]):
            dW.append(abs(r1[0] - r2[0]))
        print(f"  {c['dispersion']} eps {c['eps']}: W_c {r1[0]:.2f} ({r1[1]}) / {r2[0]:.2f}"
              f" ({r2[1]}) m; a(x): RMS z {rms:.2f}; {r1[4]} / {r2[4]}")
    if dW:
        print(f"|dW_c| over {len(dW)} points with a W_c in both runs: median"
              f" {np.median(dW):.2f} m, max {max(dW):.2f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
