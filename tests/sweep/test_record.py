"""sweep.store.record: one Record per finished point, built once from (point, outcome)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from sweep.errors import UnstorableError
from sweep.protocol import Outcome, plain
from sweep.store.journal import decode
from sweep.store.record import Record
from sweep.testing import fake_point

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"


def outcome(point, **changes):
    """A worker's outcome of ``point`` computed by ``fake_point`` (as compute_point)."""
    data = fake_point(point.config)
    profiles = {k: np.asarray(v) for k, v in data.items()
                if np.ndim(v) == 1 and k != "residual_history"}
    scalars = {k: plain(v) for k, v in data.items() if np.ndim(v) == 0}
    out = {"hash": point.hash, "status": "converged", "message": "", "scalars": scalars,
           "profiles": profiles, "residual_history": data["residual_history"],
           "host": "h", "rank": 3, "pid": 7, "start_time": "t0", "end_time": "t1",
           "wall_time": 0.5}
    out.update(changes)
    return Outcome(**out)


def provenance(rank, mode):
    return json.dumps({"rank": rank, "kernel_mode": mode})


def test_from_outcome_holds_row_datasets_and_provenance(campaign):
    p = campaign.points()[0]
    rec = Record.from_outcome(p, outcome(p), provenance=provenance)
    assert rec.hash == p.hash and rec.status == "converged"
    assert rec.row["eps"] == p.config.eps and rec.row["rank"] == 3
    assert rec.row["provenance"] == provenance(3, "fake")
    assert rec.row["model_wall_time"] == 1e-3 and rec.row["wall_time"] == 0.5
    assert rec.profiles["a"].dtype == np.float64 and rec["profiles"] is rec.profiles
    assert list(rec) == ["row", "profiles", "residual_history"]
    # swept values first, then the scalar results, then the bookkeeping
    keys = list(rec.row)
    assert keys[:7] == ["L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion"]
    assert keys[-2:] == ["config_json", "provenance"]


def test_a_scalar_of_the_wrong_kind_makes_a_failed_record(campaign):
    p = campaign.points()[0]
    out = outcome(p)
    out.scalars["W_c"] = "wide"
    rec = Record.from_outcome(p, out, provenance=provenance)
    assert rec.status == "failed" and "does not fit the schema: W_c = 'wide'" in rec.row[
        "message"]
    assert rec.profiles == {} and rec.residual_history.size == 0
    assert "W_c" not in rec.row
    assert rec.row["provenance"] == provenance(3, "fake")  # the worker's kernel mode


def test_an_unstorable_value_makes_a_failed_record(campaign):
    p = campaign.points()[0]
    out = outcome(p)
    out.scalars["iterations"] = 10 ** 20  # an int, but beyond 64 bits
    rec = Record.from_outcome(p, out, provenance=provenance)
    assert rec.status == "failed"
    assert rec.row["message"].startswith("the result cannot be stored: iterations")
    assert rec.row["provenance"] == provenance(3, "")
    with pytest.raises(UnstorableError, match="64-bit"):
        Record.coerce({"row": {"hash": p.hash, "iterations": 10 ** 20}})
    with pytest.raises(UnstorableError, match="no 'hash'"):
        Record.coerce({"row": {"status": "converged"}})


def test_known_outcome_and_journal_line(campaign):
    p = campaign.points()[1]
    rec = Record.from_outcome(p, Outcome.known(p.hash, "invalid", "cutoff"))
    assert rec.status == "invalid" and rec.row["message"] == "cutoff"
    assert rec.row["rank"] == 0 and rec.row["wall_time"] == 0.0
    assert np.isnan(rec.row["model_wall_time"]) and "provenance" not in rec.row
    stamped = rec.stamped(5, 2)
    assert list(stamped.row)[-2:] == ["seq", "run"] and "seq" not in rec.row
    obj, checked = decode(stamped.journal_line())
    assert checked and obj["row"]["seq"] == 5 and obj["row"]["run"] == 2
    assert obj["row"]["hash"] == p.hash and obj["profiles"] == {}
    # a coerced Record is not converted again; a dict is
    assert Record.coerce(stamped) is stamped
    again = Record.coerce(obj)
    assert again.row["hash"] == p.hash and again.normal

