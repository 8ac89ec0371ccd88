"""Exported tables read back as a store reads: ``sweep export`` to .csv.gz / .csv, and
``sweep.load`` of a table or of a directory of shard tables (a campaign shipped without its
store, e.g. ``results/herman2019``)."""
import gzip

import numpy as np
import pytest

import sweep
from sweep.cli import main
from sweep.errors import StoreCorruptedError, StoreError
from tests.sweep.helpers import split_shards
from tests.sweep.test_run import TOML  # noqa: F401 (the grid of the campaign fixture)


def _same(a, b) -> None:
    assert list(a.columns) == list(b.columns)
    assert (a.dtypes == b.dtypes).all(), a.dtypes[a.dtypes != b.dtypes]
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if a[c].dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), c      # bit for bit
        else:
            assert (a[c].astype(str).to_numpy() == b[c].astype(str).to_numpy()).all(), c


@pytest.mark.parametrize("name", ["t.csv.gz", "t.csv"])
def test_an_exported_table_loads_as_the_store(tmp_path, capsys, campaign, name):
    store = tmp_path / "s.h5"
    sweep.run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    assert main(["export", str(store), "-o", str(tmp_path / name)]) == 0
    assert "wrote 12 rows" in capsys.readouterr().out
    if name.endswith(".gz"):
        with gzip.open(tmp_path / name, "rt") as fh:
            assert fh.readline().startswith("hash,")
    _same(sweep.load(store), sweep.load(tmp_path / name))


def test_shard_tables_load_as_one_campaign(tmp_path, campaign):
    """Each shard stored, exported, and the directory of tables read as one table: every
    point once, as the stores hold them; a table given twice, or a row altered, is refused
    with the point named."""
    out = tmp_path / "results"
    out.mkdir()
    frames = []
    for k, part in enumerate(split_shards(campaign)):
        store = tmp_path / f"s{k}.h5"
        sweep.run_campaign(part, str(store), compute="sweep.testing:fake_point")
        assert main(["export", str(store), "-o", str(out / f"shard{k}.csv.gz")]) == 0
        frames.append(sweep.load(store))
    df = sweep.load(out)
    assert len(df) == 12 and df["hash"].is_unique
    assert list(df.attrs["files"]) == sorted(f.name for f in out.iterdir())
    import pandas as pd
    whole = pd.concat(frames, ignore_index=True)
    _same(whole.astype({"status": df["status"].dtype, "dispersion": df["dispersion"].dtype}),
          df)
    (out / "copy.csv.gz").write_bytes((out / "shard0.csv.gz").read_bytes())
    with pytest.raises(StoreError, match="appears 2 times .*copy.csv.gz, shard0.csv.gz"):
        sweep.load(out)
    (out / "copy.csv.gz").unlink()
    bad = df.copy()
    bad.loc[0, "config_json"] = bad.loc[0, "config_json"].replace('"L_sheet":6.0',
                                                                  '"L_sheet":7.0')
    bad.to_csv(tmp_path / "bad.csv", index=False)
    with pytest.raises(StoreCorruptedError, match=str(bad.loc[0, "hash"])):
        sweep.load(tmp_path / "bad.csv")
    (tmp_path / "empty").mkdir()
    with pytest.raises(StoreError, match="no exported table"):
        sweep.load(tmp_path / "empty")


def test_units_are_shared_not_copied_into_every_derived_frame(tmp_path, campaign):
    """pandas deep-copies ``attrs`` into every frame derived from a table (a column, a
    groupby group): the units and long names are one read-only mapping shared by all
    (as plain dicts they were a third of ``sweep report``'s time)."""
    import copy
    store = tmp_path / "s.h5"
    sweep.run_campaign(campaign, str(store), compute="sweep.testing:fake_point")
    df = sweep.load(store)
    sub = df[df["eps"] > 0.2]
    groups = [g for _, g in df.groupby("L_x")]
    assert sub.attrs["units"] is df.attrs["units"] is groups[0].attrs["units"]
    assert copy.deepcopy(df.attrs)["long_name"] is df.attrs["long_name"]
    assert df.attrs["units"]["W_c"] == "m" and dict(df.attrs["units"])["W_c"] == "m"
    with pytest.raises(TypeError, match="copy them"):
        sub.attrs["units"]["W_c"] = "km"
    assert df.attrs["units"]["W_c"] == "m"
