"""Is the time loop of this checkout bit for bit that of another commit?

    python benchmarks/kernel_bits.py [--against REV] [--periods 0.5]
    python benchmarks/kernel_bits.py --against 8cbf2b1 --every-step   # drag_every = 1 is v6
    python benchmarks/kernel_bits.py --against 9fc2add --midpoint     # v7's hold is v7's
    python benchmarks/kernel_bits.py --against c7d29bc --store [--speed]

A kernel change that only restructures loops (vectorisation, fission, branch-free selects)
must not change a single bit of any trajectory: otherwise it is a new model version (every
stored point would be computed again, and the docs' numbers too). This runs the same
trajectories with this checkout's floewave and with that of ``REV`` (exported by ``git
archive``; default ``HEAD``: the last commit, i.e. the uncommitted change is checked), each
in a fresh process
with its own empty numba cache, and compares every state array (positions, velocities,
accelerations, contact flags) and every window statistic byte for byte (so -0.0 is not
+0.0 and NaN must be the same NaN).

The trajectories: R = 8 replicas from random arrangements, every option the loop is built
for (contact law, damping, clipping, integrator, drag mode) and the three floe sizes of the
paper (kL from 1.4 to 8.4 rad: one or two roots per floe), spin-up and averaging steps,
each replica with its own amplitude profile, then a change of the amplitudes (the
re-evaluated first half-kick).

``--store`` also runs the demo campaign (each revision's configs/demo.toml, ``sweep run``
in-process) with this checkout and with ``REV`` (floewave, sweep and configs exported), each
in a fresh process with its own empty numba cache, and compares the two stores row for row
(rows matched by hash; every column but the run-specific ones of
:data:`sweep.revisions.RUN_SPECIFIC`) and profile for profile, byte for byte
(:func:`sweep.revisions.compare_stores`, h5py only: whatever the store code of either
revision). ``--speed`` then measures the kernel speed of both revisions in the same run
(``benchmarks/bench_vs.py --base REV``: floe-steps per second per core, alternating
windows in one process; a timing: run it on an idle machine).
Exit status 0 when every array (and with ``--store`` the stores) is equal, 1 otherwise.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from sweep.revisions import columns_added_since, compare_stores, export_revision

ROOT = Path(__file__).resolve().parent.parent

#: option sets (ModelConfig fields) checked; L_x gives 84, 28 and 14 floes
CASES = [
    dict(L_x=0.5),
    dict(L_x=1.5),
    dict(L_x=3.0),
    dict(L_x=0.5, drag_integration="exact"),
    dict(L_x=1.5, drag_integration="exact"),
    dict(L_x=3.0, drag_integration="exact"),
    dict(L_x=0.5, contact="linear", damping="exact", clip_attraction=True),
    dict(L_x=0.5, integrator="half_step", eps=0.8),
    dict(L_x=1.5, contact="linear", integrator="half_step", drag_integration="exact",
         clip_attraction=True),
    dict(L_x=0.5, d_f=0.05, C_sd=0.2, eps=0.2),
]

_RUN = r"""
import json, sys
import numpy as np
from floewave import ModelConfig, solve_dispersion
from floewave import _kernels as K
from floewave.ensemble import initial_positions
from floewave.model import FloeChain
cases, periods, out = json.loads(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
arrays = {}
import dataclasses
fields = {f.name for f in dataclasses.fields(ModelConfig)}
every_step = sys.argv[4] in ("1", "2")
for n, case in enumerate(cases):
    if sys.argv[4] == "1" and "drag_every" in fields:
        case = {**case, "drag_every": 1}
    if sys.argv[4] == "2":     # model version 7's held drag: the midpoint hold over 4 steps
        case = {**case, "drag_every": 4, **({"drag_hold": "midpoint"}
                                            if "drag_hold" in fields else {})}
    cfg = ModelConfig(T=1.2, **case)
    k, _ = solve_dispersion(cfg)
    if every_step:      # arrangements that do not depend on the configuration's fields
        x0 = np.array(initial_positions(cfg.replace(replicas=8, placement="uniform",
                                                    d_f=0.0)))
        rng0 = np.random.default_rng(100 + n)
        x0 = x0 + np.cumsum(rng0.uniform(0.0, 2 * 0.005, x0.shape), axis=1)
    else:
        x0 = np.array(initial_positions(cfg.replace(replicas=8)))
    ch = FloeChain(cfg, k, x0)
    rng = np.random.default_rng(n)
    a = cfg.a0 * (0.5 + rng.random(x0.shape))     # every replica its own profile
    steps = max(int(periods * cfg.n_t), 10)
    ch.run(a, steps)
    st = np.zeros((K.N_STATS,) + x0.shape)
    ch.run(a, steps, st)
    ch.run(a * 0.9, steps // 2)                   # new amplitudes: the init evaluation
    ch.run(a * 0.9, steps // 2, st)
    for name in ("x", "u", "acc", "in_contact"):
        arrays[f"{n}_{name}"] = getattr(ch, name)
    arrays[f"{n}_stats"] = st
import floewave
arrays["source"] = np.array(floewave.__file__)
np.savez(out, **arrays)
"""


def run(checkout: Path, periods: float, out: Path, every_step: bool | str = False) -> None:
    """The trajectories of the floewave in ``checkout``, into ``out`` (.npz)."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(checkout), NUMBA_CACHE_DIR=cache,
                   NUMBA_NUM_THREADS="1")
        subprocess.run([sys.executable, "-c", _RUN, json.dumps(CASES), str(periods),
                        str(out), every_step if isinstance(every_step, str) else
                        ("1" if every_step else "0")], env=env, cwd=cache,
                       check=True)


def demo_store(tree: Path, out: Path) -> None:
    """The demo campaign of the checkout ``tree`` (its configs/demo.toml), run in-process by
    its own sweep in a fresh process with an empty numba cache, into ``out``."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=cache)
        env.pop("SLURM_NTASKS", None)
        ran = subprocess.run([sys.executable, "-c", "import floewave, sweep; print(floewave"
                              ".__file__); print(sweep.__file__)"], env=env, cwd=cache,
                             capture_output=True, text=True, check=True).stdout.split("\n")
        for name, path in zip(("floewave", "sweep"), ran, strict=False):  # the code it should
            assert Path(path).resolve().parent == (tree / name).resolve(), path
        cmd = [sys.executable, "-m", "sweep", "run", str(tree / "configs" / "demo.toml"),
               "--store", str(out), "--no-bar"]
        done = subprocess.run(cmd, env=env, cwd=cache, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} (PYTHONPATH={tree}) exited"
                             f" {done.returncode}:\n{done.stderr[-3000:]}")


def stores_equal(rev: str, tmp: Path) -> bool:
    """The demo campaign's store of this checkout against that of ``rev``, compared."""
    tree = export_revision(rev, tmp / "tree", ("floewave", "sweep", "configs"))
    demo_store(tree, tmp / "ref.h5")
    demo_store(ROOT, tmp / "new.h5")
    problems, summary = compare_stores(tmp / "ref.h5", tmp / "new.h5",
                                       added=columns_added_since(tmp / "ref.h5"))
    for problem in problems[:20]:
        print("  " + problem)
    print(f"demo store against {rev}'s: {summary}")
    return not problems


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--against", default="HEAD", help="the commit to compare with")
    p.add_argument("--periods", type=float, default=0.5,
                   help="wave periods per phase (four phases per case)")
    p.add_argument("--midpoint", action="store_true",
                   help="the midpoint hold over drag_every = 4 steps (model version 7's"
                   " default; drag_hold = \"midpoint\" where the field exists) and"
                   " arrangements that do not depend on the configuration's fields")
    p.add_argument("--every-step", action="store_true",
                   help="drag_every = 1 where the field exists and arrangements that do not"
                        " depend on the configuration's fields: model version 7's every-step"
                        " drag against an older commit (e.g. --against 8cbf2b1)")
    p.add_argument("--store", action="store_true",
                   help="also the demo campaign's store of both revisions, compared")
    p.add_argument("--speed", action="store_true",
                   help="also the kernel speed of both revisions, measured in this run"
                        " (benchmarks/bench_vs.py --base REV)")
    p.add_argument("--speed-args", default="", metavar="ARGS",
                   help="with --speed: arguments for bench_vs.py, e.g. '--repeat 9'")
    args = p.parse_args()
    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        ref = export_revision(args.against, tmp / "ref", ("floewave",))
        mode = "2" if args.midpoint else args.every_step
        run(ref, args.periods, tmp / "ref.npz", mode)
        run(ROOT, args.periods, tmp / "new.npz", mode)
        a = dict(np.load(tmp / "ref.npz"))
        b = dict(np.load(tmp / "new.npz"))
        for arrays, where in ((a, ref), (b, ROOT)):       # each ran the floewave it should
            ran = Path(str(arrays.pop("source"))).resolve().parent
            assert ran == (where / "floewave").resolve(), ran
        bad = [key for key in a if a[key].dtype != b[key].dtype
               or a[key].shape != b[key].shape or a[key].tobytes() != b[key].tobytes()]
    for n, case in enumerate(CASES):
        keys = [key for key in a if key.startswith(f"{n}_")]
        diff = [key.split("_", 1)[1] for key in keys if key in bad]
        print(f"{json.dumps(case):<100} {'DIFFERENT: ' + ', '.join(diff) if diff else 'same bits'}")
    print(f"{len(a) - len(bad)} of {len(a)} arrays bit for bit equal to"
          f" {args.against}", flush=True)
    equal = not bad
    if args.store:
        with tempfile.TemporaryDirectory() as tmp:
            equal = stores_equal(args.against, Path(tmp)) and equal
    if args.speed:
        sys.stdout.flush()
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_vs.py"), "--base",
                        args.against, *args.speed_args.split()], check=True)
    return 0 if equal else 1


if __name__ == "__main__":
    sys.exit(main())
