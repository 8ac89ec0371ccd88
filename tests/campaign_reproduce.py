"""Do shipped results reproduce? Points of an exported table recomputed from their config.

    python -m tests.campaign_reproduce [TABLE_OR_DIR] [--n 4] [--seed 0]

(from the repository's root; a check by hand, not in the suite: on another CPU the points
agree only within their error bars).

Draws ``--n`` points with a result from the table (default ``results/herman2019``, read by
``sweep.load``), rebuilds each one's :class:`floewave.ModelConfig` from its ``config_json``,
runs :func:`floewave.run_point` in this process and compares every scalar the table holds
with the recomputed one, bit for bit (NaN equal to NaN). On the machine that made the table
every point must agree (docs/reproducibility.md: one configuration, one result, whatever
the rank count, resume or JIT cache); on another CPU they agree within their error bars.
Exit status 0 when every compared value is equal, 1 otherwise. Run it from a checkout of
the model version that made the table (``results/herman2019`` is model version 8's: the
commit in its ``provenance.json``); another version gives other draws.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

SCALARS = ("W_c", "W_c_stderr", "a_end", "a_end_stderr", "alpha_all", "alpha_all_stderr",
           "alpha_edge", "alpha_edge_stderr", "alpha_inner", "alpha_inner_stderr",
           "alpha_exp", "alpha_exp_stderr", "iterations", "floe_steps", "W_c_n")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("table", nargs="?", default=str(ROOT / "results" / "herman2019"))
    ap.add_argument("--n", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    import sweep
    from floewave import ModelConfig, run_point
    df = sweep.load(args.table)
    ok_rows = df[df["status"].isin(["converged", "converged_noisy", "not_converged"])]
    pick = ok_rows.sample(n=min(args.n, len(ok_rows)), random_state=args.seed)
    bad = 0
    for _, row in pick.iterrows():
        cfg = ModelConfig.from_dict(json.loads(row["config_json"]))
        r = run_point(cfg)
        diff = []
        for name in SCALARS:
            a, b = float(row[name]), float(getattr(r, name))
            same = (a == b) or (math.isnan(a) and math.isnan(b))
            if not same:
                diff.append(f"{name} {a!r} != {b!r}")
        same_status = str(row["status"]) == r.status
        print(f"{row['hash'][:12]} {row['status']:>15} L_x={row['L_x']} T={row['T']} "
              f"a0={row['a0']} C_sd={row['C_sd']} eps={row['eps']} d_f={row['d_f']} "
              f"{row['dispersion']}: "
              + ("bit for bit" if not diff and same_status
                 else "DIFFERS: " + "; ".join(diff + ([] if same_status else
                                                      [f"status {r.status}"]))),
              flush=True)
        bad += bool(diff) or not same_status
    print(f"{len(pick) - bad} of {len(pick)} points reproduce bit for bit"
          f" ({np.unique(pick['hash']).size} distinct)")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
