"""The paper's claims about the setup (§4.1-4.2): the initial placement and the edge spring,
each checked on a variant of a Fig. 2 campaign against ``fig2`` itself.

- ``uniform`` (configs/uniform.toml): the Fig. 2 points with the paper's uniform initial
  placement. "Random initial locations have no influence on the results" (§4.1) is an
  equivalence claim: a/a0 at the far end differs by less than :data:`NO_EFFECT` (1 % of
  a0, the resolution the campaigns are run to), with the whole +-z_c SE interval of the
  difference inside (the range rule); a difference detected from zero is named in the
  evidence all the same.
- ``spring_soft`` / ``spring_stiff`` (k_s / 10, k_s x 10): "the value of k_s does not have
  visible results on the simulated attenuation" (§4.1): the same equivalence rule, read
  with the paper's own word: within :data:`A_RESOLUTION` (0.5 % of a0), the smallest
  difference its figures of a/a0 could show. (Until the v8 settling: within 1 % of a0, the
  campaigns' resolution, a bound the paper does not state.)
- ``spring_none`` (k_s = 0): "without that force, the floes drift gradually in the upwave
  direction" (§4.2): the first floe's time-mean centre minus its initial one (L_x / 2) is
  negative, with the SE over the replicas.
"""
from __future__ import annotations

import math

import numpy as np

from herman2019.estimates import Estimate, in_range
from herman2019.points import (
    A_RESOLUTION,
    NO_EFFECT,
    Tables,
    a_end,
    col,
    difference,
    make_check,
    point,
    sheet_length,
    sorted_values,
)

__all__ = ["variant_checks", "first_floe_drift", "spring_claim", "no_effect_quantity"]

_FIG2_POINT = dict(eps=0.6, dispersion="ml")


def spring_claim(what: str) -> str:
    """The claim of the edge-spring row of variant ``what`` (``k_s / 10``, ``k_s x 10``)."""
    return f"the edge spring constant has no effect a figure of a/a0 could show ({what})"


def first_floe_drift(row, profile) -> Estimate:
    """The first floe's time-mean displacement from its start (x_1 = L_x / 2) [m], mean over
    the replicas with their SE (the profile's mean alone, no SE, for one replica)."""
    if row is None or profile is None:
        return Estimate("drift", math.nan)
    half = 0.5 * col(row, "L_x")
    rep = profile["x_mean_replicas"] if "x_mean_replicas" in profile else None
    if rep is not None:
        x1 = np.asarray(rep, dtype=float)[:, 0] - half
        if len(x1) >= 2 and np.all(np.isfinite(x1)):
            return Estimate("x_1 - L_x/2 [m]", float(x1.mean()),
                            float(x1.std(ddof=1) / math.sqrt(len(x1))), "replicas")
    return Estimate("x_1 - L_x/2 [m]", float(np.asarray(profile["x_mean"])[0]) - half)


def no_effect_quantity(what: str, margin: float) -> str:
    """The quantity of an equivalence row: the variant's a_end/a0 minus fig2's, within
    +-``margin``."""
    return f"a_end/a0 ({what}) - a_end/a0 (fig2) in [-{margin:g}, {margin:g}]"


def _no_effect(t: Tables, name: str, claim: str, source: str, what: str,
               margin: float) -> None:
    q = no_effect_quantity(what, margin)
    if name not in t.d or "fig2" not in t.d:
        gone = name if name not in t.d else "fig2"
        t.unavailable(gone, claim, source, "Fig. 2 points", q, "range")
        return
    df, ref = t.d[name], t.d["fig2"]
    est, vals = [], []
    for disp in sorted_values(df, "dispersion"):
        for e in sorted_values(df, "eps", dispersion=disp):
            lab = f"{disp} eps={e}"
            r0, r1 = point(ref, eps=e, dispersion=disp), point(df, eps=e, dispersion=disp)
            v0 = a_end(r0, f"fig2 {lab}", t.profile, "fig2")
            v1 = a_end(r1, f"{name} {lab}", t.profile, name)
            vals += [v0, v1]
            est.append(difference(v0, v1, f"difference {lab}"))
    verdict, evidence = in_range(est, -margin, margin)
    seen = [f"{e.label[11:]} (z = {e.value / e.se:+.1f})" for e in est
            if math.isfinite(e.se) and e.se > 0 and abs(e.value) >= 2 * e.se]
    if seen:
        evidence += "; a difference from zero is detected (|z| >= 2) at " + ", ".join(seen)
    t.add(make_check(claim, source, f"{name} vs fig2", "the Fig. 2 points of the variant", q,
                     "range (equivalence), every point", est + vals, (verdict, evidence)))


def variant_checks(t: Tables) -> None:
    """Append the placement and edge-spring claims to ``t``."""
    _no_effect(t, "uniform", "random initial locations have no influence on the results",
               "§4.1", "uniform placement", NO_EFFECT)
    for name, what in (("spring_soft", "k_s / 10"), ("spring_stiff", "k_s x 10")):
        _no_effect(t, name, spring_claim(what), "§4.1", what, A_RESOLUTION)
    claim = "without the edge spring the floes drift upwave"
    q = "first floe's mean centre minus its start, x_1 - L_x/2 [m] < 0"
    if "spring_none" not in t.d:
        t.unavailable("spring_none", claim, "§4.2, §5", "ml eps 0.6, k_s = 0", q, "range")
        return
    row = point(t.d["spring_none"], **_FIG2_POINT)
    drift = first_floe_drift(row, t.prof("spring_none", row))
    ests = [drift]
    if "fig2" in t.d:
        ref = point(t.d["fig2"], **_FIG2_POINT)
        d0 = first_floe_drift(ref, t.prof("fig2", ref))
        ests.append(Estimate("with the spring (fig2) " + d0.label, d0.value, d0.se,
                             d0.source))
    verdict, evidence = in_range([drift], -math.inf, 0.0)
    extra = ""
    if row is not None:
        start = sheet_length(row)
        extra = (f"; status {row.get('status', '?')}, ice extent"
                 f" {col(row, 'ice_extent'):.1f} m ({start:.1f} m at the start)")
    t.add(make_check(claim, "§4.2, §5", "spring_none", "ml eps 0.6 (Fig. 2), k_s = 0", q,
                     "range: below 0", ests, (verdict, evidence + extra)))
