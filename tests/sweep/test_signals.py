"""sweep.run.signals and sweep.system.signals_deferred: a stop signal is recorded once,
in-process the grace period ends with GraceExpired, and deferred signals wait for the end
of the block."""
from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from sweep.run import signals as signals_mod
from sweep.run.signals import GraceExpired, StopSignals
from sweep.system import signals_deferred


def test_the_first_stop_signal_is_recorded_and_handlers_are_restored():
    before = signal.getsignal(signal.SIGUSR1)
    with StopSignals(60.0, in_process=False) as s:
        os.kill(os.getpid(), signal.SIGUSR1)
        os.kill(os.getpid(), signal.SIGTERM)
        assert s.requested == "SIGUSR1"
    assert signal.getsignal(signal.SIGUSR1) == before
    assert signals_mod.campaign_over


def test_in_process_the_grace_period_ends_with_grace_expired():
    t0 = time.monotonic()
    with pytest.raises(GraceExpired), StopSignals(0.2, in_process=True) as s:
        os.kill(os.getpid(), signal.SIGINT)
        assert s.requested == "SIGINT"
        while time.monotonic() - t0 < 10:
            time.sleep(0.01)
    assert time.monotonic() - t0 < 5


def test_a_second_stop_in_process_ends_the_grace_period_at_once():
    with pytest.raises(GraceExpired), StopSignals(60.0, in_process=True):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.3)  # later than the repeat window: a new request
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)


def test_quiet_only_records():
    with StopSignals(0.05, in_process=True) as s:
        s.quiet()
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.2)  # no timer, nothing raised
        assert s.requested == "SIGTERM"


def test_signals_deferred_delivers_after_the_block():
    got = []
    old = signal.signal(signal.SIGUSR1, lambda n, f: got.append(time.monotonic()))
    try:
        with signals_deferred():  # blocked in this thread (the one that commits)
            signal.pthread_kill(threading.get_ident(), signal.SIGUSR1)
            time.sleep(0.05)
            assert got == []  # blocked inside
            left = time.monotonic()
        time.sleep(0.01)
        assert len(got) == 1 and got[0] >= left
    finally:
        signal.signal(signal.SIGUSR1, old)


def test_an_in_process_command_gives_the_callers_handlers_back(tmp_path):
    """``sweep.cli.main(argv)`` in a process (a notebook, a script): its start-up stop
    handlers go when it returns, whatever it returned, so that a later Ctrl-C is the
    caller's and no later campaign of the process is stopped by it; a start-up stop
    recorded and never taken up is dropped; the guard's copy of a taken-up stop is the
    same request."""
    from sweep import parse_campaign, run_campaign
    from sweep.cli import main
    from sweep.system import note_start_up_stop, take_start_up_stop

    stops = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
    before = [signal.getsignal(s) for s in stops]
    toml = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"
    (tmp_path / "c.toml").write_text(toml)
    for argv in (["merge", tmp_path / "o.h5", tmp_path / "missing.h5"],
                 ["run", tmp_path / "c.toml", "--store", tmp_path / "s.h5", "--compute",
                  "sweep.testing:fake_point", "--no-bar"]):
        main([str(a) for a in argv])
        assert [signal.getsignal(s) for s in stops] == before, argv
    note_start_up_stop("SIGTERM")  # left by a command whose stop was raised
    main(["run", str(tmp_path / "c.toml"), "--store", str(tmp_path / "s.h5")])
    assert take_start_up_stop() == ""
    note_start_up_stop("SIGUSR1")  # taken up by the campaign: the guard's copy is the same
    with StopSignals(60.0, in_process=True) as s:
        assert s.requested == "SIGUSR1"
        os.kill(os.getpid(), signal.SIGUSR1)  # no GraceExpired: one request, not two
    campaign = parse_campaign(toml)
    assert run_campaign(campaign, str(tmp_path / "t.h5"),
                        compute="sweep.testing:fake_point").computed == 2
