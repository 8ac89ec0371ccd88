"""Kernel speed of this checkout against another git revision, measured in the same run.

    python benchmarks/bench_vs.py --base 57cc01b [--steps 12000] [--repeat 7]
        [--modes quadrature exact] [--L_x 0.5 1.5 3.0]

Exports the base revision's ``floewave`` package (``git archive``) into a temporary
directory as ``floewave_base`` and imports it beside this checkout's ``floewave`` in one
process. For each drag mode and floe size (T = 1.2 s, the paper's lab setup; chains spun
up first so contacts are active) it times windows of ``--steps`` steps of both kernels
*alternately*, ``--repeat`` times, spin-up steps and averaging (statistics-accumulating)
steps separately, and keeps the best window of each: alternating windows share whatever
else the machine is doing. Prints floe-steps per second per core and the ratio head / base.
"""
from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from sweep.revisions import export_revision  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def export(rev: str, dest: Path) -> None:
    """``floewave/`` of ``rev`` into ``dest/floewave_base`` (the package imports itself
    relatively, so the copy imports under the new name)."""
    export_revision(rev, dest, ("floewave",))
    (dest / "floewave").rename(dest / "floewave_base")


class Cell:
    """One spun-up chain of one package: ``window(steps, acc)`` returns its seconds."""

    def __init__(self, pkg, mode: str, L_x: float):
        model = importlib.import_module(pkg.__name__ + ".model")
        cfg = pkg.ModelConfig(L_x=L_x, T=1.2, drag_integration=mode)
        k, _ = pkg.solve_dispersion(cfg)
        self.n = cfg.n_floes
        self.chain = model.FloeChain(cfg, k)
        kernels = importlib.import_module(pkg.__name__ + "._kernels")
        shape = np.shape(self.chain.x)               # (R, N_f) since ensembles
        self.a = np.full(shape, cfg.a0)
        self.stats = np.zeros((kernels.N_STATS, *shape))
        self.chain.run(self.a, 2 * cfg.n_t)          # compile, spin up
        self.chain.run(self.a, 12, self.stats)       # a multiple of drag_every (4)

    def window(self, steps: int, acc: bool) -> float:
        t = time.perf_counter()
        self.chain.run(self.a, steps, self.stats if acc else None)
        return time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="git revision to compare against")
    ap.add_argument("--steps", type=int, default=12000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--modes", nargs="+", default=["quadrature", "exact"],
                    choices=["quadrature", "exact"], help="drag modes measured")
    ap.add_argument("--L_x", nargs="+", type=float, default=[0.5, 1.5, 3.0],
                    help="floe lengths measured [m]")
    args = ap.parse_args()
    head_rev = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"],
                              capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="bench_vs-") as tmp:
        export(args.base, Path(tmp))
        sys.path.insert(0, tmp)
        sys.path.insert(0, str(ROOT))
        base = importlib.import_module("floewave_base")
        head = importlib.import_module("floewave")
        print(f"M floe-steps/s per core (one process, alternating windows of {args.steps} "
              f"steps, best of {args.repeat}); base {args.base}, head {head_rev}")
        print(f"{'mode':<12}{'L_x':>5}{'N_f':>5}{'base spin':>11}{'head spin':>11}"
              f"{'ratio':>7}{'base avg':>10}{'head avg':>10}{'ratio':>7}", flush=True)
        for mode in args.modes:
            for L_x in args.L_x:
                cells = {"base": Cell(base, mode, L_x), "head": Cell(head, mode, L_x)}
                best = {}
                for acc in (False, True):
                    for _ in range(args.repeat):
                        for name, cell in cells.items():
                            t = cell.window(args.steps, acc)
                            best[name, acc] = min(best.get((name, acc), np.inf), t)
                fs = args.steps * cells["head"].n / 1e6
                r = {key: fs / t for key, t in best.items()}
                print(f"{mode:<12}{L_x:>5}{cells['head'].n:>5}"
                      f"{r['base', False]:>11.1f}{r['head', False]:>11.1f}"
                      f"{r['head', False] / r['base', False]:>7.2f}"
                      f"{r['base', True]:>10.1f}{r['head', True]:>10.1f}"
                      f"{r['head', True] / r['base', True]:>7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
