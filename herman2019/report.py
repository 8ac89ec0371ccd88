"""``herman2019 report STORE --out FILE --stores DIR [--max N]``: the campaign report of
``sweep report`` with the paper-check table of the stores in DIR as its last section
(:func:`paper_check_section`, through :func:`sweep.report.build_report`'s ``sections``)."""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from herman2019.check import check_stores
from sweep import report
from sweep.report import Section, escape, number_cell, table, text_cell

__all__ = ["paper_check_section", "command"]


def paper_check_section(stores: str | Path) -> Callable[[], Section]:
    """The report's section of the paper-check table of the stores in ``stores`` (made
    when the report calls it, after its own sections)."""

    def make() -> Section:
        where = Path(stores)
        found = check_stores(where)
        verdict_cls = {"holds": "ok", "fails": "bad"}
        rows = [[number_cell(i), text_cell(f"{c.claim} ({c.source})"),
                 text_cell(f"{c.campaign}: {c.points}"), text_cell(c.quantity),
                 text_cell("; ".join(e.text() for e in c.estimates) or "—"),
                 text_cell(f"{c.rule}: {c.evidence}" if c.rule else c.evidence),
                 text_cell(c.verdict)]
                for i, c in enumerate(found.checks, 1)]
        classes = [verdict_cls.get(c.verdict, "warn") for c in found.checks]
        counts = ", ".join(f"{n} {v}" for v, n in found.counts().items())
        problems = "".join(f"<li>{escape(k)}: {escape(v)}</li>"
                           for k, v in found.problems.items())
        return ("paper-check", "Paper check",
                '<h2 id="paper-check">Paper check</h2>'
                f"<p>Stores in <code>{escape(where)}</code>: {escape(counts)}.</p>"
                + (f"<ul>{problems}</ul>" if problems else "")
                + table(["#", "claim (paper)", "campaign: points", "quantity", "value ± SE",
                         "rule: evidence", "verdict"], rows, classes=classes))

    return make


def command(args: Any) -> int:
    """Status 0; 2 for a bad argument, 3 for a missing or unreadable store (as ``sweep
    report``'s)."""
    return report.command(args, sections=[paper_check_section(args.stores)],
                          prog="herman2019")
