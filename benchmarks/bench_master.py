"""How fast the sweep master schedules and stores points, and its CPU share.

Runs a campaign of N points whose compute function does no work
(``sweep.testing:trivial_point``), so the rate is the master's: scheduling, the MPI
round trip, the journal append + fsync, the HDF5 row/profile write + flush + fsync
(one journal fsync and one HDF5 flush per group commit of all waiting results).
Issue 5's target: >= 1,000 points/s both ways, and < 5% of a core with 0.2 s points.
Then runs a campaign of 0.2 s points (``sleepy_point``) and reports the master's CPU
seconds per wall second while workers "compute" (it must stay well under 5%).

Usage::

    python benchmarks/bench_master.py [--points 2000] [--ranks 3]

Prints one line per measurement; run from the repository root.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sweep.testing import find_mpiexec


def campaign_text(n: int) -> str:
    eps = [round(0.001 + i * (0.998 / max(n - 1, 1)), 9) for i in range(n)]
    return ("[base]\nL_sheet = 6.0\n[sweep]\neps = [" + ", ".join(map(repr, eps)) + "]\n"
            "[run]\nprogress_interval = 1000.0\n")


def run(cmd: list[str]) -> tuple[float, str]:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{proc.stderr}")
    return time.perf_counter() - t0, proc.stdout


def parse(stdout: str) -> tuple[int, float, float]:
    # in-process runs report no master CPU share (the master computes the points)
    m = re.search(r"(\d+) stored now .* in ([\d.]+) s(?:; master CPU ([\d.]+)%)?", stdout)
    assert m, stdout
    return int(m.group(1)), float(m.group(2)), float(m.group(3) or "nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--ranks", type=int, default=3)
    ap.add_argument("--sleepy-points", type=int, default=40,
                    help="0: skip the CPU-share measurement")
    args = ap.parse_args()
    mpiexec = find_mpiexec()
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "bench.toml"
        cfg.write_text(campaign_text(args.points))
        base = [sys.executable, "-m", "sweep", "run", str(cfg), "--no-bar"]
        launches = [("in-process", [])]
        if mpiexec:
            launches.append((f"mpiexec -n {args.ranks}", [mpiexec, "-n", str(args.ranks)]))
        for label, prefix in launches:
            store = Path(tmp) / f"trivial-{len(prefix)}.h5"
            _, out = run(prefix + base + ["--store", str(store), "--compute",
                                          "sweep.testing:trivial_point"])
            n, elapsed, cpu = parse(out)
            print(f"{label}: {n} trivial points stored in {elapsed:.2f} s ="
                  f" {n / elapsed:.0f} points/s (incl. start-up)")
        if mpiexec and args.sleepy_points > 0:
            cfg.write_text(campaign_text(args.sleepy_points))
            store = Path(tmp) / "sleepy.h5"
            _, out = run([mpiexec, "-n", str(args.ranks)] + base + [
                "--store", str(store), "--compute", "sweep.testing:sleepy_point"])
            n, elapsed, cpu = parse(out)
            print(f"mpiexec -n {args.ranks}: {n} points of 0.2 s on {args.ranks - 1} workers"
                  f" in {elapsed:.2f} s; master CPU {cpu:.1f}% of a core"
                  " during the scheduling loop")


if __name__ == "__main__":
    main()
