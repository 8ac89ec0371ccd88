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
