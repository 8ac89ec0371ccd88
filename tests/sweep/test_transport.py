"""sweep.transport: the one Backoff of the waiting loops; the in-process transport."""
from __future__ import annotations

import time

from sweep import executor
from sweep.transport import POLL_MAX, POLL_MIN, Backoff, InProcessTransport


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
        t.send(0, {"hash": point.hash, "config": point.config.to_dict()})
    got = [t.poll(0.0), t.poll(0.0)]
    assert [(w, kind, out["hash"], out["status"]) for w, kind, out in got] == [
        (0, "result", point.hash, "converged") for point in p]
    assert t.poll(0.0) is None


def test_the_executor_still_names_its_parts():
    for name in ("run_campaign", "compute_point", "worker_loop", "Master", "RunSummary",
                 "InProcessTransport", "MPITransport", "resolve_compute", "mpi_world",
                 "check_launch", "DEFAULT_COMPUTE", "Backoff", "_StopSignals"):
        assert hasattr(executor, name), name
