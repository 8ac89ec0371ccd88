"""The atlas's test of the paper's trend statements of §4.2 and §5 on every pair of grid
points that differ in one parameter alone (:func:`herman2019.atlas.stats.paired`)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from herman2019.atlas.edge import EDGE_X
from herman2019.atlas.page import Page
from herman2019.atlas.stats import PARAMS, paired, verdict, where_contra

__all__ = ["trend_statements", "PAPER_ROWS", "paper_outcomes"]

#: The settled paper-check (docs/paper-check.md) the statements are read against where the
#: paper made them.
SETTLED = Path(__file__).resolve().parents[2] / "results" / "paper-settle" / "settled.json"
#: The model version the shipped settled paper-check was made at (docs/paper-check.md).
SETTLED_VERSION = "9"
#: Each statement's rows of the settled paper-check (their claims' beginnings): the same
#: statement tested at the paper's own points, with the paper's resolution.
PAPER_ROWS = {
    "higher ε, lower wave amplitude (Fig. 2)": ("higher eps -> lower a/a0",),
    "the collisional zone narrows as ε grows (Figs. 2, 3a)": ("higher eps -> narrower",),
    "attenuation steep near the edge, flatter downwave": (
        "attenuation steep near the edge",),
    "the compact zone attenuates like confined ice (eq. 25)": (
        "inner zone attenuates like confined ice",),
    "ep attenuates less than ml, all else equal, always": ("ep attenuates less than ml",),
    "smaller floes attenuate more (Fig. 5)": ("smaller floes attenuate more",),
    "smaller d_f, stronger attenuation near the edge (Fig. 6a)": (
        "smaller d_f attenuates more near the edge",),
    "further downwave the d_f order reverses where the collisional zone is narrow"
    " (Fig. 6a, T 1.2 s)": ("Fig. 6a reversal",),
    "no reversal where the collisional zone spans the domain (Fig. 6a, T 1.8 s)": (
        "Fig. 6a: no reversal",),
    "larger a0, stronger attenuation (Fig. 6b; rate a0 alpha_c)": ("larger a0 -> lower",),
    "shorter waves attenuate more (alpha(omega), eqs. 24, 27-28)": (
        "alpha_inner (DEM) ~ omega^m",),
}


def paper_outcomes(path: Path = SETTLED) -> dict[str, str]:
    """statement -> its paper-check rows and their outcomes ("#1 holds, #2 holds"), from
    the settled table read against the paper's resolution (``herman2019.outcomes``);
    "no row" for a statement the paper-check does not test."""
    from herman2019.outcomes import classify
    if not path.exists():
        return {}
    outcomes = classify(json.loads(path.read_text()))
    short = {"below the paper's resolution": "below resolution"}
    out = {}
    for statement, prefixes in PAPER_ROWS.items():
        hits = [o for o in outcomes if any(o.check.claim.startswith(x) for x in prefixes)
                and o.outcome != "merged"]
        out[statement] = ", ".join(f"#{o.row} {short.get(o.outcome, o.outcome)}"
                                   for o in hits) or "no row"
    return out


def trend_statements(page: Page) -> None:
    """The paper's statements over the whole grid: one row per statement, where its
    contradictions concentrate, and W_c appearing with eps."""
    say, ok = page.say, page.ok
    resp = page.resp
    # --- the paper's trend statements over the whole grid
    say("## The paper's statements of §4.2 and §5, over the whole grid\n")
    say("The paper reads its trends off slices (Figs. 2, 5, 6). Here each is tested on every"
        " pair of points of the grid that differ in that parameter alone (adjacent values;"
        " ep against ml for the dispersion relation): z is the pair's difference in the"
        " paper's direction over its SE (the points' jackknife SEs in quadrature). A pair"
        " *agrees* at z ≥ 2 and *contradicts* at z ≤ −2. With no effect, chance alone puts"
        " about 3.3 % of pairs at z ≤ −2 (a difference of two 8-replica jackknife means is"
        " about Student's t with 14 degrees of freedom), and with an effect ≥ 0 in every"
        " pair at most 6.5 % of the pairs with z < 0 reach z ≤ −2. A statement **holds over"
        " the grid** when at least half its pairs agree and its contradictions stay within"
        " both; *holds, with real reversals* when more contradict than that but 80 % of the"
        " deciding pairs agree; *split* below 80 %. Pairs without an SE on either point are"
        " left out. The rule takes the points' SEs at their word (the calibrated ones where"
        " the page says so above; against long reference runs the stated ones' RMS z is"
        " 0.92-1.15: docs/convergence.md); an SE 15 % too small would"
        " raise the 6.5 % to about 10 %, far below the shares that make the reversals"
        " below real. Two statements are per point (edge"
        " against inner slope; the inner slope against eq. 24's) and count points. The"
        " column *at the paper's points* is apart from the grid's: the same statement"
        " tested where the paper made it, on its own points settled over independent"
        f" seeds at model version {SETTLED_VERSION} and read against what its figure"
        " could show (docs/paper-check.md, the row numbers of its table); a statement can"
        " hold there and be split over the grid, which is then a statement about the"
        " grid, not about the paper.\n")
    ice = float(np.nanmedian(ok["ice_extent"]))
    has_zone = np.isfinite(ok["W_c"])
    ya, sa, _ = resp["a_end_rel"]
    trows = []

    def trow(claim, where_, measure, t):
        trows.append((claim, where_, measure, t))

    trow("higher ε, lower wave amplitude (Fig. 2)", "§4.2", "a_end/a0 along eps",
         paired(ok, ya, sa, "eps", -1))
    trow("the collisional zone narrows as ε grows (Figs. 2, 3a)", "§4.2",
         "W_c along eps, pairs where both have a zone",
         paired(ok, ok["W_c"], ok["W_c_stderr"], "eps", -1))
    e, i = ok["alpha_edge"], ok["alpha_inner"]
    z = (e - i) / np.sqrt(ok["alpha_edge_stderr"] ** 2 + ok["alpha_inner_stderr"] ** 2)
    z = z[np.isfinite(e) & np.isfinite(i) & has_zone].to_numpy(float)
    trow("attenuation steep near the edge, flatter downwave", "§4.2",
         "alpha_edge − alpha_inner per point with a zone",
         {"n": z.size, "agree": int((z >= 2).sum()), "contra": int((z <= -2).sum()),
          "neg": int((z < 0).sum()),
          "sign": float((z > 0).mean()), "median_rel": float(np.nanmedian(
              ((e - i) / i)[np.isfinite(e) & np.isfinite(i) & has_zone]))})
    ri, si, _ = resp["inner_c"]
    zz = np.minimum(ri - 0.8, 1.25 - ri) / si
    zz = zz[np.isfinite(ri)].to_numpy(float)
    trow("the compact zone attenuates like confined ice (eq. 25)", "§4.2, §5",
         "alpha_inner/alpha_c inside [0.8, 1.25], per point",
         {"n": zz.size, "agree": int((zz >= 2).sum()), "contra": int((zz <= -2).sum()),
          "neg": int((zz < 0).sum()),
          "sign": float((zz > 0).mean()),
          "median_rel": float(np.nanmedian(ri[np.isfinite(ri)]) - 1)})
    trow("ep attenuates less than ml, all else equal, always", "§4.2, §5",
         "a_end/a0, ep minus ml", paired(ok, ya, sa, "dispersion", 1, order=("ml", "ep")))
    trow("smaller floes attenuate more (Fig. 5)", "§4.2", "a_end/a0 along L_x",
         paired(ok, ya, sa, "L_x", 1))
    trow("small floes undergo more vigorous collisions", "§4.2",
         "collisions per pair per wave period along L_x",
         paired(ok, ok["collision_rate"], ok["collision_rate_stderr"], "L_x", -1))
    per_m = ok["collision_rate"] / ok["L_x"]
    trow("... and more collisions per distance travelled by the wave", "§4.2",
         "collisions per metre of ice per period (per pair / L_x) along L_x: the 1/L_x"
         " is most of it", paired(ok, per_m, ok["collision_rate_stderr"] / ok["L_x"],
                                  "L_x", -1))
    for d in EDGE_X:
        col = f"a_rel_{d:g}m"
        if col in ok:
            trow(f"smaller d_f, stronger attenuation near the edge (Fig. 6a): at {d:g} m",
                 "§4.2", f"a/a0 at {d:g} m along d_f (from the profiles)",
                 paired(ok, ok[col], ok[col + "_stderr"], "d_f", 1))
    trow("further downwave the d_f order reverses where the collisional zone is narrow"
         " (Fig. 6a, T 1.2 s)", "§4.2",
         "a_end/a0 along d_f, pairs whose smaller d_f has a zone",
         paired(ok, ya, sa, "d_f", -1, where=has_zone))
    if "a_rel_5m" in ok:    # the paper-check's reading (#12): the order at 5 m holds far
        trow("no reversal where the collisional zone spans the domain (Fig. 6a, T 1.8 s)",
             "§4.2", "pairs along d_f whose smaller d_f has no zone and whose a/a0 at 5 m"
             " differ (|z| ≥ 2): a_end/a0 in the same order",
             paired(ok, ya, sa, "d_f", 1, where=~has_zone,
                    ref=(ok["a_rel_5m"], ok["a_rel_5m_stderr"])))
    else:
        trow("no reversal where the collisional zone spans the domain (Fig. 6a, T 1.8 s)",
             "§4.2", "a_end/a0 along d_f, pairs whose smaller d_f has no zone",
             paired(ok, ya, sa, "d_f", 1, where=~has_zone))
    trow("larger a0, stronger attenuation (Fig. 6b; rate a0 alpha_c)", "§4.2",
         "a_end/a0 along a0", paired(ok, ya, sa, "a0", -1))
    trow("shorter waves attenuate more (alpha(omega), eqs. 24, 27-28)", "§3, §5",
         "alpha_all along T", paired(ok, ok["alpha_all"], ok["alpha_all_stderr"], "T", -1))
    at_paper = paper_outcomes()
    say("| the paper says | where | at the paper's points | over the grid | n | agree |"
        " contradict | contradict among z < 0 | right sign | median change | verdict over"
        " the grid |")
    say("|---|---|---|---|---|---|---|---|---|---|---|")
    verdicts = []
    for claim, where_, measure, t in trows:
        v = verdict(t)
        verdicts.append((claim, v, t))
        paper = next((o for k, o in at_paper.items() if claim.startswith(k)), "no row")
        say(f"| {claim} | {where_} | {paper} | {measure} | {t['n']}"
            f" | {t['agree']}"
            f" ({100 * t['agree'] / max(t['n'], 1):.1f} %) | {t['contra']}"
            f" ({100 * t['contra'] / max(t['n'], 1):.1f} %)"
            f" | {100 * t['contra'] / max(t.get('neg', 0), 1):.1f} % | {100 * t['sign']:.1f} %"
            f" | {100 * t['median_rel']:+.1f} % | {v} |")
    say("")
    say("Where the contradictions concentrate (the parameter values whose pairs contradict"
        " most often, as a share of that value's pairs), for each statement that does not"
        " hold over the grid:\n")
    for claim, v, t in verdicts:
        if t["n"] and verdict(t) != "holds over the grid" and t.get("at") is not None \
                and t["contra"]:
            say(f"- {claim}: {where_contra(t)}.")
    say("")
    say("Median change: the pair's relative difference in the paper's direction (for the"
        " per-point rows: alpha_edge/alpha_inner − 1, and the median alpha_inner/alpha_c − 1)."
        " The z of one pair is stochastic (8 replicas each); the counts over thousands of"
        " pairs are not, to their binomial error.\n")
    # W_c appearing or vanishing with eps: the zone's existence is part of the statement
    piv = ok.assign(_z=has_zone.astype(float)).pivot_table(
        index=[q for q in PARAMS if q != "eps"], columns="eps", values="_z",
        aggfunc="first", observed=True)
    cols = sorted(piv.columns)
    appear = sum(int(((piv[a] == 0) & (piv[b] == 1)).sum()) for a, b in zip(cols, cols[1:]))
    vanish = sum(int(((piv[a] == 1) & (piv[b] == 0)).sum()) for a, b in zip(cols, cols[1:]))
    say(f"Raising ε by one step makes a compact zone appear in {appear} pairs and vanish in"
        f" {vanish}: where it appears, the collisional zone has shrunk from the whole sheet"
        f" ({ice:.1f} m) to W_c, the same direction as the paper's.\n")
    sh = page.shares
    fig2 = sh[(sh["L_x"] == 0.5) & (sh["d_f"] == 0.005)]
    share_fig2 = fig2["compact"].mean()
    pts = sh[(sh["L_x"] == 0.5) & (sh["T"] == 1.2) & (sh["a0"] == 0.0125)
             & (sh["C_sd"] == 0.05) & (sh["d_f"] == 0.005)]
    k = int(pts["compact"].sum())
    there = ("the paper's reading holds where the paper made it" if len(pts) and k > len(pts) / 2
             else "not at most of them" if len(pts) else "none of them is in this table")
    say("\"In most cases\" two zones: the paper writes that a(x) has the two zones \"in"
        " most cases\", of its Fig. 2 points (L_x 0.5 m, T 1.2 s, a0 0.0125 m, C_sd 0.05,"
        f" d_f 5 mm, every eps). There the grid has a compact zone at {k} of its"
        f" {len(pts)} points with results (every eps and dispersion relation): {there}."
        f" Over the grid a compact zone forms at {100 * sh['compact'].mean():.1f} % of the"
        f" points, and at {100 * share_fig2:.1f} % ±"
        f" {100 * math.sqrt(share_fig2 * (1 - share_fig2) / max(len(fig2), 1)):.1f} % of the"
        " whole L_x 0.5 m, d_f 5 mm corner (every T, a0, C_sd); elsewhere no compact zone"
        " forms and a(x) has a single regime. The two are kept apart: the first is the"
        " paper's statement, the second the grid's.\n")
    ri, _, _ = resp["inner_c"]
    rr = ri[np.isfinite(ri)].to_numpy(float)
    if rr.size:
        med = float(np.median(rr))
        boot = np.median(page.rng.choice(rr, (200, rr.size)), axis=1)
        se = float(np.std(boot))
        by_eps = ok.assign(_r=ri).groupby("eps", observed=True)["_r"].median()
        rising = bool(np.all(np.diff(by_eps.to_numpy(float)) > 0))
        way = ("faster than" if med - 1 > 2 * se else "slower than" if 1 - med > 2 * se
               else "as")
        say("**alpha_inner / alpha_c: the compact zone against eq. 24.** Over the"
            f" {rr.size} converged points with a compact zone: median {med:.3f} ± {se:.3f}"
            f" (bootstrap over points; 10-90 %: {np.quantile(rr, 0.1):.3f}-"
            f"{np.quantile(rr, 0.9):.3f}); by eps: "
            + ", ".join(f"{e:g}: {m:.3f}" for e, m in by_eps.items())
            + (" (rising with eps)" if rising else "") + f". The DEM's compact zone"
            f" attenuates {way} eq. 24's alpha_c (the confined-ice rate, eq. 25) says"
            + (f", by {100 * (med - 1):.0f} % at the median" if way != "as" else "")
            + "; why is not measured here. A finding of the grid, not a statement of the"
            " paper.\n")
    page.verdicts = verdicts
