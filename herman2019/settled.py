"""The settled table of ``herman2019 check --settle`` (:mod:`herman2019.settle`): Markdown
and JSON, with the reasons of undecided rows and the threshold curves
(:mod:`herman2019.thresholds`)."""
from __future__ import annotations

import json
import math
from typing import Any

from herman2019.check import markdown_cell
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE
from herman2019.pooling import HONEST_R8, WIDEN_MIN
from herman2019.sequential import ALPHA, POCOCK, crossing_rate
from herman2019.settle import SettleReport
from herman2019.thresholds import curves, format_curves, undecided_reason

__all__ = ["settled_dict", "settled_json", "format_settled"]


def settled_dict(report: SettleReport) -> dict[str, Any]:
    """Everything the settled table says, machine-readable."""
    looks = report.looks
    return {"looks": list(looks), "boundaries": list(report.boundaries),
            "first_seed": report.seeds[0], "pooled_up_to": report.pooled_up_to,
            "jobs": report.jobs, "resolution_floor": report.floor,
            "floored": [i for i, r in enumerate(report.rows, 1) if r.floored],
            "alpha_one_sided": ALPHA, "spending": POCOCK,
            "rate_if_c2_every_look": crossing_rate([s / looks[-1] for s in looks],
                                                   [2.0] * len(looks)),
            "counts": report.counts(),
            "counts_audited": report.counts(audited=True), "cost": report.cost(), "runs": report.runs,
            "calibration": report.calibration, "curves": curves(report),
            "rows": [{"look": r.look, "seeds": r.seeds, "boundary": r.boundary,
                      "extendable": r.extendable, "audited": r.audited,
                      "audited_look": r.audited_look, "floored": r.floored,
                      "undecided": undecided_reason(r, budget=looks[-1], floor=report.floor),
                      **r.check.to_dict()} for r in report.rows]}


def settled_json(report: SettleReport) -> str:
    return json.dumps(settled_dict(report), indent=2)


def format_settled(report: SettleReport) -> str:
    """The settled table (Markdown) with its rule, rate, calibration and cost lines, then
    the threshold curves (:mod:`herman2019.thresholds`)."""
    lines = ["| # | claim (paper) | campaign: points | seeds (look) | value ± SE (pooled) |"
             " rule: evidence | verdict | audited (look) |", "|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(report.rows, 1):
        c = r.check
        values = "; ".join(e.text() for e in c.estimates) or "—"
        why = undecided_reason(r, budget=report.looks[-1], floor=report.floor)
        why = f"; undecided: {why}" if why else ""
        lines.append("| " + " | ".join(markdown_cell(s) for s in (
            str(i), f"{c.claim} ({c.source})", f"{c.campaign}: {c.points}",
            f"{r.seeds} ({r.look})", values, f"{c.rule}: {c.evidence}{why}",
            c.verdict, f"{r.audited} ({r.audited_look})" if r.audited else "—")) + " |")
    counts = report.counts()
    cost = report.cost()
    cal = report.calibration
    fr = [s / report.looks[-1] for s in report.looks]
    lines += ["", f"{counts[HOLDS]} hold, {counts[FAILS]} fail, {counts[INCONCLUSIVE]}"
              f" inconclusive. Seeds from {report.seeds[0]} (the budget's {report.seeds[0]}-"
              f"{report.seeds[-1]}; pooled: up to {report.pooled_up_to}); looks at"
              f" {', '.join(map(str, report.looks))} seeds pooled,"
              f" boundaries |z| >= {', '.join(f'{c:.3f}' for c in report.boundaries)}"
              f" (Pocock-type alpha spending, one-sided alpha {ALPHA:.4f} per z; reading"
              f" every look at 2 would be {crossing_rate(fr, [2.0] * len(fr)):.4f})."]
    if report.floor is not None:
        floored = [f"#{i}" for i, r in enumerate(report.rows, 1) if r.floored]
        lines.append(f"Resolution floor: a chain of a/a0 whose undecided steps all lie within"
                     f" ±{report.floor:g} of a0 at a look gets no more seeds; stopped there: "
                     + (", ".join(floored) if floored else "none") + ".")
    moved = [f"#{i} ({r.check.verdict} -> {r.audited})" for i, r in enumerate(report.rows, 1)
             if r.audited and r.audited != r.check.verdict]
    ca = report.counts(audited=True)
    lines.append(f"Audited: {ca[HOLDS]} hold, {ca[FAILS]} fail, {ca[INCONCLUSIVE]}"
                 " inconclusive (the looks read again with each stated SE widened by the"
                 " factor all the stored seeds' spread shows it too small, on >="
                 f" {WIDEN_MIN} seeds; each look's mean its own seeds'); verdicts that move: "
                 + (", ".join(moved) if moved else "none") + ".")
    if cal:
        lines.append(f"Seeds' spread against their stated SEs: chi^2/dof"
                     f" {cal['chi2_per_dof']:.3f} over {cal['estimates']} estimates"
                     f" ({cal['dof']:.0f} dof, {cal['seeds']} seeds; SEs known exactly give"
                     f" 1 ± {math.sqrt(2 / cal['dof']):.3f}, honest SEs estimated from 8"
                     f" replicas about {HONEST_R8:.1f}).")
    lines.append(f"Settling's cost: this run added {cost['points_added']} points in"
                 f" {cost['cpu_s']:.0f} CPU s ({cost['wall_s']:.0f} s wall summed over the"
                 " looks' runs, "
                 + ("in 1 process" if report.jobs == 1 else f"{report.jobs} MPI workers")
                 + "; the"
                 f" settling took {cost['elapsed_s']:.0f} s wall, reading included); the"
                 f" table rests on {cost.get('stored_points', 0)} stored points"
                 f" ({cost.get('stored_core_s', 0)} core-s)"
                 + (f", of which seeds 2 and up (beyond --seeds 0 1):"
                    f" {cost.get('stored_points_seeds_2_up', 0)} points"
                    f" ({cost.get('stored_core_s_seeds_2_up', 0)} core-s)."
                    if report.seeds[0] < 2 else "."))
    lines += ["", "Verdicts against the thresholds the paper's words leave open:", "",
              format_curves(curves(report))]
    return "\n".join(lines)
