"""Do shipped results reproduce? Points of an exported table recomputed from their config.

    python -m tests.campaign_reproduce [TABLE_OR_DIR] [--n 4] [--seed 0] [--here] [--code DIR]

(from the repository's root; a check by hand, not in the suite).

Draws ``--n`` points with a result from the table (default ``results/herman2019``, read by
``sweep.load``), rebuilds each one's :class:`floewave.ModelConfig` from its ``config_json``,
runs :func:`floewave.run_point` in this process and compares every scalar the table holds
with the recomputed one. A row made on a CPU of this kind (the shard's ``machine`` in the
directory's ``provenance.json``) must agree bit for bit (NaN equal to NaN;
docs/reproducibility.md: one configuration, one result, whatever the rank count, resume
or JIT cache). A row made on another kind of CPU (another vector width rounds otherwise,
and a chaotic trajectory then moves) must agree within its error bars: every quantity
within 4 of sqrt(SE_table^2 + SE_here^2); its largest such z is printed (a status that
differs there, e.g. converged_noisy against not_converged at a point near the stopping
rule's threshold, is printed and does not fail the row by itself). ``--here``
draws only rows made on this kind of CPU. Exit status 0 when every row passes its test,
1 otherwise. Recompute with the code of the commit in the table's ``provenance.json``
(another model version gives other draws): run it from a checkout of that commit, or give
``--code DIR``, a clean checkout of it (``git worktree add DIR COMMIT``), whose ``floewave``
then computes the points in a child interpreter (this checkout only draws and compares).
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


def _row_machines(table: Path, hashes) -> list[str | None]:
    """The machine that made each row: its shard's in TABLE/provenance.json (a shard K/N
    holds the points whose hash, as an integer, is K mod N); None when not recorded."""
    prov = table / "provenance.json" if table.is_dir() else table.parent / "provenance.json"
    if not prov.exists():
        return [None] * len(hashes)
    shards = json.loads(prov.read_text()).get("shards", {})
    out = []
    for h in hashes:
        m = [s.get("machine") for key, s in shards.items()
             if int(h, 16) % int(key.split("/")[1]) == int(key.split("/")[0])]
        out.append(m[0] if m else None)
    return out


#: A child interpreter's loop (``--code``): one configuration (JSON) per line in, the
#: point's scalars and status (JSON: floats exact, NaN as NaN) per line out; its first line
#: says which floewave it imported.
_CHILD = """
import json, sys
import floewave
from floewave import ModelConfig, run_point
print(json.dumps(floewave.__file__), flush=True)
for line in sys.stdin:
    r = run_point(ModelConfig.from_dict(json.loads(line)))
    print(json.dumps({**{n: float(getattr(r, n)) for n in NAMES}, "status": r.status}),
          flush=True)
"""


def _compute(configs: list[str], code: Path | None) -> list[dict]:
    """Each configuration's scalars and status: in this process, or with ``code``'s
    floewave in a child interpreter (its working directory, first on its path)."""
    if code is None:
        from floewave import ModelConfig, run_point
        out = []
        for c in configs:
            r = run_point(ModelConfig.from_dict(json.loads(c)))
            out.append({**{n: getattr(r, n) for n in SCALARS}, "status": r.status})
        return out
    import os
    import subprocess
    code = code.resolve()
    env = dict(os.environ, PYTHONPATH=str(code))
    child = subprocess.run(
        [sys.executable, "-c", f"NAMES = {SCALARS!r}\n" + _CHILD], cwd=code, env=env,
        input="".join(json.dumps(json.loads(c)) + "\n" for c in configs),
        capture_output=True, text=True, check=False)
    if child.returncode != 0:
        raise SystemExit(f"--code {code}: the child failed:\n{child.stderr[-2000:]}")
    lines = child.stdout.splitlines()
    where = Path(json.loads(lines[0])).resolve()
    if code not in where.parents:
        raise SystemExit(f"--code {code}: the child imported floewave from {where}")
    print(f"computed by {where.parent}")
    return [json.loads(line) for line in lines[1:]]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("table", nargs="?", default=str(ROOT / "results" / "herman2019"))
    ap.add_argument("--n", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--here", action="store_true",
                    help="only rows made on this kind of CPU")
    ap.add_argument("--code", type=Path, help="a checkout whose floewave computes the points"
                    " (e.g. a git worktree at the commit the table's provenance records)")
    args = ap.parse_args()
    import sweep
    from herman2019.numbers import machine
    here = machine()
    df = sweep.load(args.table)
    ok_rows = df[df["status"].isin(["converged", "converged_noisy", "not_converged"])].copy()
    ok_rows["_machine"] = _row_machines(Path(args.table), list(ok_rows["hash"]))
    if args.here:
        ok_rows = ok_rows[ok_rows["_machine"] == here]
        if ok_rows.empty:
            print(f"no row of {args.table} was made on this kind of CPU ({here})")
            return 1
    pick = ok_rows.sample(n=min(args.n, len(ok_rows)), random_state=args.seed)
    print(f"this CPU: {here}")
    bad = 0
    results = _compute(list(pick["config_json"]), args.code)
    for (_, row), r in zip(pick.iterrows(), results, strict=True):
        diff, zmax = [], 0.0
        for name in SCALARS:
            a, b = float(row[name]), float(r[name])
            same = (a == b) or (math.isnan(a) and math.isnan(b))
            if not same:
                diff.append(f"{name} {a!r} != {b!r}")
                if not name.endswith("_stderr") and name + "_stderr" in SCALARS:
                    se = math.hypot(float(row[name + "_stderr"]), float(r[name + "_stderr"]))
                    z = abs(a - b) / se if se > 0 else math.inf
                    zmax = max(zmax, z if not math.isnan(z) else math.inf)
        same_status = str(row["status"]) == r["status"]
        own = row["_machine"] == here
        if own:
            ok = not diff and same_status
            verdict = ("bit for bit" if ok else "DIFFERS (made on this kind of CPU): "
                       + "; ".join(diff + ([] if same_status else [f"status {r['status']}"])))
        else:
            ok = zmax <= 4.0
            verdict = (f"made on {row['_machine'] or 'an unrecorded CPU'}: "
                       + ("bit for bit" if not diff and same_status else
                          f"largest z {zmax:.2f}" + ("" if same_status else
                                                     f", status {r['status']}")
                          + (" (within error bars)" if ok else " BEYOND ERROR BARS")))
        print(f"{row['hash'][:12]} {row['status']:>15} L_x={row['L_x']} T={row['T']} "
              f"a0={row['a0']} C_sd={row['C_sd']} eps={row['eps']} d_f={row['d_f']} "
              f"{row['dispersion']}: {verdict}", flush=True)
        bad += not ok
    print(f"{len(pick) - bad} of {len(pick)} points pass ({np.unique(pick['hash']).size}"
          f" distinct; {int((pick['_machine'] == here).sum())} made on this kind of CPU,"
          " held to bit for bit, the others to their error bars)")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
