"""results/herman2019/README.md lists the grid's values (issue [harden] 9), and they are
the shipped campaign's."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_results_readme_lists_the_grid_of_its_campaign():
    text = (ROOT / "results" / "herman2019" / "README.md").read_text()
    listed = {}
    for name, values in re.findall(r"^\| `(\w+)`[^|]*\| ([^|]+) \|$", text, re.M):
        listed[name] = tuple(v.strip() for v in values.split(","))
    # the campaign file's own lists (load_campaign would expand and check all 24,192
    # points: seconds)
    sweep = tomllib.loads((ROOT / "configs" / "herman2019.toml").read_text())["sweep"]
    assert set(listed) == set(sweep), listed
    for name, values in sweep.items():
        want = tuple(str(v) for v in values)
        got = tuple(str(float(x)) if isinstance(v, float) else x
                    for x, v in zip(listed[name], values, strict=False))
        assert got == want, name
