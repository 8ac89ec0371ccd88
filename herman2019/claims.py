"""The paper's qualitative claims (Herman et al. 2019, §4; docs/model.md §8), each checked.

Each claim is checked on the campaigns' tables and profiles.

:func:`paper_checks` is pure (DataFrames and profile arrays in, one :class:`Check` per
claim out); the rules and the standard errors are :mod:`herman2019.estimates`'s, the
points, their estimates and the floors (:data:`FLOORS`) :mod:`herman2019.points`'s. The
claims of Figs. 2, 5, 6 (orderings) are here; the two zones' claims are
:mod:`herman2019.zones`', the alpha(omega) exponents :mod:`herman2019.exponents`', the
setup's (placement, edge spring) :mod:`herman2019.variants`'.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from herman2019.estimates import FAILS, in_range, ordering, pairs, same_order
from herman2019.exponents import exponent_checks
from herman2019.points import (
    FLOORS,
    FORCE_DECADES,
    INNER_OVER_C,
    X_NEAR,
    Check,
    Profile,
    Tables,
    a_end,
    a_near,
    config_of,
    force_decades,
    inner_over_c,
    label_of,
    make_check,
    point,
    sorted_values,
    w_c,
)
from herman2019.scan import scan_checks, scan_explanation
from herman2019.traces import trace_checks
from herman2019.variants import variant_checks
from herman2019.zones import notes, unless_marginal, zone_checks
from sweep.analysis.stats import derived

__all__ = ["PAPER_CAMPAIGNS", "FLOORS", "X_NEAR", "Check", "Profile", "paper_checks",
           "NO_REVERSAL", "NO_REVERSAL_Q", "NO_REVERSAL_RULE"]

#: Fig. 6a, T = 1.8 s: "no analogous effect [no reversal] is present for the longer waves":
#: the d_f ordering of a/a0 near the edge (x = X_NEAR) is the far end's, step by step
#: (:func:`herman2019.estimates.same_order`). Until the v8 settling it was read as "a_end/a0
#: increases with d_f", which is the near-edge claim, not the absence of a reversal.
NO_REVERSAL = (f"Fig. 6a: no reversal for long waves (the d_f order at {X_NEAR:g} m holds at the"
               " far end)")
NO_REVERSAL_Q = f"a/a0 along d_f at x = {X_NEAR:g} m and at the far end"
NO_REVERSAL_RULE = "same order at both places, every step (no step flips)"

#: The shipped paper campaigns (``configs/<name>.toml``), checked in this order.
PAPER_CAMPAIGNS = ("fig2", "fig5", "fig6a", "fig6b", "periods", "periods_fine", "dfscan",
                   "uniform", "spring_none", "spring_soft", "spring_stiff")


def paper_checks(tables: Mapping[str, pd.DataFrame | None],
                 profile: Profile | None = None,
                 missing: Mapping[str, str] | None = None, *, trace: bool = True
                 ) -> list[Check]:
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
    trace : run the Fig. 4 trace (:mod:`herman2019.traces`) when the profiles allow it.
    """
    missing = dict(missing or {})
    d: dict[str, pd.DataFrame] = {}
    for name in PAPER_CAMPAIGNS:
        table = tables.get(name)
        if table is None:
            missing.setdefault(name, "no store")
        else:
            d[name] = derived(table)
    t = Tables(d, profile, missing, [], trace)
    checks = t.checks
    unavailable = t.unavailable
    scan = scan_explanation(t)       # quoted by the Fig. 6a row and the scan's own

    # ---- Fig. 2: restitution coefficient
    for disp in ("ml", "ep"):
        claim = f"higher eps -> lower a/a0 ({disp})"
        pts = f"{disp}, eps 0.2-0.8, far end"
        if "fig2" not in d:
            unavailable("fig2", claim, "§4.2, Fig. 2", pts, "a_end/a0", "chain, decreasing")
        else:
            df = d["fig2"]
            est = [a_end(point(df, eps=e, dispersion=disp), label_of(
                point(df, eps=e, dispersion=disp), "eps", e), profile, "fig2")
                for e in sorted_values(df, "eps", dispersion=disp)]
            checks.append(make_check(claim, "§4.2, Fig. 2", "fig2", pts, "a_end/a0",
                                 "chain, decreasing", est, ordering(est, increasing=False)))
    for disp in ("ml", "ep"):
        claim = f"higher eps -> narrower collisional zone W_c ({disp})"
        pts = f"{disp}, eps 0.2-0.8"
        if "fig2" not in d:
            unavailable("fig2", claim, "§4.2, Figs. 2, 3a", pts, "W_c [m]", "chain, decreasing")
        else:
            df = d["fig2"]
            eps = sorted_values(df, "eps", dispersion=disp)
            rows = [point(df, eps=e, dispersion=disp) for e in eps]
            marg = [unless_marginal(t, "fig2", r, w_c(r, f"eps={e}"))
                    for r, e in zip(rows, eps, strict=True)]
            est = [m[0] for m in marg]
            verdict, evidence = ordering(est, increasing=False)
            evidence += w_c_definitions(t, rows, eps) + notes([m[1] for m in marg])
            checks.append(make_check(claim, "§4.2, Figs. 2, 3a", "fig2", pts,
                                     "W_c [m] (per averaging window; no compact zone: no"
                                     " value)", "chain, decreasing", est, (verdict, evidence)))
    # ---- ep attenuates less than ml
    for name, key in (("fig2", "eps"), ("fig5", "L_x")):
        claim = "ep attenuates less than ml (all else equal)"
        pts = f"ml/ep pairs at each {key}, far end"
        if name not in d:
            unavailable(name, claim, "§4.2, Figs. 2, 5", pts, "a_end/a0", "pairs: ep > ml")
            continue
        df = d[name]
        plist = []
        for v in sorted_values(df, key):
            rows = {disp: point(df, **{key: v}, dispersion=disp) for disp in ("ml", "ep")}
            plist.append(tuple(a_end(rows[disp], f"{disp} {key}={v}", profile, name)
                               for disp in ("ml", "ep")))
        checks.append(make_check(claim, "§4.2, Figs. 2, 5", name, pts, "a_end/a0",
                             "pairs: ep > ml", [e for p in plist for e in p], pairs(plist)))
    # ---- Fig. 5: floe size
    for disp in ("ep", "ml"):
        claim = f"smaller floes attenuate more ({disp})"
        pts = f"{disp}, L_x 0.5-3.0 m, far end"
        if "fig5" not in d:
            unavailable("fig5", claim, "§4.2, Fig. 5", pts, "a_end/a0", "chain, increasing")
            continue
        df = d["fig5"]
        est = [a_end(point(df, L_x=v, dispersion=disp), f"L_x={v}", profile, "fig5")
               for v in sorted_values(df, "L_x", dispersion=disp)]
        checks.append(make_check(claim, "§4.2, Fig. 5", "fig5", pts, "a_end/a0",
                             "chain, increasing in L_x", est, ordering(est, increasing=True)))
    # ---- Fig. 6a: floe-floe distance, near the edge and far (the reversal)
    near = f"a/a0 at x = {X_NEAR:g} m"
    if "fig6a" not in d:
        for claim, pts, q in (
                ("smaller d_f attenuates more near the edge", "T 1.2 s and 1.8 s", near),
                ("Fig. 6a reversal: far downwave smaller d_f attenuates less (short waves)",
                 "T 1.2 s", "a_end/a0"),
                (NO_REVERSAL, "T 1.8 s", NO_REVERSAL_Q)):
            unavailable("fig6a", claim, "§4.2, Fig. 6a", pts, q, "")
    else:
        df = d["fig6a"]
        Ts = sorted_values(df, "T")
        for T in Ts:
            est = [a_near(point(df, T=T, d_f=v), f"d_f={v}", profile, "fig6a")
                   for v in sorted_values(df, "d_f", T=T)]
            verdict, evidence = ordering(est, increasing=True)
            if verdict == FAILS and scan[2] and math.isclose(T, scan[1]):
                evidence += f"; the d_f scan: {scan[2]}"
            checks.append(make_check("smaller d_f attenuates more near the edge",
                                     "§4.2, Fig. 6a", "fig6a", f"T {T} s, d_f 0.005-0.05 m",
                                     near, "chain, increasing in d_f", est,
                                     (verdict, evidence)))
        if len(Ts) >= 2:
            T = Ts[0]
            est = [a_end(point(df, T=T, d_f=v), f"d_f={v}", profile, "fig6a")
                   for v in sorted_values(df, "d_f", T=T)]
            checks.append(make_check(
                "Fig. 6a reversal: far downwave smaller d_f attenuates less (short waves)",
                "§4.2, Fig. 6a", "fig6a", f"T {T} s, d_f 0.005-0.05 m, far end", "a_end/a0",
                "chain, decreasing in d_f (smaller d_f above)", est,
                ordering(est, increasing=False)))
            T = Ts[-1]
            vals = sorted_values(df, "d_f", T=T)
            near_est = [a_near(point(df, T=T, d_f=v), f"{X_NEAR:g} m d_f={v}", profile,
                               "fig6a") for v in vals]
            far_est = [a_end(point(df, T=T, d_f=v), f"far end d_f={v}", profile, "fig6a")
                       for v in vals]
            checks.append(make_check(NO_REVERSAL, "§4.2, Fig. 6a", "fig6a",
                                     f"T {T} s, d_f 0.005-0.05 m, x = {X_NEAR:g} m and far"
                                     " end", NO_REVERSAL_Q, NO_REVERSAL_RULE,
                                     [*near_est, *far_est], same_order(near_est, far_est)))
    # ---- Fig. 6b: incident amplitude
    if "fig6b" not in d:
        unavailable("fig6b", "larger a0 -> lower a/a0 (attenuation rate a0 alpha_c, eq. 25)",
                    "§4.2, Fig. 6b", "each T", "a/a0", "chain, decreasing")
    else:
        df = d["fig6b"]
        for T in sorted_values(df, "T"):
            for where, getter in (("far end", "end"), (f"x = {X_NEAR:g} m", "near")):
                est = []
                for v in sorted_values(df, "a0", T=T):
                    row = point(df, T=T, a0=v)
                    est.append(a_end(row, f"a0={v}", profile, "fig6b") if getter == "end"
                               else a_near(row, f"a0={v}", profile, "fig6b"))
                checks.append(make_check(
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
        eps = sorted_values(df, "eps", dispersion=disp)
        marg = [unless_marginal(t, "fig2", r, inner_over_c(r, f"eps={e}"))
                for r, e in ((point(df, eps=e, dispersion=disp), e) for e in eps)]
        est = [m[0] for m in marg]
        verdict, evidence = in_range(est, *INNER_OVER_C)
        checks.append(make_check(claim, "§4.2, Fig. 2; eq. 25", "fig2", f"{disp}, eps 0.2-0.8",
                                 q, "range, every point", est,
                                 (verdict, evidence + notes([m[1] for m in marg]))))
    q = (f"median log10(F_w/F_d) over the compact zone in [{FORCE_DECADES[0]},"
         f" {FORCE_DECADES[1]}]")
    claim = "Fig. 3: drag about two orders of magnitude below the wave force (compact zone)"
    if "fig2" not in d:
        unavailable("fig2", claim, "§4.2, Fig. 3b-d", "ml, eps 0.2-0.8", q, "range")
        unavailable("fig2", "Fig. 3: drag a larger part of the balance near the edge",
                    "§4.2, Fig. 3b-d", "ml, eps 0.2-0.8", "log10(F_w/F_d)", "pairs")
    else:
        df = d["fig2"]
        eps = sorted_values(df, "eps", dispersion="ml")
        rows = [point(df, eps=e, dispersion="ml") for e in eps]
        est = [force_decades(r, f"eps={e}", profile, "fig2", "compact")
               for r, e in zip(rows, eps, strict=True)]
        checks.append(make_check(claim, "§4.2, Fig. 3b-d", "fig2", "ml, eps 0.2-0.8 (Fig. 3's)", q,
                             "range, every point", est, in_range(est, *FORCE_DECADES)))
        plist = [(force_decades(r, f"edge eps={e}", profile, "fig2", "collisional"),
                  force_decades(r, f"compact eps={e}", profile, "fig2", "compact"))
                 for r, e in zip(rows, eps, strict=True)]
        checks.append(make_check("Fig. 3: drag a larger part of the balance near the edge",
                             "§4.2, Fig. 3b-d", "fig2", "ml, eps 0.2-0.8",
                             "median log10(F_w/F_d): collisional (x < W_c) vs compact zone",
                             "pairs: compact > collisional", [e for p in plist for e in p],
                             pairs(plist)))
    zone_checks(t)
    exponent_checks(t)
    scan_checks(t, scan)
    trace_checks(t)
    variant_checks(t)
    return checks


def w_c_definitions(t: Tables, rows: Sequence[pd.Series | None], eps: Sequence[Any]) -> str:
    """Evidence text: W_c by the paper's rule on the gaps averaged over the whole averaging
    (``W_c_gap``) minus the per-window W_c, paired per replica (both definitions from the
    same replicas: ``W_c_replicas`` and :func:`floewave.collision_stats.gap_zone_width` of
    the replicas' stored mean gaps), mean ± SE over the replicas that have both."""
    from floewave.collision_stats import gap_zone_width

    parts = []
    for row, e in zip(rows, eps, strict=True):
        p = t.prof("fig2", row)
        if p is None or "config_json" not in row.index or not all(
                k in p for k in ("W_c_replicas", "x_mean_replicas", "gap_mean_replicas")):
            continue
        cfg = config_of(row)
        per_window = np.asarray(p["W_c_replicas"], dtype=float)
        averaged = gap_zone_width(cfg, np.asarray(p["x_mean_replicas"], dtype=float),
                                  np.asarray(p["gap_mean_replicas"], dtype=float))[2]
        d = (averaged - per_window)[np.isfinite(averaged) & np.isfinite(per_window)]
        if len(d) >= 2:
            parts.append(f"eps={e} {d.mean():+.2f} ± {d.std(ddof=1) / math.sqrt(len(d)):.2f}"
                         f" m ({len(d)} replicas)")
        else:
            parts.append(f"eps={e} n/a (both in {len(d)} of {len(per_window)} replicas)")
    return ("; W_c from the gaps averaged over all windows minus per window, paired per"
            " replica: " + ", ".join(parts)) if parts else ""
