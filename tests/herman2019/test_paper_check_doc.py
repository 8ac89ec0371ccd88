"""docs/paper-check.md opens with its result: the first tally on the page is the outcomes'
of results/paper-settle/settled.json read against the paper's resolution, then the settled
verdicts' own counts, and the table between its markers is what ``herman2019 check
--settled`` prints (issue [harden] 9: it gave three tallies, the settled one after ~200
lines, and an internal issue name; [grid 2]: verdicts that read the paper as written)."""
from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path

from herman2019 import outcomes

ROOT = Path(__file__).resolve().parents[2]
SETTLED = ROOT / "results" / "paper-settle" / "settled.json"
START = "<!-- herman2019 check --settled results/paper-settle/settled.json -->\n"
END = "\n<!-- end of herman2019 check --settled -->"


def test_the_page_opens_with_the_outcomes_then_the_settled_tally():
    text = (ROOT / "docs" / "paper-check.md").read_text()
    settled = json.loads(SETTLED.read_text())
    found = outcomes.counts(outcomes.classify(settled))
    first = re.search(r"(\d+) hold, (\d+) contradicted, (\d+) below the\s+paper's\s+"
                      r"resolution,\s+(\d+) inconclusive,\s+(\d+) not testable", text)
    assert first and tuple(map(int, first.groups())) == (
        found["holds"], found[outcomes.CONTRADICTED], found[outcomes.BELOW],
        found["inconclusive"], found[outcomes.NOT_TESTABLE]), first.group(0)
    counts = Counter(r["verdict"] for r in settled["rows"])
    tally = re.search(r"(\d+) hold, (\d+) fail, (\d+) inconclusive", text)
    assert tally and tuple(map(int, tally.groups())) == (
        counts["holds"], counts["fails"], counts["inconclusive"]), tally.group(0)
    assert first.start() < tally.start()
    assert text.index("## The result") < text.index("| # |"), "the result before any table"
    assert "issue [" not in text


def test_the_pages_outcome_table_is_what_the_command_prints():
    text = (ROOT / "docs" / "paper-check.md").read_text()
    assert START in text and END in text
    shown = text[text.index(START) + len(START):text.index(END)]
    assert shown == outcomes.settled_outcomes(SETTLED)
