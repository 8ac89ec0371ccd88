"""Error bars calibrated on the grid itself: a stratified sample of the shipped grid's
points, each run on several independent seeds with this checkout's model, and, per
shipped quantity and stratum, the RMS z of the seeds' spread against their stated standard
errors, with its confidence interval.

    herman2019 calibrate --out results/calibration --jobs 2    # run (resumes), then the table
    herman2019 calibrate --out results/calibration --table     # the table of the stored runs

**The sample** (:func:`draw`): from a table of the grid (by default model version 8's,
``results/herman2019-v8``, which the shipped calibration was drawn from), ``n_zone``
points whose layout has a compact zone, ``n_none`` without one, and ``n_nc`` of those it
ended ``not_converged``; within each group one point per cell of (C_sd, L_x, d_f,
dispersion) in a random order of the cells, so that every level of each is drawn about
equally often (the cells outnumber the points), and T, a0, eps at random.

**The runs**: each point at the table's swept values with every other field at this
checkout's defaults (so at this model version, not necessarily the table's) and ``seed`` =
each of ``seeds``; one row per run in ``OUT/runs.csv.gz`` (values, standard errors,
status, windows, layout), written as runs finish, so a stopped run resumes.

**The statistic** (:func:`rms_z`): per point and quantity, with the seeds' values x_s and
stated standard errors e_s, chi^2 = sum_s (x_s - xbar)^2 / e_s^2 about the weighted mean
xbar (S - 1 degrees of freedom); per stratum RMS z = sqrt(sum chi^2 / sum dof), and its
95 % interval from the chi^2 distribution of that many degrees of freedom (as if the
standard errors were exact). Honest jackknife errors of 8 replicas give about 1.18 rather
than 1 (a z with an estimated error is Student-t, 7 degrees of freedom: sqrt(7/5)).
Above that, the stated error bars are too small by about that factor. W_c, W_c_gap,
alpha_inner and alpha_edge are compared only where every seed found the same layout, as
``benchmarks/honesty.py`` does. Seeds of one protocol share its biases: this calibrates
the error bars' size against the seeds' spread, not against the truth
(docs/convergence.md's reference runs do that on fewer points).
"""
from __future__ import annotations

import math
import multiprocessing as mp
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["QUANTITIES", "ZONE_QUANTITIES", "AXES", "SHIPPED", "draw", "run_sample", "rms_z",
           "calibration_table", "format_table", "command"]

#: The swept axes of the paper's grid (a point's identity in the shipped table).
AXES = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
#: The shipped quantities with a standard error, in the table's order.
QUANTITIES = ("a_end", "W_c", "W_c_gap", "alpha_inner", "alpha_edge", "alpha_all",
              "alpha_exp", "collision_rate", "contact_fraction_mean",
              "dissipation_per_collision")
#: Compared only where every seed found the same layout.
ZONE_QUANTITIES = ("W_c", "W_c_gap", "alpha_inner", "alpha_edge")
#: The shipped calibration (runs and factors).
SHIPPED = Path(__file__).resolve().parents[1] / "results" / "calibration"
#: The strata: all points, then each level of each of these columns.
STRATA = ("group", "C_sd", "L_x", "d_f", "dispersion")


def draw(table: pd.DataFrame, n_zone: int, n_none: int, n_nc: int,
         seed: int = 0) -> pd.DataFrame:
    """The stratified sample of ``table`` (module docstring): its AXES and a ``group``
    column (``zone``, ``none``, ``not_converged``: the table's layout and status)."""
    rng = np.random.default_rng(seed)
    done = table[table["status"].isin(["converged", "converged_noisy", "not_converged"])]
    nc = done["status"] == "not_converged"
    groups = {"zone": done[~nc & (done["compact_zone"] != "none")],
              "none": done[~nc & (done["compact_zone"] == "none")],
              "not_converged": done[nc]}
    out = []
    for name, n in (("zone", n_zone), ("none", n_none), ("not_converged", n_nc)):
        rows = groups[name]
        if n > len(rows):
            raise ValueError(f"{name}: {n} points asked, the table has {len(rows)}")
        cells = [idx for _, idx in
                 rows.groupby(["C_sd", "L_x", "d_f", "dispersion"]).groups.items()]
        order = rng.permutation(len(cells))
        taken: set = set()
        k = 0
        while len(taken) < n:
            idx = [i for i in cells[order[k % len(cells)]] if i not in taken]
            k += 1
            if idx:
                taken.add(idx[int(rng.integers(len(idx)))])
        pick = rows.loc[sorted(taken), list(AXES)].copy()
        pick["group"] = name
        out.append(pick)
    return pd.concat(out, ignore_index=True)


def _run(task: tuple[dict, int]) -> dict:
    """One run: the point at this checkout's defaults and ``seed``; its row."""
    from floewave import ModelConfig, run_point
    point, seed = task
    axes = {k: point[k] for k in AXES}
    r = run_point(ModelConfig(**axes, seed=seed))
    row = {**axes, "group": point["group"], "seed": seed, "status": r.status,
           "iterations": r.iterations, "layout": r.compact_zone, "a0": axes["a0"]}
    for q in QUANTITIES:
        row[q] = float(getattr(r, q))
        row[q + "_stderr"] = float(getattr(r, q + "_stderr"))
    return row


def _key(row: dict | pd.Series) -> tuple:
    return (*(float(row[k]) if k != "dispersion" else str(row[k]) for k in AXES),
            int(row["seed"]))


def run_sample(sample: pd.DataFrame, seeds: Sequence[int], out: Path, jobs: int = 1,
               progress=print) -> pd.DataFrame:
    """Run every (point, seed) not yet in ``out/runs.csv.gz`` (``jobs`` processes),
    rewriting the file as runs finish; the runs."""
    path = Path(out) / "runs.csv.gz"
    path.parent.mkdir(parents=True, exist_ok=True)
    runs = pd.read_csv(path) if path.exists() else pd.DataFrame()
    have = {_key(r) for _, r in runs.iterrows()} if len(runs) else set()
    tasks = [(p.to_dict(), s) for _, p in sample.iterrows() for s in seeds
             if _key({**p.to_dict(), "seed": s}) not in have]
    progress(f"calibration: {len(sample)} points x {len(seeds)} seeds, {len(tasks)} runs"
             f" to compute ({len(runs)} stored) into {path}")
    rows = runs.to_dict("records") if len(runs) else []
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    with mp.get_context("fork").Pool(max(1, jobs)) as pool:
        for i, row in enumerate(pool.imap_unordered(_run, tasks), 1):
            rows.append(row)
            if i % 20 == 0 or i == len(tasks):
                pd.DataFrame(rows).to_csv(path, index=False)
                progress(f"  {i}/{len(tasks)} runs")
    return pd.DataFrame(rows)


def rms_z(parts: Iterable[tuple[np.ndarray, np.ndarray]]) -> tuple[float, float, float, int]:
    """(RMS z, its 95 % interval low, high, degrees of freedom) of the points' seed values
    and standard errors ``parts`` (module docstring); NaN without any degree of freedom."""
    from scipy.stats import chi2 as chi2_dist
    total, dof = 0.0, 0
    for x, se in parts:
        ok = np.isfinite(x) & np.isfinite(se) & (se > 0)
        x, se = x[ok], se[ok]
        if len(x) < 2:
            continue
        w = 1.0 / se**2
        mean = float(np.sum(w * x) / np.sum(w))
        total += float(np.sum((x - mean) ** 2 * w))
        dof += len(x) - 1
    if dof == 0:
        return math.nan, math.nan, math.nan, 0
    r = math.sqrt(total / dof)
    lo = r * math.sqrt(dof / chi2_dist.ppf(0.975, dof))
    hi = r * math.sqrt(dof / chi2_dist.ppf(0.025, dof))
    return r, lo, hi, dof


def _parts(runs: pd.DataFrame, q: str) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for _, g in runs.groupby(list(AXES), sort=False):
        if q in ZONE_QUANTITIES and g["layout"].nunique() > 1:
            continue
        out.append((g[q].to_numpy(float), g[q + "_stderr"].to_numpy(float)))
    return out


def calibration_table(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per stratum (``all``, then ``column = level``), per quantity its RMS z,
    interval and degrees of freedom (columns ``q``, ``q_lo``, ``q_hi``, ``q_dof``)."""
    strata = [("all", runs)]
    for col in STRATA:
        for level, g in runs.groupby(col, sort=True):
            strata.append((f"{col} = {level}", g))
    rows = []
    for name, g in strata:
        row: dict = {"stratum": name, "points": g.groupby(list(AXES)).ngroups}
        for q in QUANTITIES:
            r, lo, hi, dof = rms_z(_parts(g, q))
            row.update({q: r, q + "_lo": lo, q + "_hi": hi, q + "_dof": dof})
        rows.append(row)
    return pd.DataFrame(rows)


def format_table(table: pd.DataFrame, quantities: Sequence[str] = QUANTITIES[:7]) -> str:
    """The calibration table as markdown: RMS z [95 % interval] (degrees of freedom)."""
    head = "| stratum | points | " + " | ".join(quantities) + " |"
    lines = [head, "|" + "---|" * (len(quantities) + 2)]
    for _, r in table.iterrows():
        cells = []
        for q in quantities:
            if r[q + "_dof"] == 0:
                cells.append("")
            else:
                cells.append(f"{r[q]:.2f} [{r[q + '_lo']:.2f}, {r[q + '_hi']:.2f}]"
                             f" ({int(r[q + '_dof'])})")
        lines.append(f"| {r['stratum']} | {int(r['points'])} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def command(args) -> int:
    """``herman2019 calibrate``: status 0; 2 for a bad argument, 3 for a missing table."""
    import sweep
    from sweep.errors import EXIT_OK, ConfigError
    out = Path(args.out)
    if args.table:
        path = out / "runs.csv.gz"
        if not path.exists():
            raise ConfigError(f"--table: no runs in {path}")
        runs = pd.read_csv(path)
    else:
        if min(args.n_zone, args.n_none, args.n_nc) < 0 or not args.seeds:
            raise ConfigError("--n-zone, --n-none, --n-nc must be >= 0 and --seeds given")
        if len(set(args.seeds)) < 2:
            raise ConfigError(f"--seeds {args.seeds}: at least two different seeds")
        table = sweep.load(args.grid)
        try:
            sample = draw(table, args.n_zone, args.n_none, args.n_nc, args.sample_seed)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        runs = run_sample(sample, args.seeds, out, args.jobs)
    print(format_table(calibration_table(runs)))
    return EXIT_OK
