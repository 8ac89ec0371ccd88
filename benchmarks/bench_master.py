"""How fast the sweep master schedules and stores points, and its CPU share.

Runs a campaign of N points whose compute function does no work
(``sweep.testing:trivial_point``), so the rate is the master's: scheduling, the MPI
round trip, the journal append + fsync, the HDF5 row/profile write + flush + fsync
(one journal fsync and one HDF5 flush per group commit of all waiting results).
Issue 5's target: >= 1,000 points/s both ways, and < 5% of a core with 0.2 s points.
Then runs a campaign of 0.2 s points (``sleepy_point``) and reports the master's CPU
seconds per wall second while workers "compute" (it must stay well under 5%).

Scaling mode (issue [scale]): the paper's grid under oversubscribed ``mpiexec -n R`` for
each R of ``--scale``, every point a ``sweep.testing:replay_point`` that sleeps as long as a
real point of the shipped campaign (``benchmarks/data/point_costs.json``, from
``--costs-from``), times each factor of ``--cost-scale`` (0.25: points 4x cheaper). A
sleeping worker stands for a core, so 63 workers on 2 cores stand for 63 cores. Reported
per run: stored points/s over the scheduling loop, the master's CPU share, the master's
CPU per stored point, and from the store's start/end times per rank the hand-out latency
(a worker's wait between finishing a point and starting the next) and the workers' idle
share. ``benchmarks/master_model.py`` fits its queueing model to these rows.

Usage::

    python benchmarks/bench_master.py [--points 2000] [--ranks 3]
    python benchmarks/bench_master.py --scale 8 16 32 64 --cost-scale 1 0.25 0.0625
    python benchmarks/bench_master.py --costs-from results/herman2019   # refresh the costs

Prints one line per measurement; run from the repository root.
"""
from __future__ import annotations

import argparse
import json
import os
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


COSTS = Path(__file__).resolve().parent / "data" / "point_costs.json"
GRID = Path(__file__).resolve().parents[1] / "configs" / "herman2019.toml"
GRID_POINTS = 24192


def write_costs(source: str) -> None:
    """benchmarks/data/point_costs.json from a real campaign's model wall times."""
    import numpy as np

    import sweep
    df = sweep.load(source)
    wt = df["model_wall_time"].to_numpy(float)
    q = np.quantile(wt, np.linspace(0.0, 1.0, 201))
    COSTS.write_text(json.dumps({
        "source": f"{source}: {len(df)} points, model_wall_time [s]",
        "model_version": sorted(set(json.loads(p)["model_version"] for p in df["provenance"])),
        "mean": float(wt.mean()), "median": float(np.median(wt)),
        "wall_time_quantiles": [round(float(v), 6) for v in q]}, indent=0) + "\n")
    print(f"{COSTS}: {len(df)} points, mean {wt.mean():.3f} s, median {np.median(wt):.3f} s")


def latency(store: Path) -> dict[str, float]:
    """From the store's start and end times per rank: the gaps between one point's end
    and the next's start on a worker (hand-out latency), the span from the first start to
    the last end, and the workers' idle share while there was work to hand out (up to the
    moment the first worker ran out: the drain at the end, where workers must idle, is
    not the master's doing)."""
    import numpy as np

    import sweep
    df = sweep.load(store)
    t0 = df["start_time"].min()
    per = []
    for _, g in df.groupby("rank"):
        g = g.sort_values("start_time")
        per.append(((g["start_time"] - t0).dt.total_seconds().to_numpy(),
                    (g["end_time"] - t0).dt.total_seconds().to_numpy()))
    gap = np.concatenate([st[1:] - en[:-1] for st, en in per])
    span = max(float(en[-1]) for _, en in per)
    full = min(float(en[-1]) for _, en in per)  # the first worker to run out
    busy = sum(float(np.clip(np.minimum(en, full) - st, 0, None).sum()) for st, en in per)
    return {"latency_mean": float(gap.mean()) if gap.size else float("nan"),
            "latency_p95": float(np.quantile(gap, 0.95)) if gap.size else float("nan"),
            "idle": 1.0 - busy / (len(per) * full) if full > 0 else float("nan"),
            "workers": len(per), "span_s": span,
            "point_mean": float(df["wall_time"].mean()), "points": len(df)}


def scale_mode(args, mpiexec: str) -> None:
    mean = json.loads(COSTS.read_text())["mean"]
    rows = []
    print("| ranks | cost scale | writer | mean point [s] | points | stored points/s"
          " | master CPU | master CPU per point [ms] | writer CPU"
          " | hand-out latency mean / p95 [ms] | workers idle |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        grids = {}
        for writer in args.writer:  # the grid with its [run] writer set (not an identity)
            grids[writer] = Path(tmp) / f"grid-{writer}.toml"
            grids[writer].write_text(GRID.read_text().replace(
                "[run]\n", f'[run]\nwriter = "{writer}"\n', 1))
        for scale, ranks, writer in ((s, r, w) for s in args.cost_scale for r in args.scale
                                     for w in args.writer):
            workers = ranks - 1
            want = workers * args.seconds / (mean * scale)
            shards = max(1, min(GRID_POINTS, int(GRID_POINTS / max(want, 1))))
            store = Path(tmp) / f"scale-{ranks}-{scale}-{writer}.h5"
            env = {**os.environ, "FLOEWAVE_REPLAY_SCALE": repr(scale)}
            sweep_cmd = [sys.executable, "-m", "sweep", "run", str(grids[writer]),
                         "--store", str(store), "--shard", f"0/{shards}", "--no-bar",
                         "--compute", "sweep.testing:replay_point"]
            if args.nice_workers:  # MPMD: rank 0 as it is, the workers niced
                cmd = [mpiexec, "-n", "1", *sweep_cmd, ":", "-n", str(workers),
                       "nice", "-n", str(args.nice_workers), *sweep_cmd]
            else:
                cmd = [mpiexec, "-n", str(ranks), *sweep_cmd]
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                sys.exit(f"failed: {' '.join(cmd)}\n{proc.stderr[-2000:]}")
            m = re.search(r"(\d+) stored now .* in ([\d.]+) s; master CPU ([\d.]+)%"
                          r"(?: of a core, its store writer ([\d.]+)%)?", proc.stdout)
            assert m, proc.stdout
            n, elapsed, cpu = int(m.group(1)), float(m.group(2)), float(m.group(3))
            wcpu = float(m.group(4) or 0.0)
            lat = latency(store)
            # the loop's rate and the master's CPU per point over the store's span
            # (first start to last end: the scheduling loop less its first hand-out
            # and last commit); the summary's time also counts the start-up
            span = lat["span_s"]
            row = {"ranks": ranks, "scale": scale, "writer": writer, "points": n,
                   "elapsed_s": elapsed, "rate": n / span, "master_cpu_share": cpu / 100,
                   "writer_cpu_share": wcpu / 100,
                   "cpu_per_point_ms": 1e3 * cpu / 100 * span / n, **lat}
            rows.append(row)
            print(f"| {ranks} | {scale:g} | {writer} | {lat['point_mean']:.3f} | {n} |"
                  f" {row['rate']:.1f} | {cpu:.1f} % | {row['cpu_per_point_ms']:.2f} |"
                  f" {f'{wcpu:.1f} %' if wcpu else '-'} |"
                  f" {1e3 * lat['latency_mean']:.1f} / {1e3 * lat['latency_p95']:.1f} |"
                  f" {100 * lat['idle']:.1f} % |", flush=True)
            store.unlink(missing_ok=True)
            Path(str(store) + ".journal").unlink(missing_ok=True)
    if args.record:
        args.record.write_text(json.dumps({"rows": rows}, indent=1) + "\n")
        print(f"recorded in {args.record}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=int, nargs="+", metavar="RANKS",
                    help="scaling mode: oversubscribed mpiexec -n RANKS with replayed costs")
    ap.add_argument("--cost-scale", type=float, nargs="+", default=[1.0],
                    help="scaling mode: factors on the replayed point costs")
    ap.add_argument("--seconds", type=float, default=20.0,
                    help="scaling mode: about this long a run (sets its number of points)")
    ap.add_argument("--writer", nargs="+", default=["process"], choices=["process", "inline"],
                    help="scaling mode: who writes the store ([run] writer)")
    ap.add_argument("--record", type=Path, help="scaling mode: write the rows as JSON")
    ap.add_argument("--nice-workers", type=int, default=0, metavar="N",
                    help="scaling mode: run the worker ranks under nice -n N (rank 0 and its"
                    " writer process as they are), so that oversubscribed workers waiting"
                    " for a task take CPU from the master only when it has none to use, as"
                    " when each has a core of its own")
    ap.add_argument("--costs-from", metavar="TABLE_OR_STORE",
                    help="write benchmarks/data/point_costs.json from a real campaign")
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--ranks", type=int, default=3)
    ap.add_argument("--sleepy-points", type=int, default=40,
                    help="0: skip the CPU-share measurement")
    args = ap.parse_args()
    if args.costs_from:
        write_costs(args.costs_from)
        return
    mpiexec = find_mpiexec()
    if args.scale:
        if min(args.scale) < 2:
            sys.exit("--scale: at least 2 ranks (a master and a worker)")
        if not mpiexec:
            sys.exit("the scaling mode needs mpiexec (pip install mpi4py mpich)")
        scale_mode(args, mpiexec)
        return
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
