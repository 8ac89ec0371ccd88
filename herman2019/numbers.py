"""Every number quoted in the docs (README.md, docs/*.md) about results, regenerated.

    herman2019 numbers [--out DIR] [--skip-runs] [--record docs/numbers.txt] [--timings]

Runs the shipped campaigns the docs quote (``configs/demo.toml`` under ``mpiexec -n 3``
when a launcher is available, else in-process; the paper campaigns ``fig2``, ``fig5``,
``fig6a``, ``fig6b``, ``periods``, ``periods_fine``, ``dfscan``, ``uniform``, ``spring_*``
in-process, two at
a time) into stores in ``--out`` (default: a new temporary
directory; ``--skip-runs`` reuses the stores there, and takes the timings from their run
records) and prints, labelled as in the docs:

- the wall time of each campaign (a timing: machine-dependent);
- the demo's ``collision_stats`` table and the periods' ``alpha_omega`` tables;
- W_c, layout and alpha_inner / alpha_c of the Fig. 2 points;
- the d_f scan's table (:func:`herman2019.dfscan.d_f_scan`, docs/dfscan.md);
- the ``herman2019 check`` table on those stores;
- with ``--timings`` (what ``docs/numbers.txt`` is made with), the table across seeds and the
  other timings
  docs/performance.md quotes, so that one record holds them all with the machine named: the
  CPU (``/proc/cpuinfo``'s model name and vector width), the kernels' compile with an empty
  numba cache (``floewave run``'s ``kernels ready in`` line), the cost projection
  (``benchmarks/plan_check.py --n 32 --seed 7`` against model version 7's numerics in the
  same run) and ``herman2019 check --run --seeds 0 1`` (about 6 minutes more);
- with ``--timings --settle``, the settled table (``herman2019 check --run --settle
  --first-seed 64 --max-seeds 256 --jobs 2`` into ``DIR/paper-settle-64``, about 25 minutes
  more on 2 cores); ``--settle-only --out DIR`` prints that section alone, for a record
  whose other sections stand.

``--record FILE`` also writes the output to FILE under a header naming the model version
and the SHA-256 of the campaign files (:func:`stamp`). ``docs/numbers.txt`` is that record
for the numbers the docs quote: ``tests/test_docs.py`` fails when it was made for another
model version or other campaign files (rerun this command) or when a results table quoted
in the docs that tests/test_docs.py reads (its ``DOCS``) is not in it (the docs drifted from
their source). It writes only the record: the docs quote from it by hand.

Which numbers are *stochastic*: every result is an ensemble of chaotic floe trajectories
(the default R = 8 replicas). On one machine it is reproduced bit for bit
(docs/reproducibility.md); another seed or a rounding-level change (another CPU, compiler, numba
or glibc) gives other trajectories, and the numbers then move within their standard
errors (docs/convergence.md "Ensembles and error bars"). They are printed, and quoted, with them.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from herman2019.claims import PAPER_CAMPAIGNS
from sweep.errors import ConfigError

__all__ = ["CAMPAIGNS", "stamp", "machine", "command"]

#: The checkout whose configs/ the campaigns are (and whose benchmarks/ times the cost).
ROOT = Path(__file__).resolve().parent.parent
#: The paper campaigns run and quoted, in the record's order.
CAMPAIGNS = PAPER_CAMPAIGNS


def stamp() -> str:
    """The header line of a record: model version and the campaign files' SHA-256."""
    import hashlib

    import floewave
    h = hashlib.sha256()
    for name in ("demo", *CAMPAIGNS):
        h.update(name.encode() + b"\0" + (ROOT / "configs" / f"{name}.toml").read_bytes())
    return f"# docs_numbers: model_version {floewave.MODEL_VERSION}, configs {h.hexdigest()}"


class _Tee:
    """A stream writing to each of ``streams``."""

    def __init__(self, *streams):
        self.streams = streams

    def write(self, text: str) -> int:
        for s in self.streams:
            s.write(text)
        return len(text)

    def flush(self) -> None:
        for s in self.streams:
            s.flush()


def run(name: str, out: Path, launcher: list[str]) -> float:
    """``sweep run configs/<name>.toml --store <out>/<name>.h5`` (under ``launcher``), timed."""
    store = out / f"{name}.h5"
    t = time.perf_counter()
    proc = subprocess.run([*launcher, sys.executable, "-m", "sweep", "run",
                           str(ROOT / "configs" / f"{name}.toml"), "--store", str(store),
                           "--no-bar"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{name}: sweep run failed ({proc.returncode}):\n{proc.stderr}")
    return time.perf_counter() - t


def machine() -> str:
    """The CPU this record was made on: model name, vector width, cores."""
    import os
    info = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    name = next((line.split(":", 1)[1].strip() for line in info.splitlines()
                 if line.startswith("model name")), "unknown CPU")
    flags = next((line.split(":", 1)[1].split() for line in info.splitlines()
                  if line.startswith("flags")), [])
    width = ("AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags
             else "no AVX2")
    return f"{name}, {width}, {os.cpu_count()} cores"


#: plan_check's in-run baseline: model version 7's numerics (the midpoint hold over 4 steps)
V7 = ["--baseline", "drag_hold=midpoint", "--baseline", "drag_every=4", "--baseline",
      "dt=0.001"]


def timings(out: Path) -> None:
    """The compile, the cost projection and ``check --run --seeds``, timed (--timings)."""
    import os
    import re
    with tempfile.TemporaryDirectory() as cache:
        proc = subprocess.run([sys.executable, "-m", "floewave", "run", "--set",
                               "max_iterations=1", "--set", "n0=1", "--set", "nT=1"],
                              capture_output=True, text=True,
                              env=dict(os.environ, NUMBA_CACHE_DIR=cache))
    m = re.search(r"kernels ready in ([0-9.]+) s", proc.stdout + proc.stderr)
    print(f"[timing] kernels' compile with an empty numba cache (floewave run):"
          f" {m.group(1) if m else '?'} s")
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "plan_check.py"),
                           "--n", "32", "--seed", "7", *V7], capture_output=True, text=True,
                          cwd=ROOT)
    print("[timing] python benchmarks/plan_check.py --n 32 --seed 7 " + " ".join(V7)
          + " (CPU time; baseline: model version 7's numerics)")
    for line in (proc.stdout + proc.stderr).splitlines():
        if not re.match(r"^\s*(this|baseline)\s+[0-9]", line) and not line.startswith(
                "     case"):
            print("  " + line)
    seeds = out / "paper-seeds"
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "herman2019", "check", "--stores",
                           str(seeds), "--run", "--seeds", "0", "1"], capture_output=True,
                          text=True)
    t = time.perf_counter() - t
    tail = [line for line in proc.stdout.splitlines() if line.startswith("across seeds")]
    print(f"[timing] herman2019 check --stores DIR --run --seeds 0 1: {t:.0f} s;"
          f" {tail[0] if tail else proc.stderr.strip()[-200:]}")
    print("\n[ensembles, stochastic] herman2019 check --stores DIR --seeds 0 1")
    print(proc.stdout)


#: The settled table's design (docs/paper-check.md "Settled verdicts"): fresh seeds from 64
#: (seeds 0-63 were the pilot that chose the budget), a budget of 256 seeds, 2 MPI workers.
SETTLE_FIRST_SEED, SETTLE_MAX_SEEDS, SETTLE_JOBS = 64, 256, 2


def settled(out: Path) -> None:
    """``herman2019 check --run --settle --first-seed 64 --max-seeds 256 --jobs 2`` into
    ``<out>/paper-settle-64`` (resumed if there: stored points are not recomputed; about
    25 minutes on 2 cores from nothing: 2,007 core-s of points, then the reading), timed."""
    seeds = out / f"paper-settle-{SETTLE_FIRST_SEED}"
    flags = ["--first-seed", str(SETTLE_FIRST_SEED), "--max-seeds", str(SETTLE_MAX_SEEDS),
             "--jobs", str(SETTLE_JOBS)]
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "herman2019", "check", "--stores",
                           str(seeds), "--run", "--settle", *flags], capture_output=True,
                          text=True)
    t = time.perf_counter() - t
    print(f"\n[ensembles, stochastic] herman2019 check --stores DIR --run --settle"
          f" {' '.join(flags)} ({t:.0f} s, on [machine] above)")
    print(proc.stdout if proc.returncode == 0 else proc.stderr[-2000:])


def command(args: Any) -> int:
    """``herman2019 numbers``: the record (module docstring); status 0, 2 for a bad
    argument."""
    if args.settle_only:
        if args.out is None:
            raise ConfigError("--settle-only needs --out (the directory of paper-settle-64/)")
        print(f"[machine] {machine()}")
        settled(args.out)
        return 0
    if args.record is None:
        return _numbers(args)
    saved = sys.stdout
    with open(args.record, "w", encoding="utf-8") as record:
        record.write(stamp() + f" ({time.strftime('%Y-%m-%d', time.gmtime())})\n")
        sys.stdout = _Tee(saved, record)
        try:
            return _numbers(args)
        finally:
            sys.stdout = saved


def _numbers(args: Any) -> int:
    """The runs (or the stores' run records) and every table, printed."""
    out = args.out or Path(tempfile.mkdtemp(prefix="docs_numbers-"))
    out.mkdir(parents=True, exist_ok=True)
    print(f"[machine] {machine()}")
    import pandas as pd

    import sweep

    pd.set_option("display.width", 200)
    pd.set_option("display.max_columns", 30)
    if not args.skip_runs:
        mpiexec = shutil.which("mpiexec")
        launcher = [mpiexec, "-n", "3"] if mpiexec else []
        t = run("demo", out, launcher)
        print(f"[timing] demo campaign ({'mpiexec -n 3' if mpiexec else 'in-process'}),"
              f" cache warm: {t:.1f} s")
        with ThreadPoolExecutor(2) as pool:
            times = dict(zip(CAMPAIGNS, pool.map(lambda n: run(n, out, []), CAMPAIGNS),
                             strict=True))
        for name, t in times.items():
            n = len(sweep.load(out / f"{name}.h5"))
            print(f"[timing] {name}: {n} points in-process, {t:.0f} s (two campaigns at a"
                  " time on 2 cores)")
    else:       # the stores' own run records: when each campaign started and ended
        from datetime import datetime

        from sweep.analysis.load import store_runs

        for name in ("demo", *CAMPAIGNS):
            run_ = store_runs(out / f"{name}.h5")[-1]
            secs = (datetime.fromisoformat(run_["ended"])
                    - datetime.fromisoformat(run_["started"])).total_seconds()
            n = len(sweep.load(out / f"{name}.h5"))
            print(f"[timing] {name}: {n} points on {int(run_['mpi_size'])} rank(s),"
                  f" {secs:.0f} s (the store's run record, commit {run_['git_commit'][:7]};"
                  " machine shared with other jobs)")
    print(f"stores in {out}\n")

    df = sweep.load(out / "demo.h5")
    stats = sweep.collision_stats(df, by=["L_x", "eps"])
    print("[ensemble of 4, stochastic] demo: sweep.collision_stats(df, by=['L_x', 'eps'])")
    print(stats[["L_x", "eps", "n_points", "n_W_c", "n_no_compact", "W_c_mean",
                 "W_c_mean_stderr", "W_c_rel_mean", "inner_over_c_mean",
                 "edge_over_inner_mean", "frac_prefers_n2"]].round(3).to_string())

    p = sweep.load(out / "periods.h5")
    print("\n[ensemble, stochastic] periods: sweep.alpha_omega(p) (alpha_inner, per curve)")
    cols = ["dispersion", "m", "m_stderr", "weighted", "chi2_dof", "n_periods",
            "n_dropped_no_zone", "n_dropped_nan", "m_c"]
    print(sweep.alpha_omega(p)[cols].round(3).to_string())
    print("\n[ensemble, stochastic] periods: sweep.alpha_omega(p, 'alpha_all', by='dispersion')")
    print(sweep.alpha_omega(p, "alpha_all", by="dispersion")[cols].round(3).to_string())
    lay = sweep.derived(p).pivot_table(index="T", columns="dispersion", values="compact_zone",
                                       aggfunc="first")
    print("\n[ensemble, stochastic] periods: compact-zone layout per T and dispersion")
    print(lay.to_string())

    f2 = sweep.derived(sweep.load(out / "fig2.h5")).sort_values(["dispersion", "eps"])
    f2["a_end/a0"] = f2["a_end"] / f2["a0"]
    f2["SE(a_end)/a0"] = f2["a_end_stderr"] / f2["a0"]
    f2["Mfloe_steps"] = f2["floe_steps"] / 1e6
    print("\n[ensemble, stochastic] Fig. 2 points: W_c +- SE [m], layout, alpha_inner / "
          "alpha_c +- SE, a_end / a0 +- SE, cost")
    print(f2[["dispersion", "eps", "W_c", "W_c_stderr", "W_c_n", "compact_zone",
              "inner_over_c", "inner_over_c_stderr", "a_end/a0", "SE(a_end)/a0", "status",
              "iterations", "Mfloe_steps"]].round(3).to_string(index=False))
    from herman2019.dfscan import d_f_scan
    from sweep.analysis.load import load_profile

    scan = d_f_scan(sweep.load(out / "dfscan.h5"),
                    lambda name, h: load_profile(out / f"{name}.h5", h))
    print("\n[ensemble, stochastic] d_f scan (configs/dfscan.toml):"
          " herman2019.dfscan.d_f_scan")
    print(scan.drop(columns=["status", "replicas"]).to_string(index=False,
                                                              float_format="%.4g"))
    print("\n[ensemble, stochastic] herman2019 check --stores", out)
    proc = subprocess.run([sys.executable, "-m", "herman2019", "check", "--stores", str(out)],
                          capture_output=True, text=True)
    print(proc.stdout + proc.stderr)
    if args.timings:
        timings(out)
        if args.settle:
            settled(out)
    return 0
