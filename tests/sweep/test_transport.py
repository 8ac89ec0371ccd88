"""sweep.run.transport: the one Backoff of the waiting loops; the in-process transport."""
from __future__ import annotations

import os
import time

from sweep.protocol import Kind, Outcome, Task
from sweep.run.transport import POLL_MAX, POLL_MIN, Backoff, InProcessTransport


def test_backoff_doubles_to_its_cap_and_starts_again_after_a_hit(monkeypatch):
    slept = []
    monkeypatch.setattr(time, "sleep", slept.append)
    answers = iter([False] * 6 + [True])
    b = Backoff(0.001, 0.005)
    assert b.wait(lambda: next(answers))
    assert slept == [0.001, 0.002, 0.004, 0.005, 0.005, 0.005]
    assert b.delay == 0.001  # reset by the hit
    assert (Backoff().low, Backoff().high) == (POLL_MIN, POLL_MAX)


def test_backoff_gives_up_at_its_deadline_and_keeps_its_delay():
    b = Backoff(0.001, 0.004)
    t0 = time.monotonic()
    assert not b.wait(lambda: False, t0 + 0.03)
    assert 0.03 <= time.monotonic() - t0 < 1.0
    assert b.delay == 0.004
    assert not b.wait(lambda: False, time.monotonic())  # no time left: one probe


def test_in_process_transport_computes_what_it_was_sent(tmp_path):
    from sweep import parse_campaign

    p = parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n").points()
    t = InProcessTransport("sweep.testing:trivial_point")
    assert t.workers == [0] and t.poll(0.0) is None
    for point in p:
        t.send(0, Task(point.hash, point.config.to_dict()))
    got = [t.poll(0.0), t.poll(0.0)]
    assert [(w, kind, out.hash, out.status) for w, kind, out in got] == [
        (0, Kind.RESULT, point.hash, "converged") for point in p]
    assert all(isinstance(out, Outcome) for _, _, out in got)
    assert t.poll(0.0) is None


def test_in_process_transport_survives_a_point_that_ends_its_process():
    """With a timeout the in-process transport computes in a child: a point that ends
    its process (``os._exit(0)``) is ``crashed``, the others converge, and the campaign's
    process goes on."""
    from sweep import parse_campaign

    p = parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n").points()
    t = InProcessTransport("sweep.testing:exiting_point")
    for point in p:
        t.send(0, Task(point.hash, point.config.to_dict(), timeout=30.0))
    got = {out.hash: out for _, _, out in (t.poll(0.0), t.poll(0.0))}
    crashed = got[p[1].hash]
    assert got[p[0].hash].status == "converged"
    assert crashed.status == "crashed" and "with status 0" in crashed.message
    assert crashed.profiles == {} and crashed.pid != os.getpid()


def test_in_process_transport_times_out_a_point_that_ignores_its_limit():
    from sweep import parse_campaign

    p = parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.4]\n").points()
    t = InProcessTransport("sweep.testing:stubborn_point")
    t.send(0, Task(p[0].hash, p[0].config.to_dict(), timeout=0.2))
    t0 = time.monotonic()
    _, kind, out = t.poll(0.0)
    assert kind == Kind.RESULT and out.status == "timeout"
    assert "point_timeout = 0.2 s" in out.message and time.monotonic() - t0 < 20


def test_mpi_transport_sends_tasks_without_waiting_for_them(monkeypatch):
    """The master's task sends are non-blocking (``isend``, tested later: a blocking send
    took 44 % of its time at 64 ranks, docs/cluster.md); the stop waits for them."""
    import sys
    import types

    from sweep.protocol import TAG_TASK, Task
    from sweep.run.transport import MPITransport

    class Request:
        def __init__(self):
            self.tests = 0

        def Test(self):  # completes on its second test
            self.tests += 1
            return self.tests >= 2

    class Comm:
        def __init__(self):
            self.isent, self.sent = [], []

        def Get_size(self):
            return 3

        def isend(self, obj, dest, tag):
            self.isent.append((obj, dest, tag, Request()))
            return self.isent[-1][-1]

        def send(self, obj, dest, tag):
            self.sent.append((obj, dest, tag))

    fake = types.ModuleType("mpi4py")
    fake.MPI = types.SimpleNamespace(Status=lambda: None, ANY_SOURCE=-1)
    monkeypatch.setitem(sys.modules, "mpi4py", fake)
    comm = Comm()
    t = MPITransport(comm)
    tasks = [Task("a" * 64, {}), Task("b" * 64, {}), Task("c" * 64, {})]
    for worker, task in zip([1, 2, 1], tasks, strict=True):
        t.send(worker, task)
    assert comm.sent == []  # no blocking send
    assert [(o, d, g) for o, d, g, _ in comm.isent] == [
        (tasks[0], 1, TAG_TASK), (tasks[1], 2, TAG_TASK), (tasks[2], 1, TAG_TASK)]
    t.shutdown()
    assert comm.sent == [(None, 1, TAG_TASK), (None, 2, TAG_TASK)]
    assert all(r.tests >= 2 for *_, r in comm.isent)  # each seen complete
