"""kill -9 torture of a real MPI campaign, at larger scale than the test (issue 4).

    python benchmarks/torture.py                      # configs/demo.toml, mpiexec -n 2, 25 kills
    python benchmarks/torture.py --kills 40 --ranks 3 --config configs/demo.toml --seed 3

Runs the campaign uninterrupted into a reference store, then kills the whole campaign
(launcher, master, workers: SIGKILL to its process group) at random moments, resuming it
each time with the same command, finishes it and compares every point with the reference
(hashes, every result column and profile array exactly, duplicates in table and journal,
``sweep validate``). The driver is :func:`torture` in tests/sweep/test_torture.py.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _load_torture():
    """tests/sweep/test_torture.py as a module, without putting the checkout on sys.path."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "torture_driver", ROOT / "tests" / "sweep" / "test_torture.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


_torture = _load_torture()
MPIEXEC, torture = _torture.MPIEXEC, _torture.torture


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", type=Path, default=ROOT / "configs" / "demo.toml")
    ap.add_argument("--kills", type=int, default=25)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--seed", type=int, default=25)
    ap.add_argument("--workdir", type=Path, help="keep stores and logs here (default: a"
                    " temporary directory, removed unless the torture fails)")
    args = ap.parse_args()
    if args.ranks > 1 and MPIEXEC is None:
        print("no mpiexec (pip install mpich)", file=sys.stderr)
        return 2
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="sweep-torture-"))
    t0 = time.monotonic()
    fig = torture(args.config.resolve(), workdir, kills=args.kills, n_ranks=args.ranks,
                  seed=args.seed, log=lambda s: print(s, flush=True))
    print(fig["summary"])
    print(f"elapsed {time.monotonic() - t0:.0f} s; work directory {workdir}")
    for p in fig["problems"]:
        print("PROBLEM:", p)
    if fig["problems"]:
        return 1
    if args.workdir is None:
        shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
