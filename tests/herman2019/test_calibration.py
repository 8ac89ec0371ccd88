"""The grid's error-bar calibration (herman2019.calibration): the stratified draw, the
RMS z of seeds against their stated errors, and the command on stored runs."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from herman2019 import calibration as cal
from herman2019.cli import main


def _grid(n: int = 600, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({
        "L_x": rng.choice([0.5, 1.5, 3.0], n), "T": rng.choice([1.1, 1.2, 1.8], n),
        "a0": rng.choice([0.0125, 0.02], n), "C_sd": rng.choice([0.005, 0.05, 0.2], n),
        "eps": rng.choice([0.2, 0.8], n), "d_f": rng.choice([0.005, 0.05], n),
        "dispersion": rng.choice(["ml", "ep", "ow"], n),
        "status": rng.choice(["converged_noisy"] * 9 + ["not_converged"], n),
        "compact_zone": rng.choice(["edge", "none"], n)})


def test_the_draw_takes_each_group_and_spreads_over_the_cells():
    grid = _grid().drop_duplicates(list(cal.AXES)).reset_index(drop=True)
    s = cal.draw(grid, 40, 30, 10, seed=1)
    assert list(s["group"].value_counts().sort_index().items()) == [
        ("none", 30), ("not_converged", 10), ("zone", 40)]
    assert not s.duplicated(list(cal.AXES)).any()
    merged = s.merge(grid, on=list(cal.AXES))
    assert (merged.loc[merged.group == "not_converged", "status"] == "not_converged").all()
    zone = merged[merged.group == "zone"]
    assert (zone.compact_zone != "none").all() and (zone.status != "not_converged").all()
    # one point per (C_sd, L_x, d_f, dispersion) cell before any cell gets a second:
    # 54 cells, 40 zone points: no cell twice
    assert not zone.duplicated(["C_sd", "L_x", "d_f", "dispersion"]).any()
    assert cal.draw(grid, 40, 30, 10, seed=1).equals(s)
    with pytest.raises(ValueError, match="not_converged"):
        cal.draw(grid, 1, 1, 10_000)


def test_rms_z_is_one_for_honest_errors_and_the_factor_for_wrong_ones():
    rng = np.random.default_rng(3)
    se = rng.uniform(0.5, 2.0, (4000, 3))
    x = 5.0 + rng.normal(size=se.shape) * se
    honest = cal.rms_z(zip(x, se))
    assert abs(honest[0] - 1.0) < 0.03 and honest[1] < 1.0 < honest[2] and honest[3] == 8000
    small = cal.rms_z(zip(x, se / 2))
    assert abs(small[0] - 2.0) < 0.06
    # a point with one finite value has no degree of freedom; none at all: NaN
    assert cal.rms_z([(np.array([1.0, np.nan]), np.array([1.0, 1.0]))])[3] == 0
    assert math.isnan(cal.rms_z([])[0])


def _runs(factor: float, seed: int = 5) -> pd.DataFrame:
    """Three seeds of 60 points, every quantity's SE stated ``factor`` times too small."""
    rng = np.random.default_rng(seed)
    grid = _grid(60, seed).drop(columns=["status", "compact_zone"])
    rows = []
    for i, p in grid.iterrows():
        for s in (1, 2, 3):
            row = {**p.to_dict(), "group": "zone" if i % 2 else "none", "seed": s,
                   "status": "converged_noisy", "iterations": 16,
                   "layout": "edge" if i % 2 else "none"}
            for q in cal.QUANTITIES:
                row[q] = 1.0 + 0.1 * rng.normal()
                row[q + "_stderr"] = 0.1 / factor
            rows.append(row)
    return pd.DataFrame(rows).drop_duplicates(list(cal.AXES) + ["seed"])


def test_the_table_names_each_stratum_and_finds_a_wrong_factor():
    t = cal.calibration_table(_runs(3.0))
    assert t["stratum"].iloc[0] == "all"
    assert {"group = zone", "group = none", "dispersion = ml", "C_sd = 0.2"} <= set(t["stratum"])
    assert 2.6 < t.loc[0, "a_end"] < 3.4 and t.loc[0, "a_end_lo"] < 3.0 < t.loc[0, "a_end_hi"]
    md = cal.format_table(t)
    assert md.splitlines()[0].startswith("| stratum | points | a_end | W_c |")


def test_calibrate_table_reads_stored_runs_and_refuses_none(tmp_path, capsys):
    _runs(1.0).to_csv(tmp_path / "runs.csv.gz", index=False)
    assert main(["calibrate", "--out", str(tmp_path), "--table"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("| stratum | points |") and "| all |" in out
    assert main(["calibrate", "--out", str(tmp_path / "none"), "--table"]) == 2
    assert main(["calibrate", "--out", str(tmp_path), "--seeds", "1", "1"]) == 2


def test_the_docs_table_is_what_the_command_makes():
    """docs/convergence.md and results/calibration/README.md hold the table `herman2019
    calibrate --table` makes of the shipped runs."""
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    runs = pd.read_csv(root / "results" / "calibration" / "runs.csv.gz")
    want = cal.format_table(cal.calibration_table(runs))
    start, end = "<!-- herman2019 calibrate --table -->\n", "\n<!-- end of herman2019 calibrate --table -->"
    for doc in (root / "docs" / "convergence.md", root / "results" / "calibration" / "README.md"):
        text = doc.read_text()
        assert text[text.index(start) + len(start):text.index(end)] == want, doc
