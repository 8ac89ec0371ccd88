"""Error bars calibrated on the grid itself: a stratified sample of the shipped grid's
points, each run on several independent seeds with this checkout's model, and, per
shipped quantity and stratum, the RMS z of the seeds' spread against their stated standard
errors, with its confidence interval.

    herman2019 calibrate --out results/calibration --jobs 2    # run (resumes), then the table
    herman2019 calibrate --out results/calibration --table     # the table of the stored runs

**The sample** (:func:`draw`): from the shipped table (``results/herman2019``), ``n_zone``
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

__all__ = ["QUANTITIES", "ZONE_QUANTITIES", "AXES", "FEATURES", "draw", "run_sample",
           "rms_z",
           "calibration_table", "format_table", "point_chi", "fit_factors", "factors_of",
           "with_calibrated_stderr", "calibrated", "calibrated_factors", "CALIBRATED_VERSION",
           "cross_validated", "format_check",
           "format_factors", "command"]

#: The swept axes of the paper's grid (a point's identity in the shipped table).
AXES = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
#: The shipped quantities with a standard error, in the table's order.
QUANTITIES = ("a_end", "W_c", "W_c_gap", "alpha_inner", "alpha_edge", "alpha_all",
              "alpha_exp", "collision_rate", "contact_fraction_mean",
              "dissipation_per_collision")
#: Compared only where every seed found the same layout.
ZONE_QUANTITIES = ("W_c", "W_c_gap", "alpha_inner", "alpha_edge")
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


# --- the calibrated standard errors -------------------------------------------------------
#: What a point's calibration factor depends on: four swept parameters (levels) and whether
#: the point ended ``not_converged`` (in the calibration: the share of its seeds that did).
FEATURES = ("L_x", "C_sd", "d_f", "dispersion", "not_converged")
#: The fitted factors' file in the calibration's directory (``herman2019 calibrate --factors``).
FACTORS = "factors.csv"
#: The shipped calibration (runs and factors).
SHIPPED = Path(__file__).resolve().parents[1] / "results" / "calibration"
#: The model version the shipped calibration's runs were made at: its factors apply to a
#: table of this version only.
CALIBRATED_VERSION = "9"
#: Honest jackknife errors of 8 replicas give RMS z about this (Student-t, 7 dof).
HONEST = math.sqrt(7 / 5)
#: A point's chi^2 / dof counts at most this in the fit (|z| = 4): the factor describes the
#: bulk; the rare points far beyond are the tail, counted apart (:func:`cross_validated`).
CAP = 16.0
#: The capped fit is repeated until no point's factor moves by SETTLED (at most ROUNDS).
ROUNDS, SETTLED = 40, 1e-3


def point_chi(runs: pd.DataFrame, q: str) -> pd.DataFrame:
    """Per point with at least two usable seeds of ``q``: its AXES, chi^2 of the seeds'
    values about their weighted mean, its degrees of freedom and ``not_converged`` (the
    share of its seeds that ended so); ZONE_QUANTITIES only where the seeds agree on the
    layout (as :func:`calibration_table`)."""
    rows = []
    for key, g in runs.groupby(list(AXES), sort=False):
        if q in ZONE_QUANTITIES and g["layout"].nunique() > 1:
            continue
        x, se = g[q].to_numpy(float), g[q + "_stderr"].to_numpy(float)
        ok = np.isfinite(x) & np.isfinite(se) & (se > 0)
        if ok.sum() < 2:
            continue
        x, se = x[ok], se[ok]
        w = 1.0 / se**2
        mean = float(np.sum(w * x) / np.sum(w))
        rows.append({**dict(zip(AXES, key, strict=True)),
                     "chi2": float(np.sum((x - mean) ** 2 * w)), "dof": int(ok.sum()) - 1,
                     "not_converged": float((g["status"] == "not_converged").mean())})
    return pd.DataFrame(rows, columns=[*AXES, "chi2", "dof", "not_converged"])


def _terms(levels: dict[str, list]) -> list[tuple[str, object]]:
    """The model's terms: the intercept, one per non-reference level, ``not_converged``."""
    out: list[tuple[str, object]] = [("intercept", "")]
    for f in FEATURES:
        if f == "not_converged":
            out.append((f, 1))
        else:
            out += [(f, v) for v in levels[f][1:]]
    return out


def _design(df: pd.DataFrame, terms: list[tuple[str, object]]) -> np.ndarray:
    cols = []
    for f, v in terms:
        if f == "intercept":
            cols.append(np.ones(len(df)))
        elif f == "not_converged":
            cols.append(df[f].to_numpy(float))
        elif isinstance(v, str):
            cols.append((df[f].astype(str) == v).to_numpy(float))
        else:
            cols.append(np.isclose(df[f].to_numpy(float), float(v)).astype(float))
    return np.column_stack(cols)


def _fit(X: np.ndarray, chi2: np.ndarray, dof: np.ndarray, ridge: float) -> np.ndarray:
    """log-factor coefficients b: each point's chi2 / (HONEST^2 f^2) ~ chi^2_dof with
    log f = X b (maximum likelihood, a ridge on every term but the intercept)."""
    from scipy.optimize import minimize
    c2 = HONEST**2
    pen = np.r_[0.0, np.ones(X.shape[1] - 1)] * ridge

    def nll(b):
        lf = X @ b
        return float(np.sum(dof * lf + chi2 / (2 * c2) * np.exp(-2 * lf)) + np.sum(pen * b * b))

    def grad(b):
        lf = X @ b
        return X.T @ (dof - chi2 / c2 * np.exp(-2 * lf)) + 2 * pen * b

    return minimize(nll, np.zeros(X.shape[1]), jac=grad, method="L-BFGS-B").x


def fit_factors(runs: pd.DataFrame, quantities: Sequence[str] = QUANTITIES[:7],
                ridge: float = 0.5, cap: float = CAP) -> pd.DataFrame:
    """The calibration factors' model, one row per (quantity, term): ``coef`` of log f.
    A point's factor is f = max(1, exp(sum of its terms' coefs)) (:func:`factors_of`): its
    stated SE times f is the SE the seeds' spread bears out (to the honest 1.18); never
    shrunk. Each point's chi^2 counts at most ``cap`` per degree of freedom in units of
    its own factor (so a stratum whose errors are all too small is calibrated, and a rare
    point far beyond its stratum's factor does not set it): the fit is repeated with the
    cap at ``cap`` max(1, f)^2 until no factor moves by SETTLED."""
    levels = {f: sorted(runs[f].unique().tolist()) for f in FEATURES if f != "not_converged"}
    terms = _terms(levels)
    rows = []
    for q in quantities:
        pts = point_chi(runs, q)
        X, dof = _design(pts, terms), pts["dof"].to_numpy(float)
        f = np.ones(len(pts))
        for _ in range(ROUNDS):   # cap in calibrated units: |z| > 4 after its factor
            chi2 = np.minimum(pts["chi2"].to_numpy(), cap * dof * np.maximum(f, 1.0)**2)
            b = _fit(X, chi2, dof, ridge)
            f, before = np.exp(X @ b), f
            if np.max(np.abs(np.maximum(f, 1.0) - np.maximum(before, 1.0))) < SETTLED:
                break
        rows += [{"quantity": q, "term": f, "level": str(v), "coef": float(c)}
                 for (f, v), c in zip(terms, b, strict=True)]
        # each base level, as a term of coefficient 0: the levels the calibration saw
        rows += [{"quantity": q, "term": f, "level": str(lv[0]), "coef": 0.0}
                 for f, lv in levels.items()]
    return pd.DataFrame(rows)


def factors_of(df: pd.DataFrame, factors: pd.DataFrame, q: str) -> np.ndarray:
    """Each row's calibration factor for ``q`` (its parameters give the levels; its
    ``not_converged`` column, a share of seeds as in the fit, or else its ``status``, the
    not_converged term)."""
    f = factors[factors["quantity"] == q]
    rows = df if "not_converged" in df else df.assign(
        not_converged=(df["status"].astype(str) == "not_converged").astype(float))
    terms = [(r.term, r.level if r.term == "dispersion" else
              (1 if r.term == "not_converged" else (float(r.level) if r.level else "")))
             for r in f.itertuples()]
    out = np.maximum(1.0, np.exp(_design(rows, terms) @ f["coef"].to_numpy(float)))
    # a level the calibration never saw (no term, and not its base level): no factor
    for feat in ("L_x", "C_sd", "d_f", "dispersion"):
        if feat not in rows:
            continue
        seen = [lv for term, lv in terms if term == feat]
        if feat == "dispersion":
            unseen = ~rows[feat].astype(str).isin(seen).to_numpy()
        else:
            vals = rows[feat].to_numpy(float)
            unseen = ~np.any(np.isclose(vals[:, None], np.asarray(seen, float)[None, :]),
                             axis=1)
        out[unseen] = np.nan
    return out


def with_calibrated_stderr(df: pd.DataFrame, factors: pd.DataFrame) -> pd.DataFrame:
    """``df`` with ``q_stderr_cal`` = ``q_stderr`` times the row's factor, for every
    quantity of ``factors`` (and ``a_end_rel_stderr_cal`` with a_end's); NaN for a row at
    a parameter value the calibration never saw."""
    out = df.copy()
    for q in dict.fromkeys(factors["quantity"]):
        f = factors_of(out, factors, q)
        out[q + "_stderr_cal"] = out[q + "_stderr"].to_numpy(float) * f
        if q == "a_end" and "a_end_rel_stderr" in out:
            out["a_end_rel_stderr_cal"] = out["a_end_rel_stderr"].to_numpy(float) * f
    return out


def calibrated_factors(path: str | Path | None = None) -> pd.DataFrame:
    """The factors' table of ``path`` (default the shipped ``results/calibration/factors.csv``)."""
    return pd.read_csv(SHIPPED / FACTORS if path is None else path, dtype={"level": str},
                       keep_default_na=False)


def calibrated(df: pd.DataFrame, factors: str | Path | pd.DataFrame | None = None
               ) -> pd.DataFrame:
    """``df`` (a table of the grid at the calibration's model version, e.g. the release's
    ``sweep.load("results/herman2019-release")``) with the calibrated standard errors
    ``q_stderr_cal`` of the shipped factors (``results/calibration/factors.csv``, or
    ``factors``: a file or its table). ValueError for a table of another model version
    (its ``provenance``) than the factors' ``model_version``."""
    import json as _json
    if not isinstance(factors, pd.DataFrame):
        factors = calibrated_factors(factors)
    want = str(factors["model_version"].iloc[0]) if "model_version" in factors else None
    if want is not None and "provenance" in df and len(df):
        have = sorted({str(_json.loads(p).get("model_version")) for p in df["provenance"]})
        if have != [want]:
            raise ValueError(f"the factors were calibrated at model version {want}; this"
                             f" table is version {', '.join(have)}: its SEs cannot be"
                             " calibrated with them")
    return with_calibrated_stderr(df, factors)


def cross_validated(runs: pd.DataFrame, quantities: Sequence[str] = QUANTITIES[:7],
                    folds: int = 5, seed: int = 0) -> pd.DataFrame:
    """The factors checked on points they were not fitted on: the points split at random
    into ``folds`` parts, each part's factors fitted on the others; per stratum and
    quantity the RMS z of the stated SEs (``q_raw``) and of the calibrated ones
    (``q_cal``), the RMS z without the points beyond |z| = 4 after calibration
    (``q_bulk``), and how many such points (``q_tail`` of ``q_n``)."""
    strata_cols = ("L_x", "C_sd", "d_f", "dispersion")
    rng = np.random.default_rng(seed)
    keys = runs.groupby(list(AXES), sort=False).ngroup()
    fold = rng.integers(0, folds, keys.max() + 1)[keys]
    held: dict[str, pd.DataFrame] = {}
    for q in quantities:
        parts = []
        for k in range(folds):
            fac = fit_factors(runs[fold != k], [q])
            pts = point_chi(runs[fold == k], q)
            if len(pts):
                pts["f"] = factors_of(pts, fac, q)   # its share of not_converged seeds
                parts.append(pts)
        held[q] = pd.concat(parts, ignore_index=True)
    strata: list[tuple[str, object, object]] = [("all", None, None)]
    for col in strata_cols:
        strata += [(f"{col} = {v}", col, v) for v in sorted(runs[col].unique())]
    strata.append(("not_converged (a seed)", "not_converged", None))
    rows = []
    for name, col, v in strata:
        row: dict = {"stratum": name}
        for q in quantities:
            p = held[q]
            if col == "not_converged":
                p = p[p["not_converged"] > 0]
            elif col is not None:
                p = p[p[col] == v]
            z2 = p["chi2"] / p["f"] ** 2
            bulk = z2 <= CAP * p["dof"]
            dof = p["dof"].sum()
            row.update({
                q + "_raw": math.sqrt(p["chi2"].sum() / dof) if dof else math.nan,
                q + "_cal": math.sqrt(z2.sum() / dof) if dof else math.nan,
                q + "_bulk": (math.sqrt(z2[bulk].sum() / p["dof"][bulk].sum())
                              if bulk.any() else math.nan),
                q + "_tail": int((~bulk).sum()), q + "_n": len(p)})
        rows.append(row)
    return pd.DataFrame(rows)


def format_check(check: pd.DataFrame, quantities: Sequence[str] = QUANTITIES[:7]) -> str:
    """:func:`cross_validated` as markdown: per cell stated -> calibrated RMS z, and the
    calibrated points beyond |z| = 4 of all."""
    lines = ["| stratum | " + " | ".join(quantities) + " |",
             "|" + "---|" * (len(quantities) + 1)]
    for _, r in check.iterrows():
        cells = ["" if not r[q + "_n"] else
                 f"{r[q + '_raw']:.2f} → {r[q + '_cal']:.2f}; {r[q + '_bulk']:.2f}"
                 f" ({int(r[q + '_tail'])}/{int(r[q + '_n'])})" for q in quantities]
        lines.append(f"| {r['stratum']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_factors(factors: pd.DataFrame) -> str:
    """The factors' model as markdown: exp(coef) per term (rows) and quantity (columns)."""
    qs = list(dict.fromkeys(factors["quantity"]))
    head = "| term | " + " | ".join(qs) + " |"
    lines = [head, "|" + "---|" * (len(qs) + 1)]
    order = ("intercept", *FEATURES)

    def key(tl):
        term, level = tl
        try:
            lv: tuple = (0, float(level))
        except ValueError:
            lv = (1, level)
        return (order.index(term), lv)

    groups = dict(list(factors.groupby(["term", "level"], sort=False)))
    for term, level in sorted(groups, key=key):
        g = groups[term, level]
        name = "intercept (at every base level: those at 1.00)" if term == "intercept" \
            else (term if term == "not_converged" else f"{term} = {level}")
        vals = g.set_index("quantity")["coef"]
        lines.append(f"| {name} | " + " | ".join(f"{math.exp(vals[q]):.2f}" for q in qs) + " |")
    return "\n".join(lines)


def command(args) -> int:
    """``herman2019 calibrate``: status 0; 2 for a bad argument, 3 for a missing table."""
    import sweep
    from sweep.errors import EXIT_OK, ConfigError
    out = Path(args.out)
    if getattr(args, "factors", False):
        path = out / "runs.csv.gz"
        if not path.exists():
            raise ConfigError(f"--factors: no runs in {path}")
        runs = pd.read_csv(path)
        factors = fit_factors(runs).assign(model_version=CALIBRATED_VERSION)
        factors.to_csv(out / FACTORS, index=False, float_format="%.6f")
        print(format_factors(factors))
        print()
        print(format_check(cross_validated(runs)))
        return EXIT_OK
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
