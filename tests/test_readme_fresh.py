"""The README's figures say which model drew them, and it is this one (issue [harden] 8:
its Fig. 2 said model version 7 under model version 8, and lacked what `sweep figures`
now draws). A model version bump makes this fail until the figures are redrawn with the
commands their captions give."""
from __future__ import annotations

import json
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


def shipped_grid_versions() -> set[str]:
    """The model versions that computed the shipped grid (results/herman2019)."""
    prov = json.loads((ROOT / "results" / "herman2019" / "provenance.json").read_text())
    return {v for shard in prov["shards"].values() for v in shard["model_version"]}


def test_every_readme_figure_names_this_model_version():
    """A figure the model draws names this model version; one drawn from the shipped
    grid's table ("from the shipped table") names the version that computed the grid."""
    found = captions((ROOT / "README.md").read_text())
    assert len(found) >= 2, found
    for image, caption in found:
        assert (ROOT / image).is_file(), image
        versions = set(re.findall(r"model version (\d+)", caption))
        want = (shipped_grid_versions() if "from the shipped table" in caption
                else {str(floewave.MODEL_VERSION)})
        assert versions == want, (image, versions, want)


def test_the_readme_s_measured_blocks_name_this_model_version():
    """The demo's output and the fast tier's timing are made by docs/make_readme.py and
    stamped with the model version that made them: a model change fails this until they
    are made again (issue [harden] 8: they were another machine's and model version's)."""
    text = (ROOT / "README.md").read_text()
    blocks = dict(re.findall(r"<!-- ([a-z-]+): (.*?) -->\n.*?<!-- /\1 -->", text, re.S))
    assert set(blocks) == {"demo-output", "fast-tier"}, blocks
    for name, stamp in blocks.items():
        assert stamp.startswith(f"model version {floewave.MODEL_VERSION}, "), (name, stamp)
    demo = text.split("<!-- demo-output:", 1)[1].split("<!-- /demo-output -->", 1)[0]
    assert re.search(r"^sweep: 16 grid points: \d+ already stored, 16 stored now", demo, re.M)
