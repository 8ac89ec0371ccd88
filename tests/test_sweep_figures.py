"""``sweep figures``: one PNG per non-eps group plus the W_c summary, from a real store."""
import pytest

from sweep import parse_campaign, run_campaign
from sweep.cli import main

TOML = """\
[base]
L_sheet = 9.0
n0 = 1
nT = 1
max_iterations = 4
[sweep]
L_x = [1.5, 3.0]
eps = [0.2, 0.8]
dispersion = ["ml"]
"""


def test_figures_from_a_store(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    store = tmp_path / "s.h5"
    run_campaign(parse_campaign(TOML, "t.toml"), str(store))
    out = tmp_path / "figs"
    assert main(["figures", str(store), "--out", str(out)]) == 0
    files = sorted(p.name for p in out.iterdir())
    # two groups (L_x 1.5 and 3.0, both eps in each) + the collision-zone summary
    assert len(files) == 3 and "collision_zone.png" in files
    assert all((out / f).stat().st_size > 5000 for f in files)
    assert sum(f.startswith("profile_L_x1.5") for f in files) == 1
    assert main(["figures", str(store), "--out", str(tmp_path / "f1"), "--max", "1"]) == 0
    assert len(list((tmp_path / "f1").iterdir())) == 2


def test_figures_of_a_missing_store_is_an_error(tmp_path, capsys):
    assert main(["figures", str(tmp_path / "nope.h5"), "--out", str(tmp_path / "o")]) == 3
    assert "no such store" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
