"""sweep.store.writer: the HDF5 side of a store: a new file has the schema's layout, written
points are committed by n_rows, rows beyond it and their profiles are dropped on prepare."""
from __future__ import annotations

import h5py
import numpy as np

from sweep.protocol import Outcome
from sweep.store.cells import text
from sweep.store.record import Record
from sweep.store.schema import COLUMNS, FORMAT, PROFILE_VARS, SCHEMA_VERSION, profile_path
from sweep.store.validate import validate
from sweep.store.writer import H5Writer
from sweep.testing import fake_point

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4, 0.6]\n"


def records(campaign):
    out = []
    for seq, p in enumerate(campaign.points()):
        data = fake_point(p.config)
        o = Outcome(p.hash, "converged", scalars={"W_c": data["W_c"],
                                                  "n_floes": data["n_floes"]},
                    profiles={k: np.asarray(data[k]) for k in PROFILE_VARS},
                    residual_history=np.asarray(data["residual_history"]), host="h")
        out.append(Record.from_outcome(p, o).stamped(seq, 0))
    return out


def test_a_new_store_has_the_schema_layout(tmp_path, campaign):
    w = H5Writer.create(tmp_path / "s.h5", campaign)
    w.close()
    with h5py.File(tmp_path / "s.h5", "r") as f:
        assert f.attrs["schema_version"] == SCHEMA_VERSION and text(f.attrs["format"]) == FORMAT
        assert set(f["table"]) == {c.name for c in COLUMNS}
        assert f["table"].attrs["n_rows"] == 0 and "profiles" in f and "runs" in f
    assert validate(tmp_path / "s.h5") == []


def test_written_points_are_committed_and_read_back(tmp_path, campaign):
    recs = records(campaign)
    w = H5Writer.create(tmp_path / "s.h5", campaign)
    w.prepare()
    w.write_many(recs)
    w.durable()
    assert w.rows == {r.hash: i for i, r in enumerate(recs)}
    assert w.status_of(recs[1].hash) == "converged"
    w.trim()
    w.close()
    with h5py.File(tmp_path / "s.h5", "r") as f:
        assert f["table"].attrs["n_rows"] == 3 and f["table/hash"].shape == (3,)
        assert np.array_equal(f[profile_path(recs[2].hash)]["a"][...],
                              recs[2].profiles["a"])
    assert validate(tmp_path / "s.h5") == []


def test_prepare_drops_what_was_not_committed(tmp_path, campaign):
    recs = records(campaign)
    w = H5Writer.create(tmp_path / "s.h5", campaign)
    w.prepare()
    w.write_many(recs[:2])
    w.file["table"].attrs["n_rows"] = 1  # as if killed before the second commit landed
    w.close()
    w = H5Writer.open(tmp_path / "s.h5")
    assert w.prepare() == 1  # the second point's profile group was an orphan
    assert list(w.rows) == [recs[0].hash]
    assert profile_path(recs[1].hash) not in w.file
    w.write_many([recs[2]])  # the next row goes where the dropped one was
    assert w.rows == {recs[0].hash: 0, recs[2].hash: 1}
    w.close()


def test_a_point_written_again_replaces_its_row(tmp_path, campaign):
    recs = records(campaign)
    w = H5Writer.create(tmp_path / "s.h5", campaign)
    w.prepare()
    w.write_many(recs[:1])
    again = Record(dict(recs[0].row, status="converged_noisy", seq=9), recs[0].profiles,
                   recs[0].residual_history)
    w.write_many([Record.coerce(again)])
    assert w.rows == {recs[0].hash: 0} and w.status_of(recs[0].hash) == "converged_noisy"
    w.close()
