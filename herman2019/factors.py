"""The calibrated standard errors: per shipped quantity a factor by stratum, fitted to the
calibration's runs (:mod:`herman2019.calibration`), that makes a point's stated SE the one
the seeds' spread bears out, and its check on points it was not fitted on.

    herman2019 calibrate --out results/calibration --factors   # fit, write factors.csv, check

A point's factor is f = max(1, exp(b_0 + its levels' terms of L_x, C_sd, d_f, dispersion +
b_nc if it ended ``not_converged``)) (:func:`fit_factors`); :func:`calibrated` adds
``q_stderr_cal`` = f ``q_stderr`` to a table of the grid at the calibration's model
version (docs/convergence.md, "Calibrated standard errors").
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from herman2019.calibration import AXES, QUANTITIES, SHIPPED, ZONE_QUANTITIES

__all__ = ["FEATURES", "FACTORS", "CALIBRATED_VERSION", "HONEST", "CAP", "point_chi",
           "fit_factors", "factors_of", "factors_between", "with_calibrated_stderr",
           "calibrated_factors",
           "calibrated", "cross_validated", "format_check", "format_factors", "command"]

#: What a point's calibration factor depends on: four swept parameters (levels) and whether
#: the point ended ``not_converged`` (in the calibration: the share of its seeds that did).
FEATURES = ("L_x", "C_sd", "d_f", "dispersion", "not_converged")
#: The fitted factors' file in the calibration's directory (``herman2019 calibrate --factors``).
FACTORS = "factors.csv"
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


#: The swept parameters whose factor :func:`factors_between` reads between the levels.
BETWEEN = ("L_x", "C_sd", "d_f")


def factors_between(df: pd.DataFrame, factors: pd.DataFrame, q: str) -> np.ndarray:
    """Each row's factor for ``q`` as :func:`factors_of`, and at a value of L_x, C_sd or d_f
    between the calibration's levels (the grid's, e.g. the surrogate's off-grid points or
    another grid's floe lengths) the log of the factor read linearly in the log of the
    parameter between the two levels around it (multilinearly when several are off their
    levels; the end level's factor beyond the levels). A row on the levels gets exactly
    :func:`factors_of`'s factor."""
    f = factors[factors["quantity"] == q]
    rows = df.reset_index(drop=True)
    out = factors_of(rows, factors, q)
    lows, weights = {}, {}
    off = np.zeros(len(rows), bool)
    bad = np.zeros(len(rows), bool)
    for feat in BETWEEN:
        if feat not in rows:
            continue
        lv = np.array(sorted({float(x) for x in f.loc[f["term"] == feat, "level"]}))
        if len(lv) < 2:
            continue
        v = rows[feat].to_numpy(float)
        bad |= ~(np.isfinite(v) & (v > 0))
        with np.errstate(invalid="ignore", divide="ignore"):
            x = np.log(np.where(np.isfinite(v) & (v > 0), v, lv[0]))
        u = np.log(lv)
        i = np.clip(np.searchsorted(u, x, side="right") - 1, 0, len(lv) - 2)
        w = np.clip((x - u[i]) / (u[i + 1] - u[i]), 0.0, 1.0)
        on = np.isclose(rows[feat].to_numpy(float)[:, None], lv[None, :]).any(axis=1)
        w[on] = 0.0
        i[on] = np.argmin(np.abs(x[on, None] - u[None, :]), axis=1) if on.any() else i[on]
        lows[feat] = (lv, i)
        weights[feat] = w
        off |= ~on
    off &= ~bad
    out[bad] = np.nan                   # no parameter value, no factor
    if not off.any():
        return out
    sub = rows[off]
    feats = list(lows)
    logf = np.zeros(int(off.sum()))
    for corner in range(2 ** len(feats)):
        snap, wt = sub.copy(), np.ones(len(sub))
        for k, feat in enumerate(feats):
            lv, i = lows[feat]
            up = (corner >> k) & 1
            j = np.minimum(i[off] + up, len(lv) - 1)
            snap[feat] = lv[j]
            wt *= weights[feat][off] if up else 1.0 - weights[feat][off]
        if not (wt > 0).any():
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            logf += np.where(wt > 0, wt * np.log(factors_of(snap, factors, q)), 0.0)
    out[off] = np.exp(logf)
    return out


def with_calibrated_stderr(df: pd.DataFrame, factors: pd.DataFrame, between: bool = False
                           ) -> pd.DataFrame:
    """``df`` with ``q_stderr_cal`` = ``q_stderr`` times the row's factor, for every
    quantity of ``factors`` (and ``a_end_rel_stderr_cal`` with a_end's); NaN for a row at
    a parameter value the calibration never saw, or with ``between`` the factor read
    between its levels (:func:`factors_between`)."""
    out = df.copy()
    for q in dict.fromkeys(factors["quantity"]):
        f = (factors_between if between else factors_of)(out, factors, q)
        out[q + "_stderr_cal"] = out[q + "_stderr"].to_numpy(float) * f
        if q == "a_end" and "a_end_rel_stderr" in out:
            out["a_end_rel_stderr_cal"] = out["a_end_rel_stderr"].to_numpy(float) * f
    return out


def calibrated_factors(path: str | Path | None = None) -> pd.DataFrame:
    """The factors' table of ``path`` (default the shipped ``results/calibration/factors.csv``)."""
    return pd.read_csv(SHIPPED / FACTORS if path is None else path, dtype={"level": str},
                       keep_default_na=False)


def calibrated(df: pd.DataFrame, factors: str | Path | pd.DataFrame | None = None,
               between: bool = False) -> pd.DataFrame:
    """``df`` (a table of the grid at the calibration's model version, e.g. the release's
    ``sweep.load("results/herman2019")``) with the calibrated standard errors
    ``q_stderr_cal`` of the shipped factors (``results/calibration/factors.csv``, or
    ``factors``: a file or its table). ValueError for a table of another model version
    (its ``provenance``) than the factors' ``model_version``. A row at a value of L_x, C_sd
    or d_f the calibration never saw has no calibrated SE (NaN), or with ``between`` one
    of the factor read between the levels around it (:func:`factors_between`)."""
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
    return with_calibrated_stderr(df, factors, between)


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
    """``herman2019 calibrate --factors``: fit the factors to ``OUT/runs.csv.gz``, write
    ``OUT/factors.csv``, print them and their check (status 0; 2 without runs)."""
    from sweep.errors import EXIT_OK, ConfigError
    out = Path(args.out)
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
