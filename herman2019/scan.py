"""The d_f scan's claim in ``herman2019 check`` (issue 23): "smaller d_f attenuates more
near the edge" (§4.2, Fig. 6a) at T = 1.8 s over nine d_f (``configs/dfscan.toml``), and
what the collision statistics say about where it reverses (docs/dfscan.md).

The claim is the chain rule on a/a0 at 5 m; the evidence names the d_f of the strongest
near-edge attenuation and, below it, how the ice-wide contact fraction and collision rate
change (stored columns with their replicas' SEs, :mod:`floewave.collision_stats`). The
same explanation (:func:`scan_explanation`, made once) is quoted by the Fig. 6a row of the
same period when it fails.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from herman2019.estimates import Estimate, ordering
from herman2019.points import X_NEAR, Tables, make_check

__all__ = ["scan_checks", "scan_explanation"]


def _why(table) -> str:
    a = table["a_near_rel"].to_numpy(float)
    if not np.isfinite(a).any():
        return ""
    k = int(np.nanargmin(a))
    if k == 0:
        return ""
    lo, at = table.iloc[0], table.iloc[k]
    se = table["a_near_rel_stderr"].to_numpy(float)
    tied = [j for j in (k - 1, k + 1) if 0 <= j < len(a) and math.isfinite(a[j])
            and abs(a[j] - a[k]) < 2 * math.hypot(se[j], se[k])]
    lowest = sorted([k, *tied])
    where = "-".join(f"{table['d_f'].iloc[j] * 1e3:g}" for j in (lowest[0], lowest[-1]))
    where = where if len(lowest) > 1 else f"{at['d_f'] * 1e3:g}"

    def both(name: str, fmt: str, unit: str = "") -> str:
        return (f"{lo[name]:{fmt}}{unit} at {lo['d_f'] * 1e3:g} mm, {at[name]:{fmt}}{unit} at"
                f" {at['d_f'] * 1e3:g} mm")

    dpc = "dissipation_per_collision"

    def more(name: str) -> str:
        return "more" if lo[name] > at[name] else "less"

    return (f"non-monotonic: a/a0 at {X_NEAR:g} m is lowest at d_f = {where} mm (within 2 SE);"
            f" towards smaller d_f the floes touch {more('contact_fraction_mean')} (contact"
            f" fraction {both('contact_fraction_mean', '.3f')}) and collide"
            f" {more('collision_rate')} often (collisions per pair per period"
            f" {both('collision_rate', '.2f')}), and the drag dissipation per collision"
            f" {'falls' if lo[dpc] < at[dpc] else 'rises'}"
            f" ({both('dissipation_per_collision', '.3g', ' J')}); docs/dfscan.md")


def scan_explanation(t: Tables) -> tuple[pd.DataFrame | None, float, str]:
    """(the d_f scan's table, its period T [s], why its near-edge chain reverses: "" if it
    does not) — (None, NaN, "") without the ``dfscan`` campaign. Made once: the scan's row
    and the Fig. 6a row of the same period both quote it."""
    from herman2019.dfscan import d_f_scan

    if "dfscan" not in t.d:
        return None, math.nan, ""
    df = t.d["dfscan"]
    table = d_f_scan(df, t.profile, campaign="dfscan")
    T = float(df["T"].iloc[0]) if len(df) else math.nan
    return table, T, _why(table)


def scan_checks(t: Tables, scan: tuple[pd.DataFrame | None, float, str]) -> None:
    """Append the d_f-scan claim to ``t`` (``scan``: :func:`scan_explanation`)."""
    claim = "smaller d_f attenuates more near the edge (long waves, d_f scan)"
    q = f"a/a0 at x = {X_NEAR:g} m"
    table, T, why = scan
    if table is None:
        t.unavailable("dfscan", claim, "§4.2, Fig. 6a", "T 1.8 s, d_f 2-50 mm", q, "chain")
        return
    est = [Estimate(f"d_f={r.d_f:g}", r.a_near_rel, r.a_near_rel_stderr,
                    "profile" if math.isfinite(r.a_near_rel_stderr) else "none")
           for r in table.itertuples()]
    verdict, evidence = ordering(est, increasing=True)
    t.add(make_check(claim, "§4.2, Fig. 6a", "dfscan", f"T {T:g} s, d_f 2-50 mm", q,
                     "chain, increasing in d_f", est,
                     (verdict, evidence + (f"; {why}" if why else ""))))
