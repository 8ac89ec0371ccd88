"""Ensembles in the store (schema 3): columns, per-replica datasets, readers, migration."""
from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.store.schema import REPLICA_VARS, SCHEMA_VERSION, profile_path

TOML = """
[base]
L_sheet = 9.0
L_x = 1.5
T = 1.2
a0 = 0.02
dispersion = "ep"
n0 = 2
nT = 1
max_iterations = 3
noise_window = 2
n_average = 2
replicas = 3
placement = "random"
seed = 4
[sweep]
eps = [0.4, 0.8]
d_f = [0.005]
"""


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("ens") / "e.h5"
    summary = run_campaign(parse_campaign(TOML, "e.toml"), str(path))
    assert summary.computed == 2
    return path


def test_ensemble_columns_and_replica_datasets(store):
    assert sweep.validate(store) == []
    df = sweep.load(store)
    assert (df["replicas"] == 3).all()
    assert df["status"].isin(["converged", "converged_noisy", "not_converged"]).all()
    assert np.isfinite(df["alpha_all_stderr"]).all() and (df["alpha_all_stderr"] > 0).all()
    assert np.isfinite(df["a_end_stderr"]).all()
    assert df["W_c_n"].between(0, 3).all()
    ds = sweep.load_profile(store, df["hash"].iloc[0])
    assert ds.sizes["replica"] == 3
    for name, (_, _, shape) in REPLICA_VARS.items():
        dims = tuple({"R": "replica", "N_f": "floe"}[d] for d in shape)
        assert ds[name].dims == dims, name
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"]
    # the stored profile is the replica mean of the stored per-replica profiles
    np.testing.assert_allclose(ds["S_sd"], ds["S_sd_replicas"].mean("replica"), rtol=1e-12)
    W = ds["W_c_replicas"].values
    row = df.iloc[0]
    if row["compact_zone"] != "none" and np.isfinite(W).sum() >= 1:
        assert row["W_c"] == pytest.approx(np.nanmean(W))
    xs = sweep.load_xarray(store)
    assert "W_c_stderr" in xs and xs["W_c_stderr"].attrs["units"] == "m"


def test_a_damaged_replica_dataset_is_a_validation_problem(store, tmp_path):
    import shutil
    path = tmp_path / "d.h5"
    shutil.copy(store, path)
    h = sweep.load(path)["hash"].iloc[0]
    with h5py.File(path, "r+") as f:
        g = f[profile_path(h)]
        del g["gap_mean_replicas"]
        g["gap_mean_replicas"] = np.zeros((2, 6))
    problems = sweep.validate(path)
    assert any("gap_mean_replicas" in p and "(3, 6)" in p for p in problems), problems


def test_schema_2_store_read_as_single_trajectories_and_migrated(store, tmp_path):
    """A version-2 store (no ensemble columns, no per-replica datasets) reads with
    replicas = 1 and NaN standard errors, and a writer migrates it to version 3."""
    import shutil
    path = tmp_path / "v2.h5"
    shutil.copy(store, path)
    new_cols = [n for n, v in sweep.store.schema.ADDED_IN.items() if v == 3]
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = 2
        for name in new_cols:
            del f["table"][name]
        for hh in f["profiles"]:
            for h in f["profiles"][hh]:
                for name in REPLICA_VARS:
                    del f["profiles"][hh][h][name]
    assert sweep.validate(path) == []
    old = sweep.load(path)
    assert (old["replicas"] == 1).all() and old["W_c_stderr"].isna().all()
    assert (old["W_c_n"] == -1).all()
    ds = sweep.load_profile(path, old["hash"].iloc[0])
    assert "replica" not in ds.dims and "W_c_replicas" not in ds
    run_campaign(parse_campaign(TOML, "e.toml"), str(path))      # a writer: migrated
    with h5py.File(path, "r") as f:
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION == 5
        assert all(name in f["table"] for name in new_cols)
    assert sweep.validate(path) == []
    new = sweep.load(path)
    assert (new["replicas"] == 1).all() and (new["W_c_n"] == -1).all()
    assert new["hash"].tolist() == old["hash"].tolist()
    assert math.isnan(new["alpha_all_stderr"].iloc[0])


def test_a_store_of_an_older_model_version_is_refused_naming_both_versions(store, tmp_path):
    """A store written by model version 3 (schema 2) holds none of this model's points:
    ``sweep run`` refuses it (exit 3) naming both model and schema versions, and leaves
    it untouched and readable."""
    import json
    import shutil

    import floewave
    from sweep.cli import main
    from sweep.identity import canonical_json, sha256_hex
    path = tmp_path / "old.h5"
    shutil.copy(store, path)
    with h5py.File(path, "r+") as f:
        camp = json.loads(f.attrs["campaign_json"])
        camp["model_version"] = "3"
        f.attrs["campaign_json"] = canonical_json(camp)
        f.attrs["campaign_hash"] = sha256_hex(canonical_json(camp))
        f.attrs["schema_version"] = 2
    (tmp_path / "e.toml").write_text(TOML)
    before = path.read_bytes()
    with pytest.raises(sweep.CampaignMismatchError,
                       match=r"model version 3 \(store schema 2\).*model version "
                             + floewave.MODEL_VERSION + rf" \(schema {SCHEMA_VERSION}\)"):
        run_campaign(parse_campaign(TOML, "e.toml"), str(path))
    assert main(["run", str(tmp_path / "e.toml"), "--store", str(path)]) == 3
    assert path.read_bytes() == before
    assert len(sweep.load(path)) == 2
