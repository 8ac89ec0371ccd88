"""The paper's claims about the two zones (§4.2, Figs. 2, 3, 6b): where the attenuation
rate changes, what balances the wave force, and how the inner rate compares with alpha_c.

Each claim is one or more rows appended to a :class:`~herman2019.points.Tables`; the
measures are :mod:`herman2019.shapes`'s and :mod:`herman2019.points`'s.
"""
from __future__ import annotations

import math

import numpy as np

from herman2019.estimates import Estimate, in_range, pairs
from herman2019.points import (
    FORCE_DECADES,
    INNER_OVER_C,
    Tables,
    col,
    force_decades,
    inner_over_c,
    label_of,
    make_check,
    point,
    sheet_length,
    sorted_values,
)
from herman2019.shapes import (
    REACH_FACTOR,
    break_estimate,
    loo_amplitudes,
    reach_estimate,
    threshold_crossing,
)

__all__ = ["zone_checks", "MARGINAL", "marginal", "unless_marginal", "notes", "BALANCE",
           "BALANCE_Q", "BALANCE_DECADES"]

#: A compact zone that starts within this distance [m] of the sheet's far end (12 floes of
#: 0.5 m, two compact_min_length) is marginal: where the mean gap of the last floes dips
#: below the 0.1 mm threshold, not a zone of floes in permanent contact.
MARGINAL = 6.0

#: "The wave-induced forces are balanced by the contact forces, with drag force roughly 2
#: orders of magnitude lower" (§4.2, Fig. 3b-d): the sentence weighs the forces in orders of
#: magnitude, and "roughly 2 orders" is read as 2 +- 0.5 decade (:data:`FORCE_DECADES`);
#: "balanced" is read on the same scale, 0 +- 0.5 decade: F_c and F_w of one order, the
#: drag two below. The paper gives no tighter number. (Until the v8 settling: F_c / F_w
#: in [0.8, 1.25], the "close to" of a ratio, a bound the paper does not state.)
BALANCE_DECADES = (FORCE_DECADES[1] - FORCE_DECADES[0]) / 2
BALANCE = ("Fig. 3: in the compact zone the contact forces balance the wave force (one order"
           " of magnitude)")
BALANCE_Q = (f"median log10(F_c/F_w) over the compact zone in [-{BALANCE_DECADES:g},"
             f" {BALANCE_DECADES:g}] (decades)")


def marginal(t: Tables, name: str, row) -> str:
    """Why ``row``'s compact zone is marginal ("" if it is not, or unknown): it starts (its
    W_c, else the first pair whose mean gap is below 0.1 mm) within :data:`MARGINAL` of
    the far end of the ice as it was placed."""
    p = t.prof(name, row)
    if p is None:
        return ""
    sheet = sheet_length(row)
    cross = (threshold_crossing(np.asarray(p["x_mean"], dtype=float), p["gap_mean"], 1e-4)
             if "gap_mean" in p else math.nan)
    start = col(row, "W_c")
    start = start if math.isfinite(start) else cross
    if not (math.isfinite(start) and sheet - start <= MARGINAL):
        return ""
    where = f"the zone starts at x = {start:.1f} m, {sheet - start:.1f} m before the ice's end"
    if math.isfinite(cross) and cross != start:
        where += f" (the replica-mean gap first drops below 0.1 mm at x = {cross:.1f} m)"
    return f"{where}: a threshold artefact (marginal zone), left out"


def unless_marginal(t: Tables, name: str, row, est: Estimate) -> tuple[Estimate, str]:
    """``est``, or (when ``row``'s zone is marginal) the same without a value, and the note."""
    why = marginal(t, name, row) if row is not None else ""
    if not why:
        return est, ""
    return Estimate(f"{est.label} (marginal zone)", math.nan), f"{est.label}: {why}"


def notes(parts: list[str]) -> str:
    """Evidence suffix from non-empty notes."""
    got = [p for p in parts if p]
    return ("; " + "; ".join(got)) if got else ""


def _over_W_c(t: Tables, row, lab: str) -> dict[str, tuple[Estimate, str]]:
    """x / W_c for x = ``x_b`` (the two-line knot) and ``x_r`` (where the local rate
    reaches the compact zone's), each with its SE (x's and W_c's combined as if
    independent) and a note with x itself; the replicas' re-marched a(x) made once."""
    p = t.prof("fig2", row)
    W, W_se = col(row, "W_c"), col(row, "W_c_stderr")
    if p is None or not math.isfinite(W) or not {"config_json", "k", "c_g"} <= set(row.index):
        return {"x_b": (Estimate(lab, math.nan), ""), "x_r": (Estimate(lab, math.nan), "")}
    loo_a = loo_amplitudes(row, p)
    out = {}
    for which, (x, x_se) in (("x_b", break_estimate(row, p, loo_a)[:2]),
                             ("x_r", reach_estimate(row, p, loo_a))):
        se = math.hypot(x_se / W, x * (W_se if math.isfinite(W_se) else math.nan) / W ** 2)
        note = (f"{lab}: {which} {x:.2f} ± {x_se:.2f} m"
                + (f", W_c {W:.2f} m" if which == "x_b" else "")) if math.isfinite(x) else ""
        out[which] = (Estimate(lab, x / W, se, "replicas" if math.isfinite(se) else "none"),
                      note)
    return out


def zone_checks(t: Tables) -> None:
    """Append the zone claims to ``t``."""
    src = "§4.2, Figs. 2, 3a"
    for disp in ("ml", "ep"):
        claim = f"attenuation steep near the edge, flatter downwave ({disp})"
        pts = f"{disp}, eps 0.2-0.8"
        if "fig2" not in t.d:
            t.unavailable("fig2", claim, src, pts, "alpha_edge vs alpha_inner", "pairs")
            t.unavailable("fig2", f"the rate reaches the compact zone's at W_c ({disp})", src,
                          pts, "x_r/W_c", "range")
            continue
        df = t.d["fig2"]
        eps = sorted_values(df, "eps", dispersion=disp)
        rows = [point(df, eps=e, dispersion=disp) for e in eps]
        plist, why = [], []
        for row, e in zip(rows, eps, strict=True):
            ests = []
            for name in ("alpha_inner", "alpha_edge"):
                if row is None:
                    ests.append(Estimate(f"{name} eps={e}", math.nan))
                    continue
                se = col(row, f"{name}_stderr")
                est, note = unless_marginal(t, "fig2", row, Estimate(
                    f"{name[6:]} eps={e}", col(row, name), se,
                    "replicas" if math.isfinite(se) else "none"))
                ests.append(est)
                why.append(note if name == "alpha_inner" else "")
            plist.append(tuple(ests))
        verdict, evidence = pairs(plist)
        t.add(make_check(claim, src, "fig2", pts, "1/a fits alpha [m^-2]: alpha_edge"
                         " (x < W_c) vs alpha_inner (compact zone)", "pairs: edge > inner",
                         [e for p_ in plist for e in p_], (verdict, evidence + notes(why))))
        both = [_over_W_c(t, row, f"eps={e}") for row, e in zip(rows, eps, strict=True)]
        knots = "; ".join(f"{b['x_b'][1]} (x_b / W_c {b['x_b'][0].value:.2f})"
                          for b in both if b["x_b"][1])
        reach = [b["x_r"] for b in both]
        marg_r = [unless_marginal(t, "fig2", row, g[0]) for row, g in zip(rows, reach,
                                                                          strict=True)]
        est_r = [m[0] for m in marg_r]
        v_r, ev_r = in_range(est_r, *INNER_OVER_C)
        t.add(make_check(
            f"the rate reaches the compact zone's at W_c ({disp})", src, "fig2", pts,
            f"x_r / W_c in [{INNER_OVER_C[0]}, {INNER_OVER_C[1]}] (x_r: where the local slope"
            f" of 1/a falls to {REACH_FACTOR:g} alpha_inner)", "range, every point", est_r,
            (v_r, f"{ev_r}{notes([m[1] for m in marg_r])}; "
                  + "; ".join(g[1] for g in reach if g[1])
                  + "; SE of x_r: the same jackknife, at least the floe grid's"
                  + (f"; not the reading (a two-line fit puts its knot mid-bend): {knots}"
                     if knots else ""))))
    # Fig. 3: in the compact zone the wave force is balanced by the contact forces
    if "fig2" not in t.d:
        t.unavailable("fig2", BALANCE, "§4.2, Fig. 3b-c", "ml, eps 0.2-0.8", BALANCE_Q, "range")
    else:
        df = t.d["fig2"]
        eps = sorted_values(df, "eps", dispersion="ml")
        est = [force_decades(point(df, eps=e, dispersion="ml"), f"eps={e}", t.profile, "fig2",
                             "compact", num="F_c_mean", den="F_w_mean") for e in eps]
        verdict, evidence = in_range(est, -BALANCE_DECADES, BALANCE_DECADES)
        ratios = ", ".join(f"{10 ** e.value:.3g}" for e in est if math.isfinite(e.value))
        t.add(make_check(BALANCE, "§4.2, Fig. 3b-c", "fig2", "ml, eps 0.2-0.8 (Fig. 3's)",
                         BALANCE_Q, "range, every point", est,
                         (verdict, evidence + (f"; F_c/F_w = {ratios}" if ratios else ""))))
    # Fig. 6b: downwave the rate is a0 alpha_c at every a0
    claim = "downwave the attenuation rate is close to a0 alpha_c at every a0"
    q = f"alpha_inner/alpha_c in [{INNER_OVER_C[0]}, {INNER_OVER_C[1]}]"
    if "fig6b" not in t.d:
        t.unavailable("fig6b", claim, "§4.2, Fig. 6b; eq. 25", "each a0", q, "range")
        return
    df = t.d["fig6b"]
    est, why = [], []
    for T in sorted_values(df, "T"):
        for a0 in sorted_values(df, "a0", T=T):
            row = point(df, T=T, a0=a0)
            e, note = unless_marginal(t, "fig6b", row,
                                      inner_over_c(row, label_of(row, f"T={T} a0", a0)))
            est.append(e)
            why.append(note)
    verdict, evidence = in_range(est, *INNER_OVER_C)
    if any(not math.isfinite(e.value) for e in est):
        evidence += " (no value: no compact zone, or a marginal one)"
    Ts = ", ".join(f"{T:g}" for T in sorted_values(df, "T"))
    t.add(make_check(claim, "§4.2, Fig. 6b; eq. 25", "fig6b", f"T {Ts} s, every a0 (points"
                     " with a compact zone)", q, "range, every point", est,
                     (verdict, evidence + notes(why))))
