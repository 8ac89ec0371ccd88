"""Iteration behaviour at the paper's Fig. 2 points, full numerics (n0 = 10, nT = 5).

    python benchmarks/fig2_iteration.py [--set relax=0.3 --set n_average=20 ...] [--eps 0.2 0.8]

Fig. 2: L_x = 0.5 m, T = 1.2 s, a0 = 0.0125 m, d_f = 0.005 m, C_sd = 0.05, eps 0.2-0.8,
'ml' and 'ep'. Prints per point: status, iterations, noise, max_i a_stderr/a0, a_end/a0, W_c,
wall time and floe-steps/s, and appends one JSON line per point to --out if given.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from floewave import ModelConfig, run_point
from floewave.cli import config_from_sets


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--eps", type=float, nargs="+", default=[0.2, 0.4, 0.6, 0.8])
    p.add_argument("--dispersion", nargs="+", default=["ml", "ep"])
    p.add_argument("--out", help="append JSON lines here")
    args = p.parse_args()
    base = config_from_sets(args.set)
    print(f"settings: {' '.join(args.set) or 'defaults'} (relax={base.relax}, "
          f"noise_window={base.noise_window}, n_average={base.n_average}, n0={base.n0}, "
          f"nT={base.nT})")
    print(f"{'disp':>4} {'eps':>4} {'status':>16} {'it':>4} {'noise':>7} {'maxSE/a0':>9}"
          f" {'a_end/a0':>9} {'W_c':>6} {'wall[s]':>8} {'Mfs/s':>6}")
    for disp in args.dispersion:
        for eps in args.eps:
            cfg = ModelConfig(**{**base.to_dict(), "L_x": 0.5, "T": 1.2, "a0": 0.0125,
                                 "d_f": 0.005, "C_sd": 0.05, "eps": eps, "dispersion": disp})
            t = time.perf_counter()
            r = run_point(cfg)
            wall = time.perf_counter() - t
            se = float(np.nanmax(r.a_stderr) / cfg.a0)
            print(f"{disp:>4} {eps:>4} {r.status:>16} {r.iterations:>4} {r.noise:>7.4f}"
                  f" {se:>9.4f} {r.a_end / cfg.a0:>9.4f} {r.W_c:>6.2f} {wall:>8.1f}"
                  f" {r.floe_steps / wall / 1e6:>6.1f}", flush=True)
            if args.out:
                with open(args.out, "a") as fh:
                    fh.write(json.dumps({"settings": args.set, "dispersion": disp, "eps": eps,
                                         "status": r.status, "iterations": r.iterations,
                                         "noise": r.noise, "max_se_rel": se,
                                         "a_end_rel": r.a_end / cfg.a0, "W_c": r.W_c,
                                         "wall": wall, "floe_steps": r.floe_steps,
                                         "a_rel": (r.a / cfg.a0).tolist(),
                                         "se_rel": (r.a_stderr / cfg.a0).tolist(),
                                         "history": r.residual_history.tolist()}) + "\n")


if __name__ == "__main__":
    main()
