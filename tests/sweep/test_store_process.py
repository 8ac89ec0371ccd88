"""sweep.run.store_process: the store written by a forked writer process. What it stores
equals what the master stores inline; its errors reach the master as the same exceptions;
a writer that dies is a StoreError and the store reopens whole; a master that ends without
closing leaves the writer to commit what it was given and close the store."""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import time

import pandas as pd
import pytest

import sweep
from sweep.errors import CampaignMismatchError, StoreError, StoreLockedError
from sweep.protocol import Outcome, Packed, Task
from sweep.run.compute import compute_point, resolve_compute
from sweep.run.store_process import ORPHANED, StoreProcess
from sweep.store.record import Record
from sweep.store.store import Store
from tests.sweep.helpers import table

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4, 0.6]\nd_f = [0.005, 0.01]\n"


def _packed(campaign, compute="sweep.testing:fake_point", rank=1):
    fn = resolve_compute(compute)
    return [Packed.of(compute_point(Task(p.hash, p.config.to_dict()), fn, rank))
            for p in campaign.points()]


def _outcomes(path):
    """The recorded outcome of each run of the store, in order."""
    import h5py

    with h5py.File(path, "r", locking=False) as f:
        runs = f["runs"]
        return [runs[k].attrs["outcome"] for k in sorted(runs, key=int)]


def test_writer_stores_what_the_inline_master_stores(tmp_path, campaign):
    """The same outcomes through the writer process and through Store.add: equal tables
    and profiles; stored statuses reported only after their commit, in order."""
    results = _packed(campaign)
    a, b = tmp_path / "proc.h5", tmp_path / "inline.h5"
    sp = StoreProcess(a, campaign, run_info={"cmd": "test"})
    assert sp.pid != os.getpid() and len(sp) == 0
    sp.handout([(r.hash, 1) for r in results[:3]])
    for r in results[:3]:
        sp.forward(r)
    first = sp.sync()
    assert first == [r.status for r in results[:3]]
    sp.handout([(r.hash, 2) for r in results[3:]])
    for r in results[3:]:
        sp.forward(r)
    got = []
    deadline = time.monotonic() + 10
    while len(got) < len(results) - 3 and time.monotonic() < deadline:
        got += sp.wait(0.5)  # the writer commits after each read: no sync needed
    assert got == [r.status for r in results[3:]]
    assert sp.take_stored() == []
    sp.close("complete")
    assert sp.writer_cpu > 0

    with Store(b, campaign, run_info={"cmd": "test"}) as st:
        for p, r in zip(campaign.points(), results, strict=True):
            st.add(Record.from_outcome(p, r.outcome()))
        st.commit()
    pd.testing.assert_frame_equal(table(a), table(b))
    for p in campaign.points():
        pa, pb = sweep.load_profile(a, p.hash), sweep.load_profile(b, p.hash)
        assert pa.equals(pb)
    assert sweep.validate(a) == []
    assert _outcomes(a)[-1] == "complete"

    again = StoreProcess(a, campaign)  # what the master asks before the run
    assert len(again) == len(results) and all(r.hash in again for r in results)
    assert {again.status_of(r.hash) for r in results} == {"converged"}
    again.close()


def test_open_errors_are_the_stores_own(tmp_path, campaign, refused_at_once):
    """A store held by another writer, or of another campaign: the writer's exception, as
    Store raises it, and the writer process is gone."""
    path = tmp_path / "s.h5"
    sp = StoreProcess(path, campaign)
    with pytest.raises(StoreLockedError):
        Store(path, campaign)  # the writer process holds the lock
    with pytest.raises(StoreLockedError) as held:
        StoreProcess(path, campaign)
    assert str(sp.pid) in str(held.value)
    sp.close()
    other = sweep.parse_campaign(TOML.replace("0.6", "0.7"), "o.toml")
    with pytest.raises(CampaignMismatchError):
        StoreProcess(path, other)


def test_a_bad_result_fails_the_writer_and_nothing_more_is_stored(tmp_path, campaign):
    """A result of a point not in the campaign: the master's next wait raises the
    writer's StoreError; results after it are not stored; the store stays valid."""
    results = _packed(campaign)
    path = tmp_path / "s.h5"
    sp = StoreProcess(path, campaign)
    sp.forward(results[0])
    assert sp.sync() == [results[0].status]
    bogus = Outcome.known("f" * 64, "failed", "no such point")
    sp.forward(bogus)
    sp.forward(results[1])
    with pytest.raises(StoreError, match="not in the campaign"):
        sp.sync()
    sp.close("error: test")
    df = sweep.load(path)
    assert list(df["hash"]) == [results[0].hash]
    assert sweep.validate(path) == []


def test_a_killed_writer_is_a_store_error_and_the_store_reopens(tmp_path, campaign):
    results = _packed(campaign)
    path = tmp_path / "s.h5"
    sp = StoreProcess(path, campaign)
    for r in results[:2]:
        sp.forward(r)
    assert len(sp.sync()) == 2
    os.kill(sp.pid, signal.SIGKILL)
    with pytest.raises(StoreError, match=rf"pid {sp.pid}\) was killed by signal 9"):
        for _ in range(100):  # the pipe may take a moment to close
            sp.handout([(results[2].hash, 1)])
            time.sleep(0.05)
    sp.close()  # only reaps
    with Store(path, campaign) as st:  # left unclean: reopened from the journal
        assert len(st) == 2
    assert sweep.validate(path) == []


def test_a_master_gone_without_closing_leaves_a_closed_store(tmp_path, campaign):
    """The master's ends of the pipes close without a CLOSE (it was killed): the writer
    commits the results it was given, records the run's outcome as such, and exits."""
    results = _packed(campaign)
    path = tmp_path / "s.h5"
    sp = StoreProcess(path, campaign)
    sp.handout([(r.hash, 1) for r in results])
    for r in results:
        sp.forward(r)
    sp._chan.close()  # as a killed master's would be
    assert sp.proc.wait(30) == 0
    assert len(sweep.load(path)) == len(results)
    assert sweep.validate(path) == []
    assert _outcomes(path)[-1] == ORPHANED
    with Store(path, campaign) as st:  # closed cleanly: the lock is free
        assert len(st) == len(results)


# ---------------------------------------------------------------- attempts (issue 45)
_WRITERS: list[StoreProcess] = []


def writer_killing_point(cfg):
    """A good point, during whose computation the store's writer process is killed."""
    os.kill(_WRITERS[-1].pid, signal.SIGKILL)
    time.sleep(0.2)
    return sweep.testing.fake_point(cfg)


@pytest.fixture
def process_writer(monkeypatch):
    """In-process runs whose store is written by a writer process (as MPI runs' is)."""
    import sweep.run.launch as launch

    def open_sink(path, campaign, writer, **kw):
        # the writer keeps descriptors 0-2 only (pytest's capture of sys.stderr is another)
        with monkeypatch.context() as m:
            m.setattr(sys, "stderr", sys.__stderr__)
            _WRITERS.append(StoreProcess(path, campaign, opener=Store, **kw))
        return _WRITERS[-1]

    monkeypatch.setattr(launch, "_open_sink", open_sink)


def test_a_writer_killed_while_a_point_runs_alone_is_no_attempt(tmp_path, campaign,
                                                                process_writer):
    """kill -9 of the writer while a suspect point is computed alone: the master knows
    the writer died (StoreError, exit 3) and journals the point's release; after more
    such deaths than [run] max_attempts the good point is still computed, not stored
    ``crashed``."""
    from sweep import run_campaign

    path = tmp_path / "s.h5"
    first = next(iter(campaign.points()))
    with Store(path, campaign) as st:  # a run died while it ran: a suspect
        st.handout([(first.hash, 1)])
    for _ in range(campaign.run.max_attempts + 1):
        with pytest.raises(StoreError, match="was killed by signal 9"):
            run_campaign(campaign, str(path),
                         compute="tests.sweep.test_store_process:writer_killing_point")
    s = run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    assert s.counts.get("crashed", 0) == 0 and s.computed == campaign.size
    assert set(sweep.load(path)["status"]) <= {"converged", "converged_noisy"}
    assert sweep.validate(path) == []


# ---------------------------------------------------------------- a stuck writer (issue 45)
class _Stop:
    """What StoreProcess reads of the run's StopSignals: the request and its deadline."""

    requested = ""
    deadline = float("inf")


def test_a_stopped_writer_cannot_make_the_master_deaf(tmp_path, campaign):
    """The writer is stopped (SIGSTOP: a hung write) while the master waits for it: once
    a stop is requested, the wait ends with the grace period (the writer is killed and
    said so), close() returns at once, and the store reopens with what was committed.
    The same through mpiexec and SIGTERM/SIGINT/SIGUSR1: test_mpi.py (slow tier)."""
    from sweep.run.signals import GraceExpired

    results = _packed(campaign)
    path = tmp_path / "s.h5"
    stop = _Stop()
    sp = StoreProcess(path, campaign, stop=stop)
    sp.handout([(r.hash, 1) for r in results[:2]])
    for r in results[:2]:
        sp.forward(r)
    assert len(sp.sync()) == 2
    os.kill(sp.pid, signal.SIGSTOP)
    try:
        stop.requested, stop.deadline = "SIGTERM", time.monotonic() + 0.5
        t0 = time.monotonic()
        with pytest.raises(GraceExpired):
            sp.handout([(results[2].hash, 1)])  # its answer never comes
        assert time.monotonic() - t0 < 3
        t0 = time.monotonic()
        sp.close("interrupted (resumable)")
        assert time.monotonic() - t0 < 2
        assert sp.proc.poll() == -signal.SIGKILL
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.kill(sp.pid, signal.SIGKILL)
            os.kill(sp.pid, signal.SIGCONT)
    with Store(path, campaign) as st:  # left unclean: reopened from the journal
        assert len(st) == 2
    assert sweep.validate(path) == []


def test_the_writers_cpu_share_is_over_the_span_it_was_measured_on(tmp_path, campaign):
    """The writer counts its CPU and wall time over one span (the store open to its
    close); the summary's share divides the one by the other, not by the master's
    scheduling loop (a re-run of a finished campaign, whose loop takes no time, printed
    ``its store writer 13296.1%``)."""
    from sweep.run.master import RunSummary

    path = tmp_path / "s.h5"
    sp = StoreProcess(path, campaign)
    sp.close()
    assert 0 < sp.store_cpu <= sp.store_wall
    done = RunSummary(total=6, skipped=6, elapsed=0.3, master_cpu=1e-5, loop_elapsed=1e-5,
                      writer_cpu=0.133, writer_wall=0.2)
    assert str(done).endswith("; master CPU 100.0% of a core, its store writer 66.5%")
    assert "its store writer" not in str(RunSummary(total=6, writer_cpu=0.1,
                                                    loop_elapsed=1e-5))


def test_a_full_disk_in_the_writer_charges_no_attempt(tmp_path, campaign, process_writer,
                                                      monkeypatch):
    """ENOSPC in the writer process while it commits a suspect point's result (its store
    broken): the writer still journals the release of the point, which did not kill its
    worker; after more such runs than [run] max_attempts it is not stored ``crashed``."""
    from sweep import run_campaign
    from tests.sweep.helpers import suspect_with_a_full_disk

    path = tmp_path / "s.h5"
    with monkeypatch.context() as m:  # the forked writer inherits it
        suspect_with_a_full_disk(path, campaign, m)
        for _ in range(campaign.run.max_attempts + 1):
            with pytest.raises(StoreError, match="no space left"):
                run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    s = run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    assert s.counts.get("crashed", 0) == 0 and s.computed == campaign.size
    assert sweep.validate(path) == []
