"""Per-point profiles in a netCDF file (``sweep export --profiles``; issue 47's shipped
profiles): the values of the store, CF attributes, readable by xarray without sweep,
shards read as one, bad input refused before anything is written."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import run_campaign
from sweep.analysis.export import export_profiles
from sweep.analysis.profiles_file import PROFILE_FILE_VARS
from sweep.cli import main
from sweep.errors import PointNotFoundError, StoreError
from tests.sweep.test_run import TOML  # the in-process campaign: 12 points, eps 0.4 fails


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """12 points, the four at eps 0.4 failed (no profiles)."""
    from sweep import parse_campaign

    path = tmp_path_factory.mktemp("prof") / "s.h5"
    run_campaign(parse_campaign(TOML, "t.toml"), str(path),
                 compute="sweep.testing:raising_point")
    return path


def test_the_file_holds_the_stores_profiles(store, tmp_path):
    out = tmp_path / "p.nc"
    assert export_profiles(store, out) == 8            # the 4 failed points have none
    df = sweep.load(store)
    ds = xr.open_dataset(out, engine="h5netcdf").load()
    assert ds.attrs["Conventions"] == "CF-1.10" and "model version" in ds.attrs["source"]
    assert list(ds["hash"].values) == [h for h, s in zip(df["hash"], df["status"],
                                                         strict=True) if s != "failed"]
    for k, (units, long_name) in PROFILE_FILE_VARS.items():
        assert ds[k].dtype == np.float32 and ds[k].attrs["units"] == units, k
        assert ds[k].attrs["long_name"] == long_name
    assert ds["x"].attrs["units"] == "m" and ds["L_x"].attrs["units"] == "m"
    assert ds.sizes["floe"] == 12                          # L_x 0.5 on a 6 m sheet
    for i, h in enumerate(ds["hash"].values):
        one = sweep.load_profile(store, h)
        n = one.sizes["floe"]
        a0 = float(df.set_index("hash").loc[h, "a0"])
        assert int(ds["n_floes"][i]) == n
        np.testing.assert_array_equal(ds["a_rel"].values[i, :n],
                                      (one["a"].values / a0).astype(np.float32))
        np.testing.assert_array_equal(ds["a_rel_stderr"].values[i, :n],
                                      (one["a_stderr"].values / a0).astype(np.float32))
        np.testing.assert_array_equal(ds["x"].values[i, :n],
                                      one["x_mean"].values.astype(np.float32))
        np.testing.assert_array_equal(ds["gap_mean"].values[i, :n],
                                      one["gap_mean"].values.astype(np.float32))
        assert np.isnan(ds["a_rel"].values[i, n:]).all()
        row = df.set_index("hash").loc[h]
        assert float(ds["L_x"][i]) == row["L_x"] and str(ds["dispersion"][i].values) == \
            row["dispersion"]


def test_xarray_reads_it_without_sweep_or_floewave(store, tmp_path):
    out = tmp_path / "p.nc"
    export_profiles(store, out)
    code = ("import sys; sys.modules['sweep'] = None; sys.modules['floewave'] = None\n"
            "import xarray as xr\n"
            f"ds = xr.open_dataset({str(out)!r})\n"
            "p = ds.isel(point=0)\n"
            "print(ds.sizes['point'], float(p.a_rel[0]), ds.a_rel.attrs['units'])\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    got = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, cwd=tmp_path, check=True).stdout.split()
    first = xr.open_dataset(out, engine="h5netcdf")
    assert got == ["8", repr(float(first["a_rel"].values[0, 0])), "1"]


def test_load_profiles_reads_a_directory_of_shards_and_selects(store, tmp_path):
    df = sweep.load(store)
    ok = df[df["status"] != "failed"]
    half = [ok.iloc[:3], ok.iloc[3:]]
    folder = tmp_path / "grid" / "profiles"
    folder.mkdir(parents=True)
    for i, part in enumerate(half):
        export_profiles(store, folder / f"profiles-{i}-of-2.nc", part)
    ds = sweep.load_profiles(tmp_path / "grid")        # the campaign folder, or profiles/
    assert list(ds["hash"].values) == list(ok["hash"])
    assert ds.attrs["source_files"] == "profiles-0-of-2.nc, profiles-1-of-2.nc"
    one = sweep.load_profiles(folder, L_x=1.5, dispersion="ml")
    assert set(one["L_x"].values) == {1.5} and set(one["dispersion"].values) == {"ml"}
    assert one.sizes["point"] == len(ok[(ok["L_x"] == 1.5) & (ok["dispersion"] == "ml")])
    by_hash = sweep.load_profiles(folder, hash=ok["hash"].iloc[4][:12])
    assert list(by_hash["hash"].values) == [ok["hash"].iloc[4]]
    with pytest.raises(PointNotFoundError, match="'T_p' is not a parameter"):
        sweep.load_profiles(folder, T_p=1.0)
    with pytest.raises(PointNotFoundError, match="no point with profiles matches"):
        sweep.load_profiles(folder, eps=0.4)             # the failed points: no profiles
    with pytest.raises(StoreError, match="no profiles file"):
        sweep.load_profiles(tmp_path / "grid" / "nothing.nc")


def test_export_cli_refuses_bad_input_and_writes_nothing(store, tmp_path, capsys):
    table = tmp_path / "t.csv"
    assert main(["export", str(store), "--output", str(table),
                 "--profiles", str(tmp_path / "p.txt")]) == 2
    assert "expected a .nc file name" in capsys.readouterr().err
    assert not table.exists() and not (tmp_path / "p.txt").exists()
    assert main(["export", str(store)]) == 2
    assert "give --output FILE" in capsys.readouterr().err
    assert main(["export", str(store), "--output", str(table),
                 "--profiles", str(tmp_path / "p.nc")]) == 0
    assert table.exists() and (tmp_path / "p.nc").exists()
    assert "profiles of 8 points" in capsys.readouterr().out


def test_two_exports_of_one_campaign_in_a_folder_are_refused(store, tmp_path):
    folder = tmp_path / "profiles"
    folder.mkdir()
    export_profiles(store, folder / "a.nc")
    export_profiles(store, folder / "b.nc")
    with pytest.raises(StoreError, match="appears 2 times across the profile files"):
        sweep.load_profiles(folder)


def test_a_store_without_profiles_writes_nothing(tmp_path, capsys):
    from sweep import parse_campaign
    failed = tmp_path / "f.h5"
    run_campaign(parse_campaign(TOML.replace("eps = [0.2, 0.4, 0.6]", "eps = [0.4]"),
                                "t.toml"), str(failed), compute="sweep.testing:raising_point")
    out = tmp_path / "p.nc"
    with pytest.raises(StoreError, match="no point has profiles"):
        export_profiles(failed, out)
    assert not out.exists() and not (tmp_path / "p.nc.part").exists()
    assert main(["export", str(failed), "--profiles", str(out), "--output",
                 str(tmp_path / "t.csv")]) != 0
    assert not out.exists() and not (tmp_path / "t.csv").exists()
