"""Every number quoted in the docs (README.md, docs/*.md) about results, regenerated.

    python benchmarks/docs_numbers.py [--out DIR] [--skip-runs] [--record docs/numbers.txt]

Runs the shipped campaigns the docs quote (``configs/demo.toml`` under ``mpiexec -n 3``
when a launcher is available, else in-process; ``fig2``, ``fig5``, ``fig6a``, ``fig6b``,
``periods`` in-process, two at a time) into stores in ``--out`` (default: a new temporary
directory; ``--skip-runs`` reuses the stores there, and takes the timings from their run
records) and prints, labelled as in the docs:

- the wall time of each campaign (a timing: machine-dependent);
- the demo's ``collision_stats`` table and the periods' ``alpha_omega`` tables;
- W_c, layout and alpha_inner / alpha_c of the Fig. 2 points.

- the ``sweep paper-check`` table on those stores.

``--record FILE`` also writes the output to FILE under a header naming the model version
and the SHA-256 of the campaign files (:func:`stamp`). ``docs/numbers.txt`` is that record
for the numbers the docs quote: ``tests/test_docs.py`` fails when it was made for another
model version or other campaign files (rerun this script) or when a results table quoted
in the docs that tests/test_docs.py reads (its ``DOCS``) is not in it (the docs drifted from
their source). It writes only the record: the docs quote from it by hand.

Which numbers are *stochastic*: every result is an ensemble of chaotic floe trajectories
(the default R = 8 replicas). On one machine it is reproduced bit for bit
(docs/reproducibility.md); another seed or a rounding-level change (another CPU, compiler, numba
or glibc) gives other trajectories, and the numbers then move within their standard
errors (docs/convergence.md "Ensembles and error bars"). They are printed, and quoted, with them.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGNS = ("fig2", "fig5", "fig6a", "fig6b", "periods")


def stamp() -> str:
    """The header line of a record: model version and the campaign files' SHA-256."""
    import hashlib

    import floewave
    h = hashlib.sha256()
    for name in ("demo", *CAMPAIGNS):
        h.update(name.encode() + b"\0" + (ROOT / "configs" / f"{name}.toml").read_bytes())
    return f"# docs_numbers: model_version {floewave.MODEL_VERSION}, configs {h.hexdigest()}"


class _Tee:
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
    store = out / f"{name}.h5"
    t = time.perf_counter()
    proc = subprocess.run([*launcher, sys.executable, "-m", "sweep", "run",
                           str(ROOT / "configs" / f"{name}.toml"), "--store", str(store),
                           "--no-bar"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{name}: sweep run failed ({proc.returncode}):\n{proc.stderr}")
    return time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--skip-runs", action="store_true")
    ap.add_argument("--record", type=Path, default=None, metavar="FILE")
    args = ap.parse_args()
    if args.record is not None:
        record = open(args.record, "w", encoding="utf-8")  # noqa: SIM115 - closed at exit
        record.write(stamp() + f" ({time.strftime('%Y-%m-%d', time.gmtime())})\n")
        sys.stdout = _Tee(sys.__stdout__, record)
    out = args.out or Path(tempfile.mkdtemp(prefix="docs_numbers-"))
    out.mkdir(parents=True, exist_ok=True)
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
    print("\n[ensemble, stochastic] sweep paper-check --stores", out)
    proc = subprocess.run([sys.executable, "-m", "sweep", "paper-check", "--stores", str(out)],
                          capture_output=True, text=True)
    print(proc.stdout + proc.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
