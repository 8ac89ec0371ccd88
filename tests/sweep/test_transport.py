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
