"""Collision-zone statistics and alpha(omega) power laws across a campaign (pandas).

Everything here takes the per-point table of :func:`sweep.load` (or any DataFrame with
the same columns) and returns a new DataFrame; nothing reads profiles.

- :func:`derived` — per point: W_c / L_sheet, alpha_inner / alpha_c,
  alpha_edge / alpha_inner, the n = 1 (exponential) versus n = 2 (1/a, eq. 25) fit quality.
  A point without a compact zone (``compact_zone == "none"``) has no W_c and no
  alpha_inner (NaN): it never reads as a boundary, and it is counted apart.
- :func:`collision_stats` — the same quantities summarised per group of any swept
  parameters (``by="eps"``, ``by=["L_x", "dispersion"]``, ...).
- :func:`alpha_omega` — least-squares power laws ``alpha = c omega^m`` across the wave
  periods T for every combination of the other swept parameters (the paper's m, §3 and
  Fig. 1), for the fitted rates and, as the analytic reference, for alpha_c (eq. 24).

Only points with a result (``converged``, ``converged_noisy``, ``not_converged``) enter;
``failed`` and ``invalid`` rows have no numbers. Ratios whose denominator is zero or NaN
are NaN and are left out of the group statistics (pandas' skip-NaN aggregation); the
``n_*`` columns say how many points each statistic rests on.
"""
from __future__ import annotations

import json
import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from floewave.results import STATUSES, power_law, power_law_weighted
from sweep.identity import DIMENSIONS

__all__ = ["SWEPT", "RESULT_STATUSES", "derived", "collision_stats", "alpha_omega"]

#: The dimensions a campaign may sweep, in grid order: floewave's seven parameters, then
#: the ensemble ``seed`` (:data:`sweep.identity.DIMENSIONS`).
SWEPT = DIMENSIONS
#: Statuses of points that have results (the model's own statuses).
RESULT_STATUSES = STATUSES


def _ratio(num: pd.Series, den: pd.Series) -> pd.Series:
    num = num.astype(float)
    den = den.astype(float)
    out = num / den.where(den != 0.0)
    return out.where(np.isfinite(out))


def _sheet_lengths(df: pd.DataFrame, L_sheet: float | None) -> pd.Series:
    if L_sheet is not None:
        return pd.Series(float(L_sheet), index=df.index)
    if "L_sheet" in df.columns:
        return df["L_sheet"].astype(float)
    if "config_json" not in df.columns:
        raise ValueError("collision statistics need L_sheet: pass L_sheet=... or a table"
                         " with the config_json column (sweep.load gives it)")
    cache: dict[str, float] = {}

    def one(text: str) -> float:
        if text not in cache:
            try:
                cache[text] = float(json.loads(text)["L_sheet"])
            except (ValueError, KeyError, TypeError):
                cache[text] = math.nan
        return cache[text]

    return df["config_json"].map(one).astype(float)


def derived(df: pd.DataFrame, *, L_sheet: float | None = None,
            statuses: Sequence[str] = RESULT_STATUSES) -> pd.DataFrame:
    """The points of ``df`` with results, plus derived columns:

    - ``omega`` [rad s-1] 2 pi / T; ``L_sheet`` [m] the sheet length (from each row's
      ``config_json``, or the ``L_sheet`` argument, which overrides it);
    - ``W_c_rel`` W_c / L_sheet (NaN without a compact zone); ``compact_zone`` the
      layout (edge, inverted, patchy, none; points of stores written before model
      version 3 get ``none`` where their W_c reached L_sheet, else ``legacy``);
      ``no_compact_zone`` (bool) the whole ice is collisional: its W_c and alpha_inner
      are NaN here whatever the store holds;
    - ``inner_over_c`` alpha_inner / alpha_c (1: confined-ice attenuation, eq. 25);
      ``edge_over_inner`` alpha_edge / alpha_inner;
    - ``fit_ratio`` alpha_exp_resid / alpha_all_resid (> 1: the 1/a law, n = 2, fits better
      than the exponential, n = 1); ``prefers_n2`` (bool) alpha_all_resid <
      alpha_exp_resid;
    - standard errors (ensembles, schema 3; NaN for single trajectories): ``W_c_rel_stderr``,
      ``inner_over_c_stderr`` (alpha_inner_stderr / alpha_c: alpha_c is exact) and
      ``edge_over_inner_stderr`` (first order, the two fits' errors taken as independent).
    """
    out = df[df["status"].isin(statuses)].copy() if "status" in df.columns else df.copy()
    out["omega"] = 2.0 * math.pi / out["T"].astype(float)
    out["L_sheet"] = _sheet_lengths(out, L_sheet)
    out["compact_zone"] = _layouts(out)
    out["no_compact_zone"] = out["compact_zone"] == "none"
    # no compact zone: no boundary and no inner-zone rate (rows of old stores kept the
    # first-pair rule's W_c = L_sheet and an inner fit over the last floes)
    out["W_c"] = out["W_c"].astype(float).where(~out["no_compact_zone"])
    out["alpha_inner"] = out["alpha_inner"].astype(float).where(~out["no_compact_zone"])
    out["W_c_rel"] = out["W_c"] / out["L_sheet"]
    out["inner_over_c"] = _ratio(out["alpha_inner"], out["alpha_c"])
    out["edge_over_inner"] = _ratio(out["alpha_edge"], out["alpha_inner"])
    out["fit_ratio"] = _ratio(out["alpha_exp_resid"], out["alpha_all_resid"])
    both = out["alpha_all_resid"].notna() & out["alpha_exp_resid"].notna()
    out["prefers_n2"] = both & (out["alpha_all_resid"] < out["alpha_exp_resid"])
    for name in _SE_COLUMNS:
        if name not in out.columns:
            out[name] = math.nan
        out[name] = out[name].astype(float)
    out["W_c_stderr"] = out["W_c_stderr"].where(out["W_c"].notna())
    out["W_c_rel_stderr"] = out["W_c_stderr"] / out["L_sheet"]
    out["inner_over_c_stderr"] = _ratio(out["alpha_inner_stderr"], out["alpha_c"]).abs()
    out["edge_over_inner_stderr"] = (out["edge_over_inner"].abs() * np.sqrt(
        _ratio(out["alpha_edge_stderr"], out["alpha_edge"]) ** 2
        + _ratio(out["alpha_inner_stderr"], out["alpha_inner"]) ** 2))
    return out


#: Standard-error columns of an ensemble store (schema 3), NaN where a table lacks them.
_SE_COLUMNS = ("W_c_stderr", "alpha_all_stderr", "alpha_edge_stderr", "alpha_inner_stderr",
               "alpha_exp_stderr", "a_end_stderr")


def _se_of_mean(values: pd.Series, se: pd.Series) -> float:
    """Standard error of the plain mean of ``values`` (the finite ones) from the points'
    own standard errors, sqrt(sum se_i^2) / n: NaN when any of them lacks one."""
    ok = values.notna()
    n = int(ok.sum())
    e = se[ok]
    if n == 0 or e.isna().any():
        return math.nan
    return float(np.sqrt((e.astype(float) ** 2).sum()) / n)

def _layouts(df: pd.DataFrame) -> pd.Series:
    """The compact_zone column; for rows of older stores (empty value) derived from the
    old rule: W_c >= L_sheet meant no compact pair (``none``), else ``legacy``."""
    if "compact_zone" in df.columns:
        lay = df["compact_zone"].astype(object).where(df["compact_zone"].notna(), "")
    else:
        lay = pd.Series("", index=df.index, dtype=object)
    old = lay == ""
    if old.any():
        spans = df["W_c"].astype(float) >= df["L_sheet"].astype(float)
        lay = lay.where(~old, np.where(spans, "none", "legacy"))
    return lay.astype(str)


def _as_list(by: str | Sequence[str] | None) -> list[str]:
    if by is None:
        return []
    return [by] if isinstance(by, str) else list(by)


def collision_stats(df: pd.DataFrame, by: str | Sequence[str] | None = None, *,
                    L_sheet: float | None = None,
                    statuses: Sequence[str] = RESULT_STATUSES,
                    layouts: Sequence[str] | None = None,
                    converged_only: bool = False) -> pd.DataFrame:
    """Collision-zone statistics of a campaign, one row per group of ``by``.

    By default ``not_converged`` points (error bars above their targets, or never
    stationary; their stored profile
    is the mean so far, with its standard error) enter the statistics: ``n_not_converged``
    counts them per group, and ``converged_only=True`` leaves them out.

    Parameters
    ----------
    df : the table of :func:`sweep.load` (one row per point).
    by : swept parameter(s) to group by; ``None`` summarises all points in one row.
    L_sheet : sheet length [m]; default: from each row's ``config_json``.
    statuses : which points enter (default: all with results, ``not_converged`` included).
    converged_only : shortcut for ``statuses=("converged", "converged_noisy")``.

    Returns
    -------
    DataFrame with the ``by`` columns and

    - ``n_points``, ``n_not_converged``: points in the group, and how many of them ended
      ``not_converged``;
    - ``n_edge``, ``n_compact``, ``n_inverted``, ``n_patchy``, ``n_no_compact``: points
      per compact-zone layout (:func:`floewave.results.compact_zones`),
      ``frac_no_compact_zone``; ``n_legacy``: points of stores written before model
      version 3 that had a compact pair (old first-pair rule, no layout);
    - ``layouts`` (argument): only points of these layouts enter (e.g. ``["edge"]`` for the
      paper's layout alone); default all;
    - ``n_W_c`` (points with a W_c: a compact zone), ``W_c_mean``, ``W_c_std``,
      ``W_c_min``, ``W_c_max`` [m] over those;
    - ``W_c_rel_mean``, ``W_c_rel_std`` (W_c / L_sheet);
    - ``inner_over_c_mean``, ``inner_over_c_median``, ``n_inner_over_c`` (alpha_inner /
      alpha_c; NaN — left out — without a compact zone or where it is too short to fit);
    - ``edge_over_inner_mean``, ``edge_over_inner_median``, ``n_edge_over_inner``;
    - ``frac_prefers_n2`` (share of points where 1/a fits better than the exponential),
      ``fit_ratio_median`` (alpha_exp_resid / alpha_all_resid), ``alpha_all_resid_median``,
      ``alpha_exp_resid_median``;
    - ``W_c_mean_stderr``, ``W_c_rel_mean_stderr``, ``inner_over_c_mean_stderr``: the
      standard errors of those means propagated from the points' own (ensemble) standard
      errors, sqrt(sum se_i^2) / n — the uncertainty from the chaotic dynamics, not the
      spread across parameters (that is ``*_std``); NaN when any point of the mean has
      no standard error (single-trajectory points).
    """
    keys = _as_list(by)
    unknown = [k for k in keys if k not in df.columns]
    if unknown:
        raise KeyError(f"collision_stats: no column {unknown[0]!r} to group by")
    if converged_only:
        statuses = [s for s in statuses if s != "not_converged"]
    d = derived(df, L_sheet=L_sheet, statuses=statuses)
    if layouts is not None:
        d = d[d["compact_zone"].isin(list(layouts))]
    d = d.assign(_nc=(d["status"] == "not_converged") if "status" in d.columns else False,
                 _all=0, _edge=d["compact_zone"] == "edge",
                 _compact=d["compact_zone"] == "compact",
                 _inverted=d["compact_zone"] == "inverted",
                 _patchy=d["compact_zone"] == "patchy",
                 _legacy=d["compact_zone"] == "legacy")
    grouped = d.groupby(keys or ["_all"], sort=True, dropna=False, observed=True)
    agg = grouped.agg(
        n_points=("W_c", "size"),
        n_not_converged=("_nc", "sum"),
        n_edge=("_edge", "sum"), n_compact=("_compact", "sum"),
        n_inverted=("_inverted", "sum"), n_patchy=("_patchy", "sum"),
        n_no_compact=("no_compact_zone", "sum"), n_legacy=("_legacy", "sum"),
        frac_no_compact_zone=("no_compact_zone", "mean"),
        n_W_c=("W_c", "count"),
        W_c_mean=("W_c", "mean"), W_c_std=("W_c", "std"),
        W_c_min=("W_c", "min"), W_c_max=("W_c", "max"),
        W_c_rel_mean=("W_c_rel", "mean"), W_c_rel_std=("W_c_rel", "std"),
        inner_over_c_mean=("inner_over_c", "mean"),
        inner_over_c_median=("inner_over_c", "median"),
        n_inner_over_c=("inner_over_c", "count"),
        edge_over_inner_mean=("edge_over_inner", "mean"),
        edge_over_inner_median=("edge_over_inner", "median"),
        n_edge_over_inner=("edge_over_inner", "count"),
        frac_prefers_n2=("prefers_n2", "mean"),
        fit_ratio_median=("fit_ratio", "median"),
        alpha_all_resid_median=("alpha_all_resid", "median"),
        alpha_exp_resid_median=("alpha_exp_resid", "median"),
    ).reset_index()
    se_cols = {"W_c_mean_stderr": ("W_c", "W_c_stderr"),
               "W_c_rel_mean_stderr": ("W_c_rel", "W_c_rel_stderr"),
               "inner_over_c_mean_stderr": ("inner_over_c", "inner_over_c_stderr")}
    for name, (val, se) in se_cols.items():
        agg[name] = [_se_of_mean(g[val], g[se]) for _, g in grouped] if len(d) else []
    if not keys:
        agg = agg.drop(columns="_all")
    for col in ("n_not_converged", "n_edge", "n_compact", "n_inverted", "n_patchy",
                "n_no_compact", "n_legacy"):
        agg[col] = agg[col].astype(int)
    return agg


def alpha_omega(df: pd.DataFrame, alpha: str = "alpha_inner",
                by: str | Sequence[str] | None = None, *, min_periods: int = 3,
                statuses: Sequence[str] = RESULT_STATUSES) -> pd.DataFrame:
    """Power laws ``alpha = c omega^m`` across wave periods, one row per group.

    Parameters
    ----------
    df : the table of :func:`sweep.load`.
    alpha : the rate to fit: ``alpha_inner`` (default; the compact zone, the paper's
        comparison with eq. 24), ``alpha_all``, ``alpha_edge``, ``alpha_exp`` or
        ``alpha_c``.
    by : the parameters that define a group; default every swept parameter except T
        that is a column of ``df`` (so each group is one curve alpha(T)), ``seed`` only
        when it takes more than one value (swept seeds: one fit per seed; pass a ``by``
        without ``seed`` to pool a point's seeds into one fit). Points of a group
        that share a T (when ``by`` is coarser) all enter the fit.
    min_periods : fewer distinct T with a positive, finite alpha give NaN m.

    Returns
    -------
    DataFrame with the ``by`` columns and ``m`` (exponent), ``c`` (prefactor, units of
    alpha times s^m), ``m_stderr`` (standard error of m; NaN with 2 periods),
    ``weighted`` (True when every fitted point has a standard error, ``<alpha>_stderr``
    of an ensemble: the fit is then weighted by them and ``m_stderr`` is the weighted
    fit's, inflated by sqrt(chi^2/dof) when the scatter exceeds the error bars —
    :func:`floewave.results.power_law_weighted`; otherwise the unweighted fit and its
    residual-based standard error), ``chi2_dof`` (weighted fits),
    ``rms_log_resid`` (RMS of ln alpha - fit), ``n_periods`` (distinct T fitted),
    ``n_points`` (points fitted), ``n_dropped`` (points left out) and why:
    ``n_dropped_no_zone`` (no rate because the point has no compact zone: alpha_inner),
    ``n_dropped_nan`` (no rate otherwise: a zone too short to fit, or no floe to fit) and
    ``n_dropped_nonpositive`` (alpha <= 0: no logarithm), ``omega_min``, ``omega_max``
    [rad s-1], and ``m_c``: the same fit of ``alpha_c`` over the same points (the
    confined-ice exponent, eq. 24-28), for comparison.
    """
    if alpha not in df.columns:
        raise KeyError(f"alpha_omega: no column {alpha!r}")
    keys = _as_list(by) if by is not None else [
        k for k in SWEPT if k in df.columns and k != "T"
        and (k != "seed" or df[k].nunique() > 1)]
    if "T" in keys:
        raise ValueError("alpha_omega: T is the fitted variable, it cannot be a group key")
    d = df[df["status"].isin(statuses)] if "status" in df.columns else df
    rows = []
    for key, g in (d.groupby(keys, sort=True, dropna=False, observed=True) if keys
                   else [((), d)]):
        key = key if isinstance(key, tuple) else (key,)
        om = 2.0 * math.pi / g["T"].to_numpy(float)
        al = g[alpha].to_numpy(float)
        none = (g["compact_zone"].to_numpy(object) == "none" if "compact_zone" in g.columns
                else np.zeros(len(g), dtype=bool))
        ok = np.isfinite(al) & (al > 0)
        row = dict(zip(keys, key, strict=True))
        n_per = int(len(np.unique(om[ok])))
        se_col = alpha + "_stderr"
        se = g[se_col].to_numpy(float) if se_col in g.columns else np.full(len(g), np.nan)
        weighted = bool(n_per >= min_periods
                        and np.all(np.isfinite(se[ok]) & (se[ok] > 0)))
        chi2 = math.nan
        if n_per >= min_periods:
            m, c, m_se, rms = power_law(om[ok], al[ok])
            if weighted:
                m, c, m_se, chi2 = power_law_weighted(om[ok], al[ok], se[ok])
                rms = float(np.sqrt(np.mean((np.log(al[ok]) - np.log(c)
                                             - m * np.log(om[ok])) ** 2)))
        else:
            m = c = m_se = rms = math.nan
        ac = g["alpha_c"].to_numpy(float) if "alpha_c" in g.columns else np.full(len(g), np.nan)
        okc = ok & np.isfinite(ac) & (ac > 0)
        m_c = (power_law(om[okc], ac[okc])[0]
               if len(np.unique(om[okc])) >= min_periods else math.nan)
        row.update(m=m, c=c, m_stderr=m_se, weighted=weighted, chi2_dof=chi2,
                   rms_log_resid=rms, n_periods=n_per,
                   n_points=int(ok.sum()), n_dropped=int((~ok).sum()),
                   n_dropped_no_zone=int((~np.isfinite(al) & none).sum()),
                   n_dropped_nan=int((~np.isfinite(al) & ~none).sum()),
                   n_dropped_nonpositive=int((np.isfinite(al) & (al <= 0)).sum()),
                   omega_min=float(om[ok].min()) if ok.any() else math.nan,
                   omega_max=float(om[ok].max()) if ok.any() else math.nan, m_c=m_c)
        rows.append(row)
    cols = keys + ["m", "c", "m_stderr", "weighted", "chi2_dof", "rms_log_resid",
                   "n_periods", "n_points",
                   "n_dropped", "n_dropped_no_zone", "n_dropped_nan",
                   "n_dropped_nonpositive", "omega_min",
                   "omega_max", "m_c"]
    return pd.DataFrame(rows, columns=cols)
