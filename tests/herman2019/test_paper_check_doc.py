"""docs/paper-check.md opens with its result: the first tally on the page is the settled
one, the counts of results/paper-settle/settled.json (issue [harden] 9: it gave three
tallies, the settled one after ~200 lines, and an internal issue name)."""
from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_page_opens_with_the_settled_tally():
    text = (ROOT / "docs" / "paper-check.md").read_text()
    settled = json.loads((ROOT / "results" / "paper-settle" / "settled.json").read_text())
    counts = Counter(r["verdict"] for r in settled["rows"])
    first = re.search(r"(\d+) hold, (\d+) fail, (\d+) inconclusive", text)
    assert first and tuple(map(int, first.groups())) == (
        counts["holds"], counts["fails"], counts["inconclusive"]), first.group(0)
    assert text.index("## The result") < text.index("| # |"), "the result before any table"
    assert "issue [" not in text
