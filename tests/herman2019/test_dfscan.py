"""The d_f scan analysis (herman2019.dfscan): a hand-built table and profiles with known
answers, the figure, and the v3 -> v4 store migration of the columns it reads."""
from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from herman2019.dfscan import UNITS, d_f_scan, plot_d_f_scan

#: 14 floes of L_x = 0.5 m, L_y = 10 m; windows of nT = 2 periods of T = 2 s (4 s)
N = 14
X = 0.25 + 0.52 * np.arange(N)          # mean centres; pair i's contact point at X[i] + 0.25


def _row(d_f: float, h: str, status: str = "converged_noisy") -> dict:
    return {"hash": h, "d_f": d_f, "L_x": 0.5, "T": 2.0, "a0": 0.02, "status": status,
            "replicas": 4, "a_end": 0.015, "a_end_stderr": 0.0002, "W_c": np.nan,
            "W_c_gap": 7.5, "contact_fraction_mean": 0.3,
            "contact_fraction_mean_stderr": 0.01, "collision_rate": 2.0,
            "collision_rate_stderr": 0.1, "dissipation_per_collision": 0.02,
            "dissipation_per_collision_stderr": 0.001,
            "config_json": json.dumps({"L_y": 10.0, "nT": 2})}


def _profile(scale: float) -> dict:
    nan = np.nan
    cf = np.concatenate([np.full(N - 1, 0.1), [nan]])
    cf[:4] = 0.5                                    # pairs 0-3 (contact points <= 2.33 m)
    coll = np.concatenate([np.full(N - 1, 4.0), [nan]])
    coll[:4] = 8.0
    a = 0.02 * (1 - 0.01 * X)
    return {"x_mean": X, "a": a, "a_stderr": np.full(N, 1e-5), "contact_fraction": cf,
            "collisions": coll, "S_sd": np.full(N, -0.01 * scale),
            "F_c_mean": np.full(N, 2.0)}


def test_d_f_scan_hand_built():
    df = pd.DataFrame([_row(0.01, "b" * 64), _row(0.005, "a" * 64),
                       _row(0.02, "c" * 64, status="failed")])
    profiles = {("dfscan", "a" * 64): _profile(1.0), ("dfscan", "b" * 64): _profile(2.0)}

    def profile(campaign, h):
        return profiles[campaign, h]

    t = d_f_scan(df, profile, x_near=2.4)
    assert t["d_f"].tolist() == [0.005, 0.01, 0.02]                  # sorted
    assert list(t.columns) == list(UNITS) and t.attrs["units"]["collision_rate"]
    r = t.iloc[0]
    # the floe nearest 2.4 m: X = 0.25 + 0.52 i -> i = 4 (2.33 m)
    assert r["x_near"] == pytest.approx(2.33)
    assert r["a_near_rel"] == pytest.approx(1 - 0.01 * 2.33)
    assert r["a_near_rel_stderr"] == pytest.approx(1e-5 / 0.02)
    assert r["a_end_rel"] == pytest.approx(0.75) and r["a_end_rel_stderr"] == pytest.approx(0.01)
    assert r["collision_rate"] == 2.0 and r["W_c_gap"] == 7.5
    # near-edge region x <= 2.4 m: floes 0-4 (5 floes), pairs whose contact point
    # X[i] + 0.25 <= 2.4: i = 0..3 (4 pairs, contact 0.5, 8 onsets per 4 s window)
    assert r["contact_fraction_edge"] == pytest.approx(0.5)
    assert r["collision_rate_edge"] == pytest.approx(8.0 / 2)
    power = 5 * 0.01 * 0.5 * 10.0                                   # 0.25 W
    per_second = 4 * 8.0 / 4.0                                      # 8 collisions / s
    assert r["dissipation_per_collision_edge"] == pytest.approx(power / per_second)
    # impulse proxy: 5 floes x 2 N x 4 s / 2 over 32 onsets
    assert r["impulse_per_collision_edge"] == pytest.approx(5 * 2.0 * 4.0 / 2 / 32)
    # whole ice: 14 floes x 2 N x 4 s / 2 over (4 x 8 + 9 x 4) onsets
    assert r["impulse_per_collision"] == pytest.approx(14 * 2.0 * 4.0 / 2 / 68)
    assert t.iloc[1]["dissipation_per_collision_edge"] == pytest.approx(2 * power / per_second)
    failed = t.iloc[2]
    assert failed["status"] == "failed" and math.isnan(failed["a_end_rel"])
    assert math.isnan(failed["collision_rate"]) and math.isnan(failed["x_near"])
    # without profiles: the stored columns only
    bare = d_f_scan(df)
    assert math.isnan(bare.iloc[0]["a_near_rel"]) and bare.iloc[0]["collision_rate"] == 2.0


def test_d_f_scan_refuses_two_settings():
    df = pd.DataFrame([_row(0.01, "a" * 64), _row(0.01, "b" * 64)])
    with pytest.raises(ValueError, match="several points per d_f"):
        d_f_scan(df)


def test_plot_d_f_scan_writes_a_png(tmp_path):
    df = pd.DataFrame([_row(0.005, "a" * 64), _row(0.01, "b" * 64)])
    profiles = {"a" * 64: _profile(1.0), "b" * 64: _profile(2.0)}
    t = d_f_scan(df, lambda c, h: profiles[h])
    out = plot_d_f_scan(t, tmp_path / "dfscan.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_schema_3_store_migrates_the_new_columns_as_nan(tmp_path):
    """A version-3 store (without schema 4's columns) reads them as NaN and a writer adds
    them as NaN, leaving the stored columns' values unchanged."""
    import h5py

    import sweep
    from sweep import parse_campaign, run_campaign
    from sweep.store.schema import ADDED_IN, SCHEMA_VERSION

    toml = "[base]\nL_sheet = 3.0\nreplicas = 2\n[sweep]\neps = [0.2, 0.6]\n"
    path = tmp_path / "v3.h5"
    camp = parse_campaign(toml, "m.toml")
    run_campaign(camp, str(path), compute="sweep.testing:fake_point")
    new_cols = [n for n, v in ADDED_IN.items() if v == 4]
    assert len(new_cols) == 8
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = 3
        for name in new_cols:
            del f["table"][name]
    before = sweep.load(path)
    assert all(before[c].isna().all() for c in new_cols)
    run_campaign(camp, str(path), compute="sweep.testing:fake_point")    # a writer
    with h5py.File(path, "r") as f:
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION == 5
        assert all(np.isnan(f["table"][c][:]).all() for c in new_cols)
    assert sweep.validate(path) == []
    after = sweep.load(path)
    kept = [c for c in before.columns if c not in new_cols]
    pd.testing.assert_frame_equal(before[kept], after[kept])
