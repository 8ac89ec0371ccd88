"""Stop signals of a campaign run: SIGINT, SIGTERM, SIGUSR1 ask the master to stop.

:class:`StopSignals` records the first stop signal (no new points are handed out) and,
in-process, arms a grace timer whose expiry raises :class:`GraceExpired` in the master
(the point being computed is abandoned); under MPI the master waits up to the grace
period for the running points and stops. Workers ignore stop signals
(:func:`sweep.run.worker.worker_loop`): the master decides.
"""
from __future__ import annotations

import contextlib
import math
import signal
import sys
import time
from typing import Any

from sweep.system import STOP_SIGNALS, take_start_up_stop

__all__ = ["StopSignals", "GraceExpired", "Unanswered", "MAX_TIMER", "REPEAT_WINDOW"]

#: Longest interval [s] given to ``setitimer`` (larger values overflow it).
MAX_TIMER = 1e7
#: [s] the same stop signal again within this time is the same request: a signal sent
#: to the process group reaches the campaign and its guard, which forwards it
#: (:mod:`sweep.run.guard`); a second Ctrl-C a person types comes later than this.
REPEAT_WINDOW = 0.25


#: Set once a campaign's :class:`StopSignals` are done (the run is over, whatever its
#: outcome): a stop signal after that has nothing left to stop (``sweep.cli`` records it).
campaign_over = False


class GraceExpired(BaseException):
    """Raised in-process when the grace period after a stop signal runs out."""


class Unanswered(GraceExpired):
    """Raised in the master when the store's writer process did not answer within the
    grace period after a stop signal (:class:`sweep.run.store_process.StoreProcess`)."""


class StopSignals:
    """SIGINT/SIGTERM/SIGUSR1 set ``requested``; in-process, the grace timer raises."""

    def __init__(self, grace: float, in_process: bool) -> None:
        self.requested = ""
        self.grace = grace
        self.in_process = in_process
        self.active = True
        self._old: dict[int, Any] = {}
        self._last: tuple[int, float] = (0, -1.0)
        self._since = math.inf  # [s] time.monotonic() of the first stop request

    @property
    def deadline(self) -> float:
        """When the grace period after the first stop request ends (``time.monotonic``;
        infinity while none came)."""
        return self._since + self.grace if self.requested else math.inf

    def __enter__(self) -> StopSignals:
        self.requested = take_start_up_stop()  # a start-up stop whose exception was lost
        if self.requested:  # the guard's copy of it, if it comes now, is the same request
            self._last = (signal.Signals[self.requested].value, time.monotonic())
            self._since = time.monotonic()
        for sig in STOP_SIGNALS:
            with contextlib.suppress(ValueError):  # not the main thread
                self._old[sig] = signal.signal(sig, self._handle)
        if self.in_process:
            with contextlib.suppress(ValueError):
                self._old[signal.SIGALRM] = signal.signal(signal.SIGALRM, self._expire)
        return self

    def quiet(self) -> None:
        """From now on only record signals (no grace timer, nothing raised)."""
        self.active = False
        if self.in_process:
            with contextlib.suppress(ValueError):
                signal.setitimer(signal.ITIMER_REAL, 0)

    def _handle(self, signum: int, frame: Any) -> None:
        name = signal.Signals(signum).name
        now = time.monotonic()
        last, self._last = self._last, (signum, now)
        if last[0] == signum and now - last[1] < REPEAT_WINDOW:
            return  # the same request delivered twice (group and guard)
        if not self.requested:
            self._since = now
        if not self.active:
            self.requested = self.requested or name
            return
        if self.requested and self.in_process:
            raise GraceExpired(name)
        if not self.requested:
            print(f"[sweep] {name} received: no new points are handed out; waiting up to"
                  f" {self.grace:g} s for running ones", file=sys.stderr, flush=True)
        self.requested = self.requested or name
        if self.in_process:
            signal.setitimer(signal.ITIMER_REAL, min(max(self.grace, 1e-3), MAX_TIMER))

    def _expire(self, signum: int, frame: Any) -> None:
        if self.active:
            raise GraceExpired("grace period")

    def __exit__(self, *exc: Any) -> None:
        global campaign_over
        campaign_over = True
        if self.in_process:
            with contextlib.suppress(ValueError):
                signal.setitimer(signal.ITIMER_REAL, 0)
        for sig, old in self._old.items():
            with contextlib.suppress(ValueError, TypeError):
                signal.signal(sig, old)
