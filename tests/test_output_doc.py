"""docs/output.md is generated from sweep/store/schema.py by docs/make_output.py: the committed
file must be what the script writes, and it must name every stored and derived column
and every profile dataset."""
from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _script():
    spec = importlib.util.spec_from_file_location("make_output", ROOT / "docs" / "make_output.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_output_reference_is_what_the_script_generates():
    text = _script().render()
    assert (ROOT / "docs" / "output.md").read_text(encoding="utf-8") == text, (
        "docs/output.md is stale: run python docs/make_output.py")


def test_output_reference_names_every_column_and_dataset():
    from sweep.store.schema import COLUMNS, DERIVED, HISTORY_VAR, PROFILE_VARS, REPLICA_VARS

    text = _script().render()
    for name in [c.name for c in (*COLUMNS, *DERIVED)] + list(PROFILE_VARS) + list(
            REPLICA_VARS) + [HISTORY_VAR[0]]:
        assert f"| `{name}` |" in text, name
    assert "| `a_end_rel` | 1 | float | a_end / a0" in text


def test_every_compact_zone_layout_is_explained():
    """docs/output.md says what each value of ``compact_zone`` means (issue [harden] 9: it
    listed the values without their meaning), for every layout the model can give."""
    from floewave.results import LAYOUTS

    text = (Path(__file__).resolve().parent.parent / "docs" / "output.md").read_text()
    for layout in LAYOUTS:
        line = next((x for x in text.splitlines() if x.startswith(f"- `{layout}`: ")), "")
        assert len(line) > len(f"- `{layout}`: ") + 10, layout
