"""Columns derived at load time (sweep.store.schema.DERIVED): a_end_rel = a_end / a0 and its
standard error, in sweep.load's DataFrame and in load_xarray; the store is unchanged."""
from __future__ import annotations

import h5py
import numpy as np
import pytest

import sweep
from sweep.store.schema import COLUMNS, DERIVED, SCHEMA_VERSION

TOML = "[base]\nL_sheet = 6.0\n[sweep]\na0 = [0.0125, 0.025]\neps = [0.2, 0.4]\n"


@pytest.fixture
def store(tmp_path, campaign):
    path = tmp_path / "s.h5"
    sweep.run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    with h5py.File(path, "r+", locking=False) as f:  # fake_point has no error bars
        n = f["table"].attrs["n_rows"]
        f["table"]["a_end_stderr"][:n] = np.arange(1, n + 1) * 1e-4
    return path


def test_a_end_rel_is_a_end_over_a0(store):
    df = sweep.load(store)
    np.testing.assert_array_equal(df["a_end_rel"], df["a_end"] / df["a0"])
    np.testing.assert_array_equal(df["a_end_rel_stderr"], df["a_end_stderr"] / df["a0"])
    assert (df["a_end_rel"] < 1).all() and (df["a_end_rel"] > 0).all()
    cols = list(df.columns)
    assert cols.index("a_end_rel") == cols.index("a_end") + 1
    assert cols.index("a_end_rel_stderr") == cols.index("a_end_stderr") + 1
    assert df.attrs["units"]["a_end_rel"] == "1"
    assert "a_end / a0" in df.attrs["long_name"]["a_end_rel"]


def test_a_end_rel_in_xarray(store):
    ds = sweep.load_xarray(store)
    np.testing.assert_allclose(ds["a_end_rel"], ds["a_end"] / ds["a0"])
    np.testing.assert_allclose(ds["a_end_rel_stderr"], ds["a_end_stderr"] / ds["a0"])
    assert ds["a_end_rel"].attrs["units"] == "1"


def test_derived_columns_are_not_stored(store):
    with h5py.File(store, "r", locking=False) as f:
        assert not {c.name for c in DERIVED} & set(f["table"])
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION
    assert not {c.name for c in DERIVED} & {c.name for c in COLUMNS}
    assert sweep.validate(store) == []


def test_xarray_and_profile_attributes_are_the_declared_ones(store):
    """Every model variable of load_xarray and load_profile carries the unit and long name
    floewave.outputs declares for it."""
    from floewave.outputs import OUTPUTS

    ds = sweep.load_xarray(store)
    h = sweep.load(store)["hash"].iloc[0]
    prof = sweep.load_profile(store, h)
    checked = 0
    for o in OUTPUTS:
        name = o.name if o.dims else o.column    # None: the store's own status column
        for data in (ds, prof):
            if name is not None and name in data:
                assert data[name].attrs["units"] == o.unit, name
                assert data[name].attrs["long_name"] == o.long_name, name
                checked += 1
    assert checked >= 40
