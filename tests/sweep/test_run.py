"""In-process campaigns: store contents, resume, failures, retry, invalid points, analysis."""
import json

import h5py
import numpy as np
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.testing import fake_point
from tests.sweep.helpers import partial_shard

TOML = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.5]
eps = [0.2, 0.4, 0.6]
dispersion = ["ml", "ep"]
[run]
progress_interval = 100.0
"""
CAMPAIGN_FILE = "test.toml"


def test_run_stores_every_point(tmp_path, campaign):
    store = tmp_path / "s.h5"
    summary = run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    assert summary.computed == 12 and summary.skipped == 0
    df = sweep.load(store)
    assert len(df) == 12 and df["hash"].is_unique
    assert set(df["hash"]) == {p.hash for p in campaign.points()}
    assert set(df["status"]) == {"converged"}
    for p in campaign.points():
        row = df[df["hash"] == p.hash].iloc[0]
        expected = fake_point(p.config)
        assert row["W_c"] == expected["W_c"]
        assert row["L_x"] == p.config.L_x and row["dispersion"] == p.config.dispersion
        assert row["n_floes"] == p.config.n_floes
        assert json.loads(row["config_json"]) == p.config.to_dict()
        prov = json.loads(row["provenance"])
        for key in ("python", "numpy", "numba", "git_commit", "git_dirty", "mpi4py",
                    "mpi_library", "sweep_version", "kernel_mode"):
            assert key in prov, key
        assert row["start_time"] <= row["end_time"] and row["wall_time"] >= 0
        prof = sweep.load_profile(store, p.hash[:12])
        np.testing.assert_array_equal(prof["a"].values, expected["a"])
        np.testing.assert_array_equal(prof["residual_history"].values,
                                      expected["residual_history"])
        assert prof["a"].attrs["units"] == "m"
    assert sweep.validate(store) == []
    with h5py.File(store, "r") as f:
        assert f.attrs["campaign_toml"] == TOML
        assert f.attrs["schema_version"] == sweep.SCHEMA_VERSION
        assert f["runs/0"].attrs["outcome"] == "complete"


def test_costliest_first(tmp_path, campaign):
    run_campaign(campaign, str(tmp_path / "s.h5"), compute="sweep.testing:fake_point")
    df = sweep.load(tmp_path / "s.h5").sort_values("seq")
    assert list(df["L_x"]) == [0.5] * 6 + [1.5] * 6  # 12 floes before 4 floes


def test_resume_recomputes_nothing(tmp_path, campaign):
    store = tmp_path / "s.h5"
    run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    before = sweep.load(store)
    again = run_campaign(campaign, str(store), compute="sweep.testing:raising_point")
    assert again.computed == 0 and again.skipped == 12
    after = sweep.load(store)
    assert len(after) == 12
    assert list(after["seq"]) == list(before["seq"])
    assert set(after["status"]) == {"converged"}  # raising_point was never called


def test_partial_then_resume(tmp_path, campaign):
    store = tmp_path / "s.h5"
    small = parse_campaign(TOML.replace("[0.2, 0.4, 0.6]", "[0.2]"), "test.toml")
    run_campaign(small, str(store), compute="sweep.testing:fake_point")
    with pytest.raises(sweep.CampaignMismatchError, match="--extend"):
        run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    s = run_campaign(campaign, str(store), compute="sweep.testing:fake_point", extend=True)
    assert (s.skipped, s.computed) == (4, 8)
    df = sweep.load(store)
    assert len(df) == 12 and df["hash"].is_unique
    with h5py.File(store, "r") as f:
        assert len(f["campaign_history"]) == 1


def test_raising_points_recorded_and_campaign_completes(tmp_path, campaign):
    store = tmp_path / "s.h5"
    s = run_campaign(campaign, str(store), compute="sweep.testing:raising_point")
    assert s.counts == {"converged": 8, "failed": 4}
    df = sweep.load(store)
    failed = df[df["status"] == "failed"]
    assert set(failed["eps"]) == {0.4}
    for msg in failed["message"]:
        assert "RuntimeError: deliberate failure" in msg
        assert "rank 0" in msg and "host" in msg and "Traceback" in msg
    ds = sweep.load_xarray(store)
    assert np.isnan(ds["W_c"].sel(eps=0.4)).all()
    assert np.isfinite(ds["W_c"].sel(eps=0.2)).all()
    assert sweep.validate(store) == []
    # retry: without the flag nothing is recomputed, with it only the failed ones
    assert run_campaign(campaign, str(store), compute="sweep.testing:fake_point").computed == 0
    s = run_campaign(campaign, str(store), compute="sweep.testing:fake_point",
                     retry_failed=True)
    assert s.computed == 4
    df = sweep.load(store)
    assert len(df) == 12 and set(df["status"]) == {"converged"}


def test_nan_results_are_failed(tmp_path):
    c = parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\nd_f = [0.005, 0.01]\n")
    run_campaign(c, str(tmp_path / "s.h5"), compute="sweep.testing:nan_point")
    df = sweep.load(tmp_path / "s.h5").set_index("d_f")
    assert df.loc[0.01, "status"] == "failed" and "non-finite" in df.loc[0.01, "message"]
    assert df.loc[0.005, "status"] == "converged"


def test_invalid_points_stored_as_invalid(tmp_path):
    c = parse_campaign("[base]\nh_i = 0.1\nL_sheet = 6.0\n[sweep]\nT = [0.6, 1.2]\n"
                       "dispersion = ['ml', 'ep']\n")
    s = run_campaign(c, str(tmp_path / "s.h5"), compute="sweep.testing:fake_point")
    assert s.counts == {"converged": 3, "invalid": 1}
    df = sweep.load(tmp_path / "s.h5")
    row = df[df["status"] == "invalid"].iloc[0]
    assert (row["T"], row["dispersion"]) == (0.6, "ml") and "cutoff" in row["message"]
    assert sweep.validate(tmp_path / "s.h5") == []


def test_xarray_layout(tmp_path, campaign):
    store = tmp_path / "s.h5"
    small = parse_campaign(TOML.replace("[0.2, 0.4, 0.6]", "[0.2]"), "test.toml")
    run_campaign(small, str(store), compute="sweep.testing:fake_point")
    run_campaign(campaign, str(store), compute="sweep.testing:fake_point", extend=True)
    ds = sweep.load_xarray(store)
    assert dict(ds.sizes) == {"L_x": 2, "eps": 3, "dispersion": 2}
    assert list(ds["eps"].values) == [0.2, 0.4, 0.6]
    assert ds["W_c"].attrs["units"] == "m" and ds["W_c"].attrs["long_name"]
    assert ds["L_x"].attrs["units"] == "m"
    assert json.loads(ds.attrs["campaign"])["sweep"]["eps"] == [0.2, 0.4, 0.6]
    assert ds["alpha_all"].sel(L_x=0.5, eps=0.4, dispersion="ml").item() == fake_point(
        campaign.base.replace(L_x=0.5, eps=0.4, dispersion="ml"))["alpha_all"]


def test_missing_points_are_nan(tmp_path, campaign):
    store = tmp_path / "s.h5"
    part = partial_shard(campaign)
    run_campaign(part, str(store), compute="sweep.testing:fake_point")
    n = len(part.points())
    assert 0 < n < 12
    ds = sweep.load_xarray(store)
    assert int(np.isfinite(ds["W_c"]).sum()) == n
    assert dict(ds.sizes) == {"L_x": 2, "eps": 3, "dispersion": 2}


def test_cli_status_and_export(tmp_path, capsys, campaign):
    store = tmp_path / "s.h5"
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    assert main(["run", str(cfg), "--store", str(store), "--compute",
                 "sweep.testing:raising_point", "--no-bar"]) == 0
    capsys.readouterr()
    assert main(["status", str(store), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["counts"] == {"converged": 8, "failed": 4}
    assert rep["grid_points"] == 12 and rep["remaining"] == 0
    assert len(rep["failures"]) == 4 and "deliberate" in rep["failures"][0]["message"]
    assert len(rep["slowest"]) == 5
    assert main(["status", str(store)]) == 0
    assert "failed" in capsys.readouterr().out
    assert main(["export", str(store), "-o", str(tmp_path / "t.csv")]) == 0
    import pandas as pd

    assert len(pd.read_csv(tmp_path / "t.csv")) == 12
    assert main(["export", str(store), "-o", str(tmp_path / "t.xlsx")]) == 2
    assert main(["validate", str(store)]) == 0
    assert main(["status", str(tmp_path / "none.h5")]) == 3


def test_export_checks_its_output_before_reading(tmp_path, capsys, campaign, monkeypatch):
    """Issue *first hour* 1, 7, 9: ``--out`` is accepted as in the guide, a bad path or a
    missing Parquet engine is one line and exit 2, before the store is read."""
    store = tmp_path / "s.h5"
    run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    capsys.readouterr()
    assert main(["export", str(store), "--out", str(tmp_path / "t.csv")]) == 0
    assert "wrote 12 rows" in capsys.readouterr().out
    assert main(["export", str(tmp_path / "none.h5"), "--out",
                 str(tmp_path / "nodir" / "t.csv")]) == 2  # the path first, not the store
    err = capsys.readouterr().err
    assert "nodir" in err and "does not exist" in err and err.count("\n") == 1
    import sweep.analysis.export

    monkeypatch.setattr(sweep.analysis.export, "parquet_engine", lambda: False)
    assert main(["export", str(store), "-o", str(tmp_path / "t.parquet")]) == 2
    err = capsys.readouterr().err
    assert "floewave[parquet]" in err and err.count("\n") == 1
    assert not (tmp_path / "t.parquet").exists()


def test_in_process_summary_reports_no_master_cpu_share(tmp_path, campaign, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    assert main(["run", str(cfg), "--store", str(tmp_path / "s.h5"), "--compute",
                 "sweep.testing:fake_point", "--no-bar"]) == 0
    out = capsys.readouterr().out
    assert "12 grid points" in out and "computed in-process" in out
    assert "master CPU" not in out


def test_a_requested_stop_is_not_reported_as_an_error(capsys):
    from sweep.cli import _err
    from sweep.errors import ConfigError, Interrupted

    _err(Interrupted("campaign stopped by SIGINT: ... resumable"))
    _err(ConfigError("bad"))
    err = capsys.readouterr().err.splitlines()
    assert err == ["sweep: stopped: campaign stopped by SIGINT: ... resumable",
                   "sweep: error: bad"]


def test_load_profiles_of_failed_points_are_nan_variables(tmp_path, campaign):
    """Points without results are NaN in every profile variable, even when no selected
    point has any (the variables exist, so ds.a works)."""
    from sweep.store.schema import PROFILE_VARS

    store = tmp_path / "f.h5"
    run_campaign(campaign, str(store), compute="sweep.testing:raising_point")  # eps 0.4 fails
    ds = sweep.load_profiles(store, eps=0.4)
    for k in PROFILE_VARS:
        assert k in ds and np.isnan(ds[k].values).all(), k
    assert (ds["status"].values == "failed").all()


def test_load_profiles_by_parameter(tmp_path, campaign):
    """Issue *first hour*: one Dataset of every profile along the swept dimensions and a
    floe dimension; missing points NaN; units on every variable; selection by value."""
    from sweep.store.schema import PROFILE_VARS

    store = tmp_path / "s.h5"
    run_campaign(partial_shard(campaign), str(store), compute="sweep.testing:fake_point")
    df = sweep.load(store)
    ds = sweep.load_profiles(store)
    assert ds["a"].dims == ("L_x", "eps", "dispersion", "floe")
    assert dict(ds.sizes) == {"L_x": 2, "eps": 3, "dispersion": 2, "floe": 12}
    for k, (units, _) in PROFILE_VARS.items():
        assert ds[k].attrs["units"] == units and ds[k].attrs["long_name"]
    # every stored point's profile is where its swept values say, padded with NaN
    for row in df.itertuples():
        one = sweep.load_profile(store, row.hash)
        got = ds["a"].sel(L_x=row.L_x, eps=row.eps, dispersion=row.dispersion).values
        n = one.sizes["floe"]
        np.testing.assert_array_equal(got[:n], one["a"].values)
        assert np.all(np.isnan(got[n:]))
    missing = ds["status"].values == "missing"
    assert missing.sum() == 12 - len(df) > 0
    assert np.all(np.isnan(ds["a"].values[missing]))
    # selection: a scalar drops its dimension, a list keeps it
    first = df.iloc[0]         # a stored point (which ones the shard holds follows the hashes)
    sub = sweep.load_profiles(store, eps=first.eps, dispersion=first.dispersion)
    assert sub["a"].dims == ("L_x", "floe") and float(sub["eps"]) == first.eps
    two = sorted(set(df["eps"]))[:2]
    assert sweep.load_profiles(store, eps=two)["a"].sizes["eps"] == len(two)
    with pytest.raises(sweep.PointNotFoundError, match="not a swept parameter"):
        sweep.load_profiles(store, T=1.2)


def test_load_profile_unknown_hash_is_a_clear_error(tmp_path, campaign):
    store = tmp_path / "s.h5"
    run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    with pytest.raises(sweep.PointNotFoundError) as info:
        sweep.load_profile(store, "0123456789ab")
    assert str(info.value).startswith(f"{store}: 0 stored points have a hash")
    assert isinstance(info.value, KeyError)  # callers catching KeyError still do


def test_table_types(tmp_path, campaign):
    """Times are datetimes, status and dispersion categoricals, integers stay integers."""
    import pandas as pd

    store = tmp_path / "s.h5"
    run_campaign(partial_shard(campaign), str(store), compute="sweep.testing:fake_point")
    df = sweep.load(store)
    assert str(df["start_time"].dtype).startswith("datetime64") and df["end_time"].dt.tz
    assert isinstance(df["status"].dtype, pd.CategoricalDtype)
    assert isinstance(df["dispersion"].dtype, pd.CategoricalDtype)
    assert (df["status"] == "converged").all()
    ds = sweep.load_xarray(store)
    assert ds["n_floes"].dtype == np.int64 and ds["iterations"].dtype == np.int64
    assert (ds["n_floes"].values == -1).sum() == 12 - len(df)


def test_status_names_the_swept_values_and_lists_runs(tmp_path, capsys):
    """Issue *first hour* 6, 7: not-converged and failed points are traceable by their
    parameters; the runs section the guide promises is printed."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    store = tmp_path / "s.h5"
    assert main(["run", str(cfg), "--store", str(store), "--compute",
                 "sweep.testing:raising_point", "--no-bar"]) == 0
    capsys.readouterr()
    assert main(["status", str(store)]) == 0
    out = capsys.readouterr().out
    assert "failed / invalid:" in out and "L_x=" in out and "dispersion=" in out
    assert "runs:\n  0: " in out and "12 points stored: complete" in out
    assert main(["status", str(store), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    f = rep["failures"][0]
    assert set(f["swept"]) == {"L_x", "eps", "dispersion"}
    assert rep["runs"][0]["stored"] == 12 and rep["slowest"][0]["swept"]
    assert rep["not_converged"] == []


def test_status_lists_not_converged_points(tmp_path, capsys):
    store = tmp_path / "s.h5"
    small = parse_campaign(TOML.replace("[0.2, 0.4, 0.6]", "[0.2, 0.8]"), "test.toml")
    run_campaign(small, str(store), compute="sweep.testing:power_point")
    capsys.readouterr()
    assert main(["status", str(store)]) == 0
    out = capsys.readouterr().out
    block = out.split("not converged (error bars above their targets")[1].split("slowest:")[0]
    assert block.count("eps=0.8") == 4 and "eps=0.2" not in block


REAL_TINY = """\
[base]
L_sheet = 2.0
n0 = 1
nT = 1
max_iterations = 2
[sweep]
L_x = [0.5]
eps = [0.2, 0.6]
[run]
progress_interval = 100.0
"""


def test_kernels_are_compiled_before_the_clock_starts(tmp_path, capsys):
    """Issue *first hour* 4: the kernels are compiled (or loaded) on the workers first,
    reported on a line of their own; fake compute functions are not warmed up."""
    summary = run_campaign(parse_campaign(REAL_TINY, "t.toml"), str(tmp_path / "s.h5"),
                           progress_bar=False)
    err = capsys.readouterr().err
    lines = err.splitlines()
    ready = [i for i, ln in enumerate(lines) if "kernels ready in" in ln]
    start = [i for i, ln in enumerate(lines) if "points to compute" in ln]
    assert len(ready) == 1 and ready[0] < start[0], err
    assert "1 worker (1 kernel variant" in lines[ready[0]]
    assert summary.warm_up > 0
    run_campaign(parse_campaign(TOML, "t.toml"), str(tmp_path / "f.h5"),
                 compute="sweep.testing:fake_point", progress_bar=False)
    assert "kernels ready" not in capsys.readouterr().err
