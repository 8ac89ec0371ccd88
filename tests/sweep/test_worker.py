"""sweep.run.worker and sweep.run.compute: a worker answers each message of the protocol,
and computing a point never raises for the point's fault."""
from __future__ import annotations

import numpy as np
import pytest

from sweep.errors import ConfigError
from sweep.protocol import (TAG_RESULT, TAG_TASK, Kind, Outcome, Packed, Task, WarmUp,
                            WorkerFailure)
from sweep.run.compute import compute_point, resolve_compute
from sweep.run.worker import worker_loop
from sweep.testing import fake_point, nan_point, raising_point

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\nd_f = [0.005, 0.01]\n"


class FakeComm:
    """Rank 1 of a two-rank world: tasks from a list, replies recorded."""

    def __init__(self, tasks):
        self.tasks = list(tasks)
        self.sent = []
        self.requests = []

    def Get_rank(self):
        return 1

    def Iprobe(self, source, tag, status=None):
        return tag == TAG_TASK and bool(self.tasks)

    def recv(self, source, tag):
        assert (source, tag) == (0, TAG_TASK)
        # a task is read only once the worker's last reply has gone (its send completed)
        assert all(r.done for r in self.requests), "a task read while a reply was in flight"
        return self.tasks.pop(0)

    def send(self, obj, dest, tag):
        assert (dest, tag) == (0, TAG_RESULT)
        self.sent.append(obj)

    def isend(self, obj, dest, tag):
        """A reply that completes on its third test, as a large one waits for the master."""
        self.send(obj, dest, tag)
        self.requests.append(FakeRequest(tests_to_complete=3))
        return self.requests[-1]


class FakeRequest:
    def __init__(self, tests_to_complete):
        self.left, self.done, self.tests = tests_to_complete, False, 0

    def Test(self):
        self.tests += 1
        self.left -= 1
        self.done = self.left <= 0
        return self.done


def test_worker_says_ready_answers_tasks_in_order_and_stops_on_none(campaign):
    p = campaign.points()
    comm = FakeComm([Task(q.hash, q.config.to_dict()) for q in p[:2]] + [None, "never"])
    worker_loop(comm, "sweep.testing:fake_point")
    kinds = [k for k, _ in comm.sent]
    assert kinds == [Kind.READY, Kind.RESULT, Kind.RESULT]
    assert isinstance(comm.sent[0][1], dict) and "python" in comm.sent[0][1]
    assert all(isinstance(o, Packed) for _, o in comm.sent[1:])  # header + pickled bytes
    assert all((o.hash, o.status) == (o.outcome().hash, o.outcome().status)
               for _, o in comm.sent[1:])
    # results and warm-ups go by a tested (sleeping) send: each tested until it completed
    assert [r.tests for r in comm.requests] == [3, 3]
    results = [o.outcome() for _, o in comm.sent[1:]]
    assert all(isinstance(o, Outcome) for o in results)
    assert [o.hash for o in results] == [q.hash for q in p[:2]]
    assert all(o.rank == 1 and o.status == "converged" for o in results)
    assert comm.tasks == ["never"]  # nothing read after the stop


def test_worker_answers_a_warm_up_with_its_time_and_first_problem(campaign):
    configs = tuple(q.config.to_dict() for q in campaign.points() if q.config.d_f == 0.005)
    comm = FakeComm([WarmUp(configs), None])
    worker_loop(comm, "sweep.testing:raising_point")  # fails for eps = 0.4
    kind, (seconds, problem) = comm.sent[1]
    assert kind is Kind.WARM and seconds >= 0.0
    assert problem == "RuntimeError: deliberate failure for eps = 0.4"


def test_a_worker_that_cannot_import_its_function_reports_and_waits_for_the_stop(campaign):
    p = campaign.points()[0]
    comm = FakeComm([Task(p.hash, p.config.to_dict()), None])
    worker_loop(comm, "sweep.testing:no_such_point")
    assert len(comm.sent) == 1  # the error only; the task is not computed
    kind, failure = comm.sent[0]
    assert kind is Kind.ERROR and isinstance(failure, WorkerFailure)
    assert failure.rank == 1 and "no_such_point" in failure.message
    assert failure.traceback == ""  # a ConfigError says it all
    assert comm.tasks == []


def test_compute_point_describes_each_kind_of_outcome(campaign):
    by = {(q.config.eps, q.config.d_f): q for q in campaign.points()}
    ok = compute_point(Task(by[0.2, 0.005].hash, by[0.2, 0.005].config.to_dict()),
                       fake_point, rank=4)
    assert ok.status == "converged" and ok.rank == 4 and ok.message == ""
    assert set(ok.profiles) >= {"a", "x_mean"} and ok.profiles["a"].dtype == np.float64
    assert "W_c" in ok.scalars and "a" not in ok.scalars and ok.wall_time >= 0
    bad = by[0.4, 0.005]
    failed = compute_point(Task(bad.hash, bad.config.to_dict()), raising_point, rank=4)
    assert failed.status == "failed" and failed.profiles == {} and failed.scalars == {}
    assert "deliberate failure" in failed.message and "rank 4" in failed.message
    assert "Traceback" in failed.message
    nan = by[0.2, 0.01]
    out = compute_point(Task(nan.hash, nan.config.to_dict()), nan_point)
    assert out.status == "failed" and "non-finite" in out.message


def test_compute_point_times_out_a_slow_point(campaign):
    import time

    p = campaign.points()[0]
    out = compute_point(Task(p.hash, p.config.to_dict(), timeout=0.1),
                        lambda cfg: time.sleep(5) or fake_point(cfg))
    assert out.status == "timeout" and "point_timeout = 0.1 s" in out.message
    assert out.wall_time < 4


def test_resolve_compute_says_what_is_wrong():
    assert resolve_compute("sweep.testing:fake_point") is fake_point
    for spec, why in (("nocolon", "expected 'module:function'"),
                      ("sweep.testing:nothing", "cannot import it"),
                      ("sweep.testing:SMALL_REAL_BASE", "not callable")):
        with pytest.raises(ConfigError, match=why):
            resolve_compute(spec)


# ---------------------------------------------------------------- start-up (issue 45)
def test_a_worker_rank_does_not_read_the_campaign(tmp_path, monkeypatch):
    """Under MPI a worker computes what rank 0 sends it: ``sweep run`` on rank 1 never
    reads the campaign (each rank parsed the whole grid at start-up: ~3 s for the
    24k-point grid of configs/herman2019.toml), and ends on rank 0's stop."""
    import sweep.cli
    import sweep.config

    comm = FakeComm([None])
    comm.Get_size = lambda: 3
    monkeypatch.setattr(sweep.cli, "mpi_world", lambda: comm)

    def never(path):
        raise AssertionError(f"a worker read the campaign {path}")

    monkeypatch.setattr(sweep.config, "load_campaign", never)
    assert sweep.cli.main(["run", str(tmp_path / "c.toml"), "--store",
                           str(tmp_path / "s.h5"), "--compute",
                           "sweep.testing:fake_point"]) == 0
    assert [k for k, _ in comm.sent] == [Kind.READY]
    assert not (tmp_path / "s.h5").exists()


def test_rank_0_that_cannot_read_the_campaign_stops_its_workers(tmp_path, monkeypatch,
                                                               capsys):
    """Rank 0 alone reads the campaign: when it cannot, it tells every worker to stop
    (they wait for its first word) and the job ends with its status."""
    import sweep.cli

    class Rank0:
        sent = []

        def Get_rank(self):
            return 0

        def Get_size(self):
            return 3

        def send(self, obj, dest, tag):
            self.sent.append((obj, dest, tag))

    comm = Rank0()
    monkeypatch.setattr(sweep.cli, "mpi_world", lambda: comm)
    assert sweep.cli.main(["run", str(tmp_path / "absent.toml"), "--store",
                           str(tmp_path / "s.h5")]) == 2
    assert comm.sent == [(None, 1, TAG_TASK), (None, 2, TAG_TASK)]
    assert "absent.toml" in capsys.readouterr().err
