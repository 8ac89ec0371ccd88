"""sweep.store.reader: one parser of the stored layout; a row whose config_json no longer
hashes to its hash is caught by load, merge and validate."""
from __future__ import annotations

import h5py
import numpy as np
import pytest

import sweep
from sweep.errors import StoreCorruptedError, StoreError
from sweep.store import reader
from sweep.store.cells import text as stored_text
from sweep.store.merge import merge

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4, 0.6]\n"


@pytest.fixture
def store(tmp_path, campaign):
    path = tmp_path / "s.h5"
    sweep.run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    return path


def corrupt(path, row=1):
    """Alter one stored row's config_json (eps 0.4 -> 0.45) in place; return its hash."""
    with h5py.File(path, "r+", locking=False) as f:
        table = f["table"]
        text = stored_text(table["config_json"][row])
        assert '"eps":0.4' in text
        table["config_json"][row] = text.replace('"eps":0.4', '"eps":0.45')
        return stored_text(table["hash"][row])


def test_reader_parses_the_layout(store, campaign):
    with reader.open_file(store) as f:
        cols = reader.table_columns(f)
        assert reader.n_rows(f) == 3 and set(cols) == {c.name for c in sweep.store.schema.COLUMNS}
        assert all(isinstance(h, str) for h in cols["hash"])
        assert reader.model_version(f) == campaign.definition()["model_version"]
        records = list(reader.iter_records(f))
        assert [r.hash for r in records] == list(cols["hash"])
        profiles, history = reader.profile_group(f, records[0].hash)
        np.testing.assert_array_equal(records[0].profiles["a"], profiles["a"])
        assert history.size and reader.profile_group(f, "0" * 64) is None
        assert reader.hash_mismatches(cols["hash"], cols["config_json"],
                                      reader.model_version(f)) == []
    assert stored_text(b"caf\xc3\xa9") == "café" and stored_text("x") == "x"


def test_load_refuses_a_row_that_no_longer_hashes(store):
    h = corrupt(store)
    with pytest.raises(StoreCorruptedError, match=h) as err:
        sweep.load(store)
    assert err.value.hashes == [h] and isinstance(err.value, StoreError)
    assert "altered after it was written" in str(err.value)
    with pytest.raises(StoreCorruptedError):
        sweep.load_xarray(store)


def test_validate_reports_a_row_that_no_longer_hashes(store):
    assert sweep.validate(store) == []
    h = corrupt(store)
    problems = sweep.validate(store)
    assert len(problems) == 1 and problems[0].startswith("/table/config_json[1]:")
    assert h in problems[0]


def test_merge_refuses_a_row_that_no_longer_hashes(store, tmp_path):
    out = tmp_path / "merged.h5"
    merge(out, [store])
    assert len(sweep.load(out)) == 3
    h = corrupt(store)
    fresh = tmp_path / "fresh.h5"
    with pytest.raises(StoreCorruptedError, match=h):
        merge(fresh, [store])
    assert not fresh.exists()  # refused before anything was written
    with pytest.raises(StoreCorruptedError):
        merge(out, [store])
    assert len(sweep.load(out)) == 3 and sweep.validate(out) == []


def test_status_command_exits_3_on_a_corrupted_store(store, run_main):
    h = corrupt(store)
    proc = run_main(sweep.cli.main, ["status", store])
    assert proc.returncode == 3, (proc.stdout, proc.stderr)
    assert h in proc.stderr


def test_an_altered_swept_column_is_caught(store, tmp_path):
    """A row whose swept column (what users select and group by) was edited while its
    config_json and hash were left alone is caught too: load raises, validate lists it,
    merge refuses (a reviewer's case: table/eps[1] = 0.9 used to pass)."""
    with h5py.File(store, "r+", locking=False) as f:
        assert f["table/eps"][1] == 0.4
        f["table/eps"][1] = 0.9
        h = stored_text(f["table/hash"][1])
    with pytest.raises(StoreCorruptedError, match=h):
        sweep.load(store)
    problems = sweep.validate(store)
    assert len(problems) == 1 and "swept columns" in problems[0] and h in problems[0]
    with pytest.raises(StoreCorruptedError, match=h):
        merge(tmp_path / "fresh.h5", [store])
