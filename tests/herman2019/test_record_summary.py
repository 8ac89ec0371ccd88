"""``herman2019 record --summary`` and ``--plan``: a shipped campaign's run from its
provenance.json, and the projection it is measured against."""
from __future__ import annotations

import json

import pytest

from herman2019.cli import main
from herman2019.record import parse_plan, summary
from sweep.errors import ConfigError


def _shard(points, cpu, runs, nc=0, commit="abc123", dirty=False):
    return {"points": points, "cpu_s_all_ranks": cpu, "machine": "CPU X, AVX2, 2 cores",
            "status": {"converged_noisy": points - nc, "not_converged": nc},
            "store_bytes": 10_000_000, "journal_bytes": 5_000_000, "table_bytes": 500_000,
            "profiles": {"bytes": 1_000_000},
            "runs": [{"git_commit": commit, "git_dirty": dirty, "wall_s": 600.0,
                      "master_cpu_share": 0.01 * (i + 1)} for i in range(runs)]}


def test_the_summary_adds_the_shards_and_scales_the_projection():
    prov = {"plan": {"core_hours": 8.0},
            "shards": {"1/16": _shard(1500, 1800.0, 1, nc=30),
                       "0/16": _shard(1500, 1800.0, 2, nc=10)}}
    text = summary(prov, 24000)
    assert "| shards | 2 of 16: 0/16, 1/16 |" in text
    assert "| points | 3,000 of 24,000 |" in text
    assert "converged_noisy 2,960; not_converged 40" in text
    assert "shards run more than once (stopped and resumed): 0/16" in text
    assert "git_dirty False" in text and "abc123" in text
    # 3,600 s = 1 core-hour for 1/8 of the grid: 8 core-hours for the whole, 1.00x
    assert "**1.00 core-hours**" in text and "(1.00x the projection" in text
    assert "1.0-2.0 % of a core" in text
    assert "profiles 2.0 MB" in text
    two = summary({"shards": {"0/16": _shard(10, 1.0, 1, dirty=True),
                              "1/16": _shard(10, 1.0, 1, commit="def456")}})
    assert "abc123, def456; git_dirty False, True" in two


def test_the_summary_names_each_machine_with_its_shards_and_speed():
    """A grid run on two kinds of CPU (its rows reproduce bit for bit only on their own
    kind): the machine row says which shards ran where, and the CPU per point on each."""
    other = _shard(1000, 1500.0, 1) | {"machine": "CPU Y, AVX-512, 2 cores"}
    text = summary({"shards": {"0/16": _shard(1500, 1800.0, 1), "2/16": other,
                               "1/16": _shard(500, 600.0, 1)}})
    assert ("| machine | CPU X, AVX2, 2 cores: shards 0/16, 1/16 (1.20 CPU-s per point);"
            " CPU Y, AVX-512, 2 cores: shard 2/16 (1.50 CPU-s per point) |") in text


def test_the_plan_log_gives_the_projection(tmp_path):
    log = tmp_path / "plan.log"
    log.write_text("kernel: 5.133e+07 floe-steps/s per core on average (calibrated ...)\n"
                   "projected: 7.936 core-hours; nothing was written\n")
    got = parse_plan(log)
    assert got["core_hours"] == 7.936 and got["rate"] == 5.133e7
    log.write_text("sweep: nothing\n")
    with pytest.raises(ConfigError, match="no 'projected"):
        parse_plan(log)


def test_record_summary_prints_and_refuses_without_provenance(tmp_path, capsys):
    (tmp_path / "provenance.json").write_text(json.dumps(
        {"shards": {"0/8": _shard(100, 360.0, 1)}}))
    assert main(["record", "--summary", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.startswith("| | |\n|---|---|\n| shards | 1 of 8: 0/8 |")
    assert main(["record", "--summary", "--out", str(tmp_path / "none")]) == 2
    assert main(["record", "--out", str(tmp_path)]) == 2
    assert "give STORE and --shard" in capsys.readouterr().err


def test_each_results_readme_holds_the_summary_of_its_provenance():
    """A shipped campaign's README quotes `herman2019 record --summary` of its own
    provenance.json, between markers (so a shard recorded without remaking it fails)."""
    from pathlib import Path
    root = Path(__file__).resolve().parents[2] / "results"
    from herman2019.record import SUMMARY_END, SUMMARY_START
    start, end = SUMMARY_START, "\n" + SUMMARY_END
    checked = 0
    for readme in sorted(root.glob("herman2019*/README.md")):
        text = readme.read_text()
        if start not in text:
            continue
        path = readme.parent / "provenance.json"     # none before its first shard
        prov = json.loads(path.read_text()) if path.exists() else {}
        assert text[text.index(start) + len(start):text.index(end)] == summary(prov), \
            readme
        checked += 1
    assert checked >= 1


_ONE = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.0]
T = [1.0, 2.0]
[run]
name = "{name}"
"""


def test_record_names_the_campaign_and_refuses_another_campaign_s_directory(
        power_store, tmp_path, capsys):
    """A store is recorded into the directory of its own campaign only (the lx extension
    was once recorded as configs/herman2019.toml, and nothing stopped recording it over
    the release): another campaign's store exits 2 and writes nothing."""
    a = power_store(_ONE.format(name="one"), "one.toml")
    b = power_store(_ONE.format(name="two").replace("2.0]", "1.5]"), "two.toml")
    out = tmp_path / "out"
    assert main(["record", str(a), "--shard", "0/1", "--out", str(out)]) == 0
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["campaign"] == "configs/one.toml"
    # the campaign's own size (2 x 2 points), not the paper grid's 24,192
    assert prov["grid_points"] == 4
    assert "| points | " in summary(prov) and " of 4 |" in summary(prov)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert main(["record", str(b), "--shard", "0/1", "--out", str(out)]) == 2
    assert "give the --out of its campaign" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
