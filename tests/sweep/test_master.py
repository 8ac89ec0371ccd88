"""sweep.run.master: the master hands out Tasks costliest-first, stores each Outcome by
group commit, and stops on a worker's error or a protocol error."""
from __future__ import annotations

import collections
import io

import pytest

from floewave import MODEL_VERSION
from sweep.errors import WorkerError
from sweep.protocol import Kind, Task, WorkerFailure
from sweep.run.compute import compute_point
from sweep.run.master import Master, RunSummary
from sweep.run.progress import Progress
from sweep.run.signals import StopSignals
from sweep.run.sink import InlineSink
from sweep.store.journal import Journal, journal_path
from sweep.store.store import Store
from sweep.testing import fake_point

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6]\n"


class FakeTransport:
    """Two workers computing in this process; ``script`` may replace a reply."""

    def __init__(self, script=None):
        self.workers = [1, 2]
        self.worker_env = {1: {"python": "x"}, 2: {"python": "y"}}
        self.sent: list[tuple[int, Task]] = []
        self.inbox: collections.deque = collections.deque()
        self.script = script or (lambda n, worker, task, out: (worker, Kind.RESULT, out))

    def send(self, worker, task):
        self.sent.append((worker, task))
        out = compute_point(task, fake_point, worker)
        self.inbox.append(self.script(len(self.sent), worker, task, out))

    def poll(self, timeout):
        return self.inbox.popleft() if self.inbox else None


def run(store, campaign, transport, timeout=0.0):
    master = Master(InlineSink(store, transport.worker_env), transport,
                    "sweep.testing:fake_point", point_timeout=timeout)
    summary = RunSummary(total=len(campaign.points()))
    progress = Progress(len(campaign.points()), bar=False, stream=io.StringIO())
    with StopSignals(5.0, in_process=True) as signals:
        master.run(campaign.points(), progress, signals, summary)
    return master, summary


def test_every_point_is_handed_out_once_as_a_task_and_stored(tmp_path, campaign):
    t = FakeTransport()
    with Store(tmp_path / "s.h5", campaign) as store:
        _, summary = run(store, campaign, t, timeout=7.5)
        assert len(store) == 6 and summary.computed == 6
        assert summary.counts == {"converged": 6}
        stored_ranks = {h: store.file["table/rank"][i] for h, i in store.rows.items()}
    tasks = [task for _, task in t.sent]
    assert all(isinstance(task, Task) and task.timeout == 7.5 for task in tasks)
    assert sorted(task.hash for task in tasks) == sorted(p.hash for p in campaign.points())
    assert {w for w, _ in t.sent} == {1, 2}  # both workers used
    # each row records the worker that computed it
    assert all(stored_ranks[task.hash] == w for w, task in t.sent)
    # the costliest points (L_x = 0.5: more floes) go out first
    costs = {p.hash: p.cost for p in campaign.points()}
    first = [costs[task.hash] for task in tasks[:2]]
    assert min(first) >= max(costs[task.hash] for task in tasks[2:])
    # each hand-out was journaled before it went out
    scan = Journal(journal_path(tmp_path / "s.h5")).scan(MODEL_VERSION, ("converged",))
    assert len(scan.latest) == 6
    assert journal_path(tmp_path / "s.h5").read_text().count('"handout"') == 6


def test_a_worker_error_stops_the_run_after_the_results_before_it(tmp_path, campaign):
    def script(n, worker, task, out):
        if n == 3:
            return worker, Kind.ERROR, WorkerFailure(worker, "h", "it broke", "tb line")
        return worker, Kind.RESULT, out

    with Store(tmp_path / "s.h5", campaign) as store:
        with pytest.raises(WorkerError, match=r"worker rank \d on h: it broke\ntb line"):
            run(store, campaign, FakeTransport(script))
        assert len(store) == 2  # the two results before the error are stored


def test_a_result_for_another_point_is_a_protocol_error(tmp_path, campaign):
    other = campaign.points()[0].hash

    def script(n, worker, task, out):
        if n == 2:
            out = type(out)(**{**out.__dict__, "hash": other})
        return worker, Kind.RESULT, out

    with Store(tmp_path / "s.h5", campaign) as store:
        with pytest.raises(WorkerError, match="protocol error"):
            run(store, campaign, FakeTransport(script))


def test_depth_grows_when_commits_are_slow_against_points():
    m = Master.__new__(Master)
    m.point_time = m.commit_time = float("nan")
    assert m.depth == 1  # not yet timed
    m.point_time, m.commit_time = 10.0, 0.01
    assert m.depth == 1  # slow points: one task each
    m.point_time, m.commit_time = 0.001, 0.05
    assert 1 < m.depth <= 64
