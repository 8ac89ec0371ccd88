"""Compare two iteration algorithms on paper-grid points: cost and agreement.

    python benchmarks/iteration_compare.py --before "relax=0.3 ..." --after "relax=0.5 ..." \
        [--points fig2|sample] [--out results.jsonl]

For each point both settings run at full numerics; printed per point: iterations,
floe-steps, max_i a_stderr/a0 and status of each, the floe-step ratio after/before, and
the agreement z = max_i |a_after - a_before| / sqrt(se_after^2 + se_before^2) (values
around 2-3 are expected from chance over N_f floes; much larger means disagreement).
'sample' is 9 points: every floe size x dispersion relation, the other swept values drawn
from the paper grid with a fixed seed.
"""
from __future__ import annotations

import argparse
import json
import random
import time

import numpy as np

from floewave import ModelConfig, run_point
from floewave.cli import config_from_sets

GRID = dict(T=[1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0], a0=[0.0125, 0.015, 0.02, 0.025],
            C_sd=[0.005, 0.01, 0.05, 0.1, 0.15, 0.2], eps=[0.2, 0.4, 0.6, 0.8],
            d_f=[0.005, 0.010, 0.020, 0.050])


def points(which: str) -> list[dict]:
    if which == "fig2":
        return [dict(L_x=0.5, T=1.2, a0=0.0125, d_f=0.005, C_sd=0.05, eps=e, dispersion=d)
                for d in ("ml", "ep") for e in (0.2, 0.4, 0.6, 0.8)]
    rng = random.Random(2019)
    out = []
    for L_x in (0.5, 1.5, 3.0):
        for d in ("ml", "ep", "ow"):
            p = {k: rng.choice(v) for k, v in GRID.items()}
            out.append(dict(L_x=L_x, dispersion=d, **p))
    return out


def run(settings: str, point: dict):
    base = config_from_sets(settings.split()).to_dict()
    cfg = ModelConfig(**{**base, **point})
    t = time.perf_counter()
    r = run_point(cfg)
    return cfg, r, time.perf_counter() - t


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", default="")
    p.add_argument("--after", required=True)
    p.add_argument("--points", default="fig2", choices=["fig2", "sample"])
    p.add_argument("--out")
    args = p.parse_args()
    print(f"before: {args.before or 'defaults'}\nafter:  {args.after}")
    hdr = (f"{'point':<44}{'it_b':>5}{'it_a':>5}{'fs_b':>9}{'fs_a':>9}{'ratio':>7}"
           f"{'se_b':>7}{'se_a':>7}{'z':>6}  status b/a")
    print(hdr)
    tot_b = tot_a = 0
    for pt in points(args.points):
        cfg, rb, wb = run(args.before, pt)
        _, ra, wa = run(args.after, pt)
        se_b = float(np.max(rb.a_stderr) / cfg.a0)
        se_a = float(np.max(ra.a_stderr) / cfg.a0)
        comb = np.sqrt(rb.a_stderr**2 + ra.a_stderr**2)
        z = float(np.max(np.abs(ra.a - rb.a) / np.where(comb > 0, comb, np.inf)))
        tot_b += rb.floe_steps
        tot_a += ra.floe_steps
        name = (f"L{pt['L_x']} T{pt['T']} a{pt['a0']} C{pt['C_sd']} e{pt['eps']} "
                f"d{pt['d_f']} {pt['dispersion']}")
        print(f"{name:<44}{rb.iterations:>5}{ra.iterations:>5}{rb.floe_steps / 1e6:>8.0f}M"
              f"{ra.floe_steps / 1e6:>8.0f}M{ra.floe_steps / rb.floe_steps:>7.2f}{se_b:>7.4f}"
              f"{se_a:>7.4f}{z:>6.1f}  {rb.status}/{ra.status}", flush=True)
        if args.out:
            with open(args.out, "a") as fh:
                fh.write(json.dumps(dict(point=pt, before=args.before, after=args.after,
                                         it_b=rb.iterations, it_a=ra.iterations,
                                         fs_b=rb.floe_steps, fs_a=ra.floe_steps, se_b=se_b,
                                         se_a=se_a, z=z, status_b=rb.status,
                                         status_a=ra.status, wall_b=wb, wall_a=wa,
                                         a_b=rb.a.tolist(), a_a=ra.a.tolist())) + "\n")
    print(f"total floe-steps: before {tot_b:.3g}, after {tot_a:.3g}, ratio {tot_a / tot_b:.3f}")


if __name__ == "__main__":
    main()
