"""The README's figures say which model drew them, and it is this one (issue [harden] 8:
its Fig. 2 said model version 7 under model version 8, and lacked what `sweep figures`
now draws). A model version bump makes this fail until the figures are redrawn with the
commands their captions give."""
from __future__ import annotations

import re
from pathlib import Path

import floewave

ROOT = Path(__file__).resolve().parent.parent


def captions(text: str) -> list[tuple[str, str]]:
    """(image path, caption) of each image of ``text`` followed by an italic caption."""
    out = []
    for m in re.finditer(r"!\[[^\]]*\]\(([^)]+\.png)\)\s*\n\s*\n\*(.+?)\*\s*\n", text, re.S):
        out.append((m.group(1), m.group(2)))
    return out


def test_every_readme_figure_names_this_model_version():
    found = captions((ROOT / "README.md").read_text())
    assert len(found) >= 2, found
    for image, caption in found:
        assert (ROOT / image).is_file(), image
        versions = set(re.findall(r"model version (\d+)", caption))
        assert versions == {str(floewave.MODEL_VERSION)}, (image, versions)
