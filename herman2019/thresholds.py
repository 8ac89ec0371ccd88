"""Verdicts as functions of the analysis thresholds the paper's words leave open, and the
reason, in numbers, why a settled row stays undecided.

Three thresholds are readings of the paper's text, not its numbers:

- **"close to", "like confined ice", "reaches the compact zone's"**: a ratio within
  [1 / b, b] with b = 1.25 (:data:`herman2019.points.INNER_OVER_C`; the log-symmetric
  half-width of "~"); curve over b (:data:`CLOSE_BOUNDS`).
- **"no visible effect", "no influence"** on a/a0: a difference within +-m, m the row's
  own (1 % of a0 for "no influence", :data:`herman2019.points.NO_EFFECT`; 0.5 % for "no
  visible", :data:`herman2019.points.A_RESOLUTION`); curve over m (:data:`MARGINS`).
- **a "spike"** of |S_sd| near the edge (Fig. 4): an excursion above f times its median,
  f = 3 (:data:`herman2019.traces.SPIKE`); curve over f
  (:data:`herman2019.traces.OTHER_SPIKES`), the rate read against [0.8, 1.25].

Each curve re-reads the row's pooled estimates with the rule of its row and the
boundary of the look that decided it (:mod:`herman2019.settle`): what the verdict would
have been under another reading. The table keeps the first reading (chosen before these
runs) and the curves show how far it may move.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from herman2019.estimates import INCONCLUSIVE, Estimate, critical, in_range
from herman2019.points import INNER_OVER_C, NO_EFFECT, range_bounds
from herman2019.settle import Settled, SettleReport
from herman2019.traces import OTHER_SPIKES, SPIKE

__all__ = ["CLOSE_BOUNDS", "MARGINS", "curves", "format_curves", "undecided_reason"]

#: The "close to" half-widths b of the curve ([1/b, b]).
CLOSE_BOUNDS = (1.1, 1.15, 1.2, 1.25, 1.3, 1.4, 1.5)
#: The "no visible effect" margins m [a0] of the curve.
MARGINS = (0.0025, 0.005, 0.0075, 0.01, 0.0125, 0.015, 0.02)
_CLOSE_Q = f"in [{INNER_OVER_C[0]}, {INNER_OVER_C[1]}]"
_LOG_Q = f"in [log10 {INNER_OVER_C[0]}, log10 {INNER_OVER_C[1]}]"


def _rule_estimates(row: Settled) -> list[Estimate]:
    c = row.check
    if c.rule.startswith("range (equivalence)"):
        return [e for e in c.estimates if e.label.startswith("difference")]
    return list(c.estimates)


def curves(report: SettleReport) -> list[dict[str, Any]]:
    """One curve per row whose verdict rests on one of the three thresholds: ``row``,
    ``claim``, ``threshold`` (what varies), ``used`` (the table's value) and ``points``
    [(value, verdict)]."""
    out = []
    for i, r in enumerate(report.rows, 1):
        c = r.check
        est = _rule_estimates(r)
        if not est:
            continue
        pts: list[tuple[float, str]] = []
        with critical(r.boundary):
            if c.claim.startswith("near the edge S_sd spikes"):
                by_f = {SPIKE: est[0], **{f: e for f, e in zip(OTHER_SPIKES, est[1:],
                                                               strict=False)}}
                pts = [(f, in_range([by_f[f]], *INNER_OVER_C)[0]) for f in sorted(by_f)]
                kind, used = "spike threshold f (x median)", SPIKE
            elif c.rule.startswith("range (equivalence)"):
                pts = [(m, in_range(est, -m, m)[0]) for m in MARGINS]
                kind, used = "no-effect margin m (a0)", (range_bounds(c.quantity)
                                                         or (0.0, NO_EFFECT))[1]
            elif _LOG_Q in c.quantity:
                pts = [(b, in_range(est, math.log10(1 / b), math.log10(b))[0])
                       for b in CLOSE_BOUNDS]
                kind, used = "close-to bound b ([1/b, b])", INNER_OVER_C[1]
            elif _CLOSE_Q in c.quantity:
                pts = [(b, in_range(est, 1 / b, b)[0]) for b in CLOSE_BOUNDS]
                kind, used = "close-to bound b ([1/b, b])", INNER_OVER_C[1]
            else:
                continue
        out.append({"row": i, "claim": c.claim, "threshold": kind, "used": used,
                    "points": pts, "verdict": c.verdict})
    return out


def format_curves(found: Sequence[dict[str, Any]]) -> str:
    """The curves as one Markdown table (h: holds, f: fails, i: inconclusive)."""
    lines = ["| # | claim | threshold | verdict at each value (the table's in bold) |",
             "|---|---|---|---|"]
    for cu in found:
        cells = []
        for v, verdict in cu["points"]:
            mark = f"{v:g}: {verdict[0]}"
            cells.append(f"**{mark}**" if math.isclose(v, cu["used"]) else mark)
        lines.append(f"| {cu['row']} | {cu['claim']} | {cu['threshold']} | "
                     + ", ".join(cells) + " |")
    lines.append("")
    lines.append("h holds, f fails, i inconclusive: the row's pooled estimates read with"
                 " its rule and look boundary at each threshold (herman2019.thresholds).")
    return "\n".join(lines)


def _z(d: float, se: float) -> float:
    return d / se if se > 0 else math.copysign(math.inf, d)


def undecided_reason(row: Settled, *, budget: int, floor: float | None = None) -> str:
    """Why an inconclusive row stays so, in numbers: the estimate (or step) nearest its
    bound, against the boundary of the last look."""
    c = row.check
    if c.verdict != INCONCLUSIVE:
        return ""
    if not row.extendable:
        return "no seed can move it (an analytic value)"
    est = [e for e in _rule_estimates(row) if math.isfinite(e.value) and math.isfinite(
        e.se)]
    where = f"at {row.seeds} seeds (the budget: {budget}), boundary {row.boundary:.2f}"
    if not est:
        return f"no estimate with an error bar {where}"
    if row.floored:
        from herman2019.settle import RESOLUTION_FLOOR, open_steps

        floor = RESOLUTION_FLOOR if floor is None else floor

        parts = [f"the step {_short(a)} -> {_short(b)} is {d:+.5f} ± {se:.5f}"
                 f" ({_z(d, se):+.1f} SE; within ±{abs(d) + zc * se:.4f} at z_c {zc:.2f})"
                 for d, se, a, b, zc in open_steps(c, row.boundary)]
        return (f"{'; '.join(parts)} {where}: below the resolution floor ±{floor:g} of a0,"
                " where the settling stops buying a step's sign")
    if c.rule.startswith("chain"):
        steps = [(b.value - a.value, math.hypot(a.se, b.se), a.label, b.label)
                 for a, b in zip(est[:-1], est[1:], strict=True)]
        d, se, a, b = min(steps, key=lambda s: abs(_z(s[0], s[1])))
        return (f"the step {_short(a)} -> {_short(b)} is {d:+.5f} ± {se:.5f}"
                f" ({_z(d, se):+.1f} SE; 95 % within ±{abs(d) + 2 * se:.4f}) {where}: a step"
                " indistinguishable from 0 leaves the ordering undecided")
    bounds = _bounds(row)
    if bounds is None:
        return f"undecided {where}"
    lo, hi = bounds
    worst = min(est, key=lambda e: abs(_z(min(abs(e.value - lo), abs(hi - e.value)), e.se)))
    bound = lo if abs(worst.value - lo) < abs(hi - worst.value) else hi
    return (f"{_short(worst.label)}: {worst.value:.4g} ± {worst.se:.2g} against the bound"
            f" {bound:.4g} ({_z(worst.value - bound, worst.se):+.1f} SE) {where}: the"
            " value sits on the threshold")


def _short(label: str) -> str:
    return label.split(" (", 1)[0]


def _bounds(row: Settled) -> tuple[float, float] | None:
    c = row.check
    if c.rule.startswith("range (equivalence)"):
        return range_bounds(c.quantity) or (-NO_EFFECT, NO_EFFECT)
    if _LOG_Q in c.quantity:
        return math.log10(INNER_OVER_C[0]), math.log10(INNER_OVER_C[1])
    if _CLOSE_Q in c.quantity:
        return INNER_OVER_C
    return None
