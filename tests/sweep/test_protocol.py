"""sweep.protocol: the messages between master and workers are frozen, picklable types."""
from __future__ import annotations

import dataclasses
import os
import pickle

import numpy as np
import pytest

from sweep.protocol import Kind, Outcome, Task, WarmUp, WorkerFailure, plain


def test_task_is_frozen_and_carries_no_compute_key():
    t = Task("ab" * 32, {"eps": 0.2}, 5.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        t.timeout = 1.0  # type: ignore[misc]
    assert [f.name for f in dataclasses.fields(Task)] == ["hash", "config", "timeout"]
    assert Task("h", {}).timeout == 0.0


def test_messages_survive_pickling_as_mpi_sends_them():
    out = Outcome("h", "converged", scalars={"W_c": 1.5}, profiles={"a": np.ones(3)},
                  residual_history=np.array([0.5, 0.1]), host="x", rank=2, pid=9)
    for msg in (Task("h", {"eps": 0.4}, 2.0), WarmUp(({"eps": 0.4},)),
                WorkerFailure(1, "x", "boom", "tb")):
        assert pickle.loads(pickle.dumps(msg)) == msg
    back = pickle.loads(pickle.dumps((Kind.RESULT, out)))
    assert back[0] is Kind.RESULT and back[1].rank == 2
    assert np.array_equal(back[1].profiles["a"], np.ones(3))


def test_kinds_compare_and_print_as_their_values():
    assert Kind.RESULT == "result" and Kind.ERROR == "error"
    assert {k.value for k in Kind} == {"ready", "error", "result", "warm"}
    assert Kind("warm") is Kind.WARM


def test_known_outcome_is_stamped_by_the_master():
    out = Outcome.known("h" * 64, "invalid", "cutoff")
    assert (out.status, out.message, out.rank, out.pid) == ("invalid", "cutoff", 0,
                                                            os.getpid())
    assert out.start_time == out.end_time and out.start_time.endswith("+00:00")
    assert out.wall_time == 0.0 and out.scalars == {} and out.residual_history.size == 0


def test_without_results_keeps_where_and_when_drops_the_results():
    out = Outcome("h", "converged", scalars={"W_c": 1.0}, profiles={"a": np.ones(2)},
                  residual_history=np.ones(3), host="x", rank=3, pid=7, start_time="t0",
                  end_time="t1", wall_time=2.0)
    failed = out.without_results("failed", "why")
    assert (failed.status, failed.message, failed.scalars, failed.profiles) == (
        "failed", "why", {}, {})
    assert failed.residual_history.size == 0
    assert (failed.host, failed.rank, failed.pid, failed.start_time, failed.wall_time) == (
        "x", 3, 7, "t0", 2.0)
    assert out.status == "converged"  # the original is unchanged


def test_plain_turns_numpy_into_python():
    assert plain(np.float64(1.5)) == 1.5 and type(plain(np.int64(3))) is int
    assert plain(np.arange(3)) == [0, 1, 2] and plain("x") == "x"
