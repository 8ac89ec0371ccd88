"""The paper's qualitative claims (Herman et al. 2019, §4; docs/model.md §8), each checked.

Each claim is checked on the campaigns' tables and profiles.

:func:`paper_checks` is pure (DataFrames and profile arrays in, one :class:`Check` per
claim out); the rules and the standard errors are :mod:`sweep.paper.estimates`'s, with
the floors (:data:`FLOORS`) stated here where a store gives no standard error.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from sweep.analysis.stats import derived
from sweep.paper.estimates import (
    INCONCLUSIVE,
    Estimate,
    in_range,
    ordering,
    pairs,
    power_exponent,
)

__all__ = ["PAPER_CAMPAIGNS", "FLOORS", "X_NEAR", "Check", "Profile", "paper_checks"]

#: The shipped paper campaigns (``configs/<name>.toml``), checked in this order.
PAPER_CAMPAIGNS = ("fig2", "fig5", "fig6a", "fig6b", "periods")

#: Standard errors assumed where a store gives none (see the module docstring):
#:
#: - ``a_rel``: a/a0 of a single trajectory, 0.01 (1 % of a0): the default
#:   ``target_stderr``; rounding-level reruns differed by 0.1-0.7 % of a0 (docs/convergence.md).
#:   Used only where the profile's ``a_stderr`` is missing or NaN.
#: - ``W_c`` [m]: 4 m. Measured: the Fig. 2 points rerun with the floe spacing changed by
#:   one ulp (``benchmarks/rounding_spread.py``, docs/reproducibility.md) gave 7 pairs of
#:   W_c differing by 0.5-2.5 m and once 15 m; sigma = RMS difference / sqrt(2) = 4.1 m.
#: - ``inner_over_c``: 0.1 (10 %) on alpha_inner / alpha_c — *assumed, not measured*
#:   (single-trajectory stores carry no spread of alpha_inner).
#: - ``log10_force``: 0.1 decade on log10(F_w / F_d) — *assumed, not measured* (the
#:   time-mean force profiles carry no standard error).
FLOORS: dict[str, float] = {"a_rel": 0.01, "W_c": 4.0, "inner_over_c": 0.1,
                            "log10_force": 0.1}

#: Distance from the ice edge [m] at which "near the edge" is read (Fig. 6): ten 0.5 m
#: floes in, inside the collisional zone of every Fig. 6 point with one (W_c >= 12 m).
X_NEAR = 5.0

#: Claimed ranges of the exponent m of alpha ~ omega^m (paper §3, §5): "~ omega^4" for
#: ``ow`` read as 4 +- 0.5; "m close to 2.0-2.5" for ``ep`` read as 2.0-2.5 widened by 0.25
#: on each side ("close to"; the paper's own fit of the laboratory case gave 1.994).
M_OW = (3.5, 4.5)
M_EP = (1.75, 2.75)
#: "Close to" confined ice: alpha_inner / alpha_c within 25 % (0.8-1.25, symmetric in log).
INNER_OVER_C = (0.8, 1.25)
#: "Roughly two orders of magnitude": log10(F_w / F_d) within half a decade of 2.
FORCE_DECADES = (1.5, 2.5)


# ---------------------------------------------------------------------- checks
@dataclass(frozen=True)
class Check:
    """One row of the table: a claim of the paper and its verdict."""

    claim: str
    source: str
    campaign: str
    points: str
    quantity: str
    rule: str
    estimates: tuple[Estimate, ...]
    verdict: str
    evidence: str

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["estimates"] = [{k: (None if isinstance(v, float) and not math.isfinite(v)
                                 and k != "dof" else v) for k, v in asdict(e).items()}
                            for e in self.estimates]
        for e in out["estimates"]:
            if isinstance(e["dof"], float) and not math.isfinite(e["dof"]):
                e["dof"] = None
        return out


Profile = Callable[[str, str], Mapping[str, Any]]


def _close(series: pd.Series, value: Any) -> pd.Series:
    if isinstance(value, str):
        return series.astype(str) == value
    return pd.Series(np.isclose(series.astype(float), float(value), rtol=1e-9, atol=0.0),
                     index=series.index)


def _point(df: pd.DataFrame, **values: Any) -> pd.Series | None:
    """The row of ``df`` with these swept values (None if absent or without result)."""
    mask = pd.Series(True, index=df.index)
    for k, v in values.items():
        mask &= _close(df[k], v)
    rows = df[mask]
    return None if rows.empty else rows.iloc[0]


def _col(row: pd.Series, name: str) -> float:
    """``row[name]`` as float; NaN where the column is absent (an older schema)."""
    v = row.get(name, math.nan)
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    # -1 is the store's fill value of its integer columns (replicas, W_c_n): unknown
    return math.nan if (name in ("replicas", "W_c_n") and v < 0) else v


def _label(row: pd.Series | None, key: str, value: Any) -> str:
    extra = ""
    if row is not None and math.isfinite(_col(row, "replicas")):
        extra = f" (R={int(_col(row, 'replicas'))})"
    return f"{key}={value}{extra}"


def _a_end(row: pd.Series | None, label: str, profile: Profile | None,
           campaign: str) -> Estimate:
    """a_end / a0 with its SE: ``a_end_stderr``, else the profile's last ``a_stderr``."""
    if row is None:
        return Estimate(label, math.nan)
    a0 = _col(row, "a0")
    value = _col(row, "a_end") / a0
    se, src = _col(row, "a_end_stderr") / a0, "replicas"
    if not math.isfinite(se) and profile is not None:
        try:
            se, src = float(np.asarray(profile(campaign, row["hash"])["a_stderr"])[-1]) / a0, \
                "profile"
        except KeyError:
            se = math.nan
    return Estimate(label, value, se, src if math.isfinite(se) else "none").floored(
        FLOORS["a_rel"])


def _a_near(row: pd.Series | None, label: str, profile: Profile | None, campaign: str,
            x_near: float = X_NEAR) -> Estimate:
    """a / a0 at the floe nearest ``x_near`` from the edge, SE from the profile."""
    if row is None or profile is None:
        return Estimate(label, math.nan)
    try:
        p = profile(campaign, row["hash"])
    except KeyError:
        return Estimate(label, math.nan)
    x = np.asarray(p["x_mean"], dtype=float)
    i = int(np.nanargmin(np.abs(x - x_near)))
    a0 = _col(row, "a0")
    se = float(np.asarray(p["a_stderr"], dtype=float)[i]) / a0
    return Estimate(label, float(np.asarray(p["a"], dtype=float)[i]) / a0, se,
                    "profile" if math.isfinite(se) else "none").floored(FLOORS["a_rel"])


def _W_c(row: pd.Series | None, label: str) -> Estimate:
    if row is None:
        return Estimate(label, math.nan)
    se = _col(row, "W_c_stderr")
    n = _col(row, "W_c_n")
    if math.isfinite(n):
        label = f"{label} n={int(n)}"
    return Estimate(label, _col(row, "W_c"), se, "replicas" if math.isfinite(se) else "none"
                    ).floored(FLOORS["W_c"])


def _inner_over_c(row: pd.Series | None, label: str) -> Estimate:
    if row is None:
        return Estimate(label, math.nan)
    c = _col(row, "alpha_c")
    se = _col(row, "alpha_inner_stderr") / c
    return Estimate(label, _col(row, "alpha_inner") / c, se,
                    "replicas" if math.isfinite(se) else "none").floored(FLOORS["inner_over_c"])


def _force_decades(row: pd.Series | None, label: str, profile: Profile | None, campaign: str,
                   zone: str) -> Estimate:
    """Median over the floes of a zone of log10(F_w_mean / F_d_mean): ``compact`` (from W_c
    to compact_end) or ``collisional`` (before W_c); SE: the floor (none stored)."""
    if row is None or profile is None:
        return Estimate(label, math.nan)
    W_c, end = _col(row, "W_c"), _col(row, "compact_end")
    if not math.isfinite(W_c):
        return Estimate(label, math.nan)
    try:
        p = profile(campaign, row["hash"])
    except KeyError:
        return Estimate(label, math.nan)
    x = np.asarray(p["x_mean"], dtype=float)
    fw = np.asarray(p["F_w_mean"], dtype=float)
    fd = np.asarray(p["F_d_mean"], dtype=float)
    if zone == "compact":
        sel = (x >= W_c) & (x <= (end if math.isfinite(end) else np.inf))
    else:
        sel = x < W_c
    sel &= (fw > 0) & (fd > 0)
    if not sel.any():
        return Estimate(label, math.nan)
    return Estimate(label, float(np.median(np.log10(fw[sel] / fd[sel])))).floored(
        FLOORS["log10_force"])


def _exponent(df: pd.DataFrame, disp: str, alpha: str) -> Estimate:
    g = df[df["dispersion"].astype(str) == disp]
    se_col = {"alpha_inner": "alpha_inner_stderr"}.get(alpha)
    se = g[se_col].to_numpy(float) if se_col and se_col in g.columns else None
    if alpha == "alpha_c":          # the analytic rate (eq. 24) has no noise: unweighted
        se = None
    return power_exponent(2 * math.pi / g["T"].to_numpy(float), g[alpha].to_numpy(float), se,
                          label=f"m ({disp})")


def _check(claim: str, source: str, campaign: str, points: str, quantity: str, rule: str,
           estimates: Sequence[Estimate], verdict: tuple[str, str]) -> Check:
    return Check(claim, source, campaign, points, quantity, rule, tuple(estimates), *verdict)


def _sorted_values(df: pd.DataFrame, key: str, **fixed: Any) -> list[Any]:
    mask = pd.Series(True, index=df.index)
    for k, v in fixed.items():
        mask &= _close(df[k], v)
    return sorted(df.loc[mask, key].unique().tolist())


def paper_checks(tables: Mapping[str, pd.DataFrame | None],
                 profile: Profile | None = None,
                 missing: Mapping[str, str] | None = None) -> list[Check]:
    """Every claim, checked on the campaigns' tables.

    Parameters
    ----------
    tables : campaign name (:data:`PAPER_CAMPAIGNS`) -> the table of :func:`sweep.load`
        (or any DataFrame with its columns; the ensemble columns ``*_stderr``, ``W_c_n``,
        ``replicas`` are used when present); ``None`` or absent: no store.
    profile : ``profile(campaign, hash)`` -> that point's profiles (``x_mean``, ``a``,
        ``a_stderr``, ``F_w_mean``, ``F_d_mean``: arrays along the floes), e.g.
        :func:`sweep.load_profile` of the campaign's store. Without it the claims that need
        profiles are inconclusive (and a_end has only its column SE or the floor).
    missing : campaign name -> why its table is absent (shown in the evidence).
    """
    missing = dict(missing or {})
    d: dict[str, pd.DataFrame] = {}
    for name in PAPER_CAMPAIGNS:
        t = tables.get(name)
        if t is None:
            missing.setdefault(name, "no store")
        else:
            d[name] = derived(t)
    checks: list[Check] = []

    def unavailable(name: str, claim: str, source: str, points: str, quantity: str,
                    rule: str) -> None:
        checks.append(Check(claim, source, name, points, quantity, rule, (), INCONCLUSIVE,
                            f"not checked: {missing[name]}"))

    # ---- Fig. 2: restitution coefficient
    for disp in ("ml", "ep"):
        claim = f"higher eps -> lower a/a0 ({disp})"
        pts = f"{disp}, eps 0.2-0.8, far end"
        if "fig2" not in d:
            unavailable("fig2", claim, "§4.2, Fig. 2", pts, "a_end/a0", "chain, decreasing")
        else:
            df = d["fig2"]
            est = [_a_end(_point(df, eps=e, dispersion=disp), _label(
                _point(df, eps=e, dispersion=disp), "eps", e), profile, "fig2")
                for e in _sorted_values(df, "eps", dispersion=disp)]
            checks.append(_check(claim, "§4.2, Fig. 2", "fig2", pts, "a_end/a0",
                                 "chain, decreasing", est, ordering(est, increasing=False)))
    for disp in ("ml", "ep"):
        claim = f"higher eps -> narrower collisional zone W_c ({disp})"
        pts = f"{disp}, eps 0.2-0.8"
        if "fig2" not in d:
            unavailable("fig2", claim, "§4.2, Figs. 2, 3a", pts, "W_c [m]", "chain, decreasing")
        else:
            df = d["fig2"]
            est = [_W_c(_point(df, eps=e, dispersion=disp), f"eps={e}")
                   for e in _sorted_values(df, "eps", dispersion=disp)]
            checks.append(_check(claim, "§4.2, Figs. 2, 3a", "fig2", pts,
                                 "W_c [m] (no compact zone: no value)", "chain, decreasing",
                                 est, ordering(est, increasing=False)))
    # ---- ep attenuates less than ml
    for name, key in (("fig2", "eps"), ("fig5", "L_x")):
        claim = "ep attenuates less than ml (all else equal)"
        pts = f"ml/ep pairs at each {key}, far end"
        if name not in d:
            unavailable(name, claim, "§4.2, Figs. 2, 5", pts, "a_end/a0", "pairs: ep > ml")
            continue
        df = d[name]
        plist = []
        for v in _sorted_values(df, key):
            rows = {disp: _point(df, **{key: v}, dispersion=disp) for disp in ("ml", "ep")}
            plist.append(tuple(_a_end(rows[disp], f"{disp} {key}={v}", profile, name)
                               for disp in ("ml", "ep")))
        checks.append(_check(claim, "§4.2, Figs. 2, 5", name, pts, "a_end/a0",
                             "pairs: ep > ml", [e for p in plist for e in p], pairs(plist)))
    # ---- Fig. 5: floe size
    for disp in ("ep", "ml"):
        claim = f"smaller floes attenuate more ({disp})"
        pts = f"{disp}, L_x 0.5-3.0 m, far end"
        if "fig5" not in d:
            unavailable("fig5", claim, "§4.2, Fig. 5", pts, "a_end/a0", "chain, increasing")
            continue
        df = d["fig5"]
        est = [_a_end(_point(df, L_x=v, dispersion=disp), f"L_x={v}", profile, "fig5")
               for v in _sorted_values(df, "L_x", dispersion=disp)]
        checks.append(_check(claim, "§4.2, Fig. 5", "fig5", pts, "a_end/a0",
                             "chain, increasing in L_x", est, ordering(est, increasing=True)))
    # ---- Fig. 6a: floe-floe distance, near the edge and far (the reversal)
    near = f"a/a0 at x = {X_NEAR:g} m"
    if "fig6a" not in d:
        for claim, pts, q in (
                ("smaller d_f attenuates more near the edge", "T 1.2 s and 1.8 s", near),
                ("Fig. 6a reversal: far downwave smaller d_f attenuates less (short waves)",
                 "T 1.2 s", "a_end/a0"),
                ("Fig. 6a: no reversal for long waves", "T 1.8 s", "a_end/a0")):
            unavailable("fig6a", claim, "§4.2, Fig. 6a", pts, q, "")
    else:
        df = d["fig6a"]
        Ts = _sorted_values(df, "T")
        for T in Ts:
            est = [_a_near(_point(df, T=T, d_f=v), f"d_f={v}", profile, "fig6a")
                   for v in _sorted_values(df, "d_f", T=T)]
            checks.append(_check("smaller d_f attenuates more near the edge",
                                 "§4.2, Fig. 6a", "fig6a", f"T {T} s, d_f 0.005-0.05 m",
                                 near, "chain, increasing in d_f", est,
                                 ordering(est, increasing=True)))
        if len(Ts) >= 2:
            for T, claim, reverse in (
                    (Ts[0], "Fig. 6a reversal: far downwave smaller d_f attenuates less"
                     " (short waves)", True),
                    (Ts[-1], "Fig. 6a: no reversal for long waves (collisional zone spans"
                     " the domain)", False)):
                dfs = _sorted_values(df, "d_f", T=T)
                if len(dfs) < 2:
                    checks.append(Check(claim, "§4.2, Fig. 6a", "fig6a", f"T {T} s", "a_end/a0",
                                        "pair", (), INCONCLUSIVE,
                                        f"fewer than 2 values of d_f stored at T {T} s"))
                    continue
                lo, hi = (_a_end(_point(df, T=T, d_f=v), f"d_f={v}", profile, "fig6a")
                          for v in (dfs[0], dfs[-1]))
                pair = (hi, lo) if reverse else (lo, hi)
                rule = ("pair: smallest d_f above largest" if reverse
                        else "pair: smallest d_f below largest")
                checks.append(_check(claim, "§4.2, Fig. 6a", "fig6a",
                                     f"T {T} s, d_f {dfs[0]} vs {dfs[-1]} m, far end",
                                     "a_end/a0", rule, [lo, hi], pairs([pair])))
    # ---- Fig. 6b: incident amplitude
    if "fig6b" not in d:
        unavailable("fig6b", "larger a0 -> lower a/a0 (attenuation rate a0 alpha_c, eq. 25)",
                    "§4.2, Fig. 6b", "each T", "a/a0", "chain, decreasing")
    else:
        df = d["fig6b"]
        for T in _sorted_values(df, "T"):
            for where, getter in (("far end", "end"), (f"x = {X_NEAR:g} m", "near")):
                est = []
                for v in _sorted_values(df, "a0", T=T):
                    row = _point(df, T=T, a0=v)
                    est.append(_a_end(row, f"a0={v}", profile, "fig6b") if getter == "end"
                               else _a_near(row, f"a0={v}", profile, "fig6b"))
                checks.append(_check(
                    "larger a0 -> lower a/a0 (attenuation rate a0 alpha_c, eq. 25)",
                    "§4.2, Fig. 6b (direction: eq. 25)", "fig6b",
                    f"T {T} s, a0 0.0125-0.025 m, {where}",
                    "a_end/a0" if getter == "end" else near, "chain, decreasing", est,
                    ordering(est, increasing=False)))
    # ---- inner zone like confined ice; Fig. 3 force balance
    for disp in ("ml", "ep"):
        claim = f"inner zone attenuates like confined ice ({disp})"
        q = f"alpha_inner/alpha_c in [{INNER_OVER_C[0]}, {INNER_OVER_C[1]}]"
        if "fig2" not in d:
            unavailable("fig2", claim, "§4.2, Fig. 2; eq. 25", f"{disp}, eps 0.2-0.8", q,
                        "range")
            continue
        df = d["fig2"]
        est = [_inner_over_c(_point(df, eps=e, dispersion=disp), f"eps={e}")
               for e in _sorted_values(df, "eps", dispersion=disp)]
        checks.append(_check(claim, "§4.2, Fig. 2; eq. 25", "fig2", f"{disp}, eps 0.2-0.8", q,
                             "range, every point", est, in_range(est, *INNER_OVER_C)))
    q = (f"median log10(F_w/F_d) over the compact zone in [{FORCE_DECADES[0]},"
         f" {FORCE_DECADES[1]}]")
    claim = "Fig. 3: drag about two orders of magnitude below the wave force (compact zone)"
    if "fig2" not in d:
        unavailable("fig2", claim, "§4.2, Fig. 3b-d", "ml, eps 0.2-0.8", q, "range")
        unavailable("fig2", "Fig. 3: drag a larger part of the balance near the edge",
                    "§4.2, Fig. 3b-d", "ml, eps 0.2-0.8", "log10(F_w/F_d)", "pairs")
    else:
        df = d["fig2"]
        eps = _sorted_values(df, "eps", dispersion="ml")
        rows = [_point(df, eps=e, dispersion="ml") for e in eps]
        est = [_force_decades(r, f"eps={e}", profile, "fig2", "compact")
               for r, e in zip(rows, eps, strict=True)]
        checks.append(_check(claim, "§4.2, Fig. 3b-d", "fig2", "ml, eps 0.2-0.8 (Fig. 3's)", q,
                             "range, every point", est, in_range(est, *FORCE_DECADES)))
        plist = [(_force_decades(r, f"edge eps={e}", profile, "fig2", "collisional"),
                  _force_decades(r, f"compact eps={e}", profile, "fig2", "compact"))
                 for r, e in zip(rows, eps, strict=True)]
        checks.append(_check("Fig. 3: drag a larger part of the balance near the edge",
                             "§4.2, Fig. 3b-d", "fig2", "ml, eps 0.2-0.8",
                             "median log10(F_w/F_d): collisional (x < W_c) vs compact zone",
                             "pairs: compact > collisional", [e for p in plist for e in p],
                             pairs(plist)))
    # ---- alpha(omega) exponents: analytic alpha_c (eq. 24) and the DEM's alpha_inner
    for alpha, what in (("alpha_c", "alpha_c (eq. 24)"), ("alpha_inner", "alpha_inner (DEM)")):
        pts = "T 1.1-2.0 s, eps 0.6" + (" (points with a compact zone)"
                                         if alpha == "alpha_inner" else "")
        claims = (("ow", f"{what} ~ omega^4 for ow", f"m in [{M_OW[0]}, {M_OW[1]}]"),
                  ("ml", f"{what} grows faster with omega for ml than for ow", "m(ml) > m(ow)"),
                  ("ep", f"{what} ~ omega^m, m 2-2.5, for ep",
                   f"m in [{M_EP[0]}, {M_EP[1]}]"))
        if "periods" not in d:
            for _, claim, q in claims:
                unavailable("periods", claim, "§3, §5", pts, q, "")
            continue
        df = d["periods"]
        m = {disp: _exponent(df, disp, alpha) for disp in ("ow", "ml", "ep")}
        checks.append(_check(claims[0][1], "§3 (eq. 27), §5", "periods", pts, claims[0][2],
                             "range", [m["ow"]], in_range([m["ow"]], *M_OW)))
        checks.append(_check(claims[1][1], "§3 (eq. 28), Fig. 1b", "periods", pts,
                             claims[1][2], "pair: ml > ow", [m["ow"], m["ml"]],
                             pairs([(m["ow"], m["ml"])])))
        checks.append(_check(claims[2][1], "§3, §5", "periods", pts, claims[2][2], "range",
                             [m["ep"]], in_range([m["ep"]], *M_EP)))
    return checks


