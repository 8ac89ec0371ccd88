"""Stop signals during a command's start-up: ``sweep run`` and ``sweep merge`` before the
store is opened.

:func:`catch` installs the start-up handler first thing in ``sweep.cli.main``: a SIGINT,
SIGTERM or SIGUSR1 from then on raises :class:`~sweep.errors.Interrupted` (status 6,
nothing changed), once; one after the campaign's own handlers were done is recorded in
:data:`LATE` (nothing left to stop). Where Python cannot raise the handler's exception (it
ran in a weakref callback or finaliser inside an import: Python reports "Exception ignored"
and goes on), the stop is not lost: it is recorded (:func:`sweep.system.note_start_up_stop`)
and the campaign's or the merge's own handlers take it up when they start; on the command
line that report is not printed. :func:`release` ends the start-up of an in-process
command: the caller's handlers come back, and a stop recorded and not taken is dropped.
Not under an MPI launcher: there rank 0 alone leaving would leave the workers waiting; the
default action ends the job.
"""
from __future__ import annotations

import signal
import sys
from collections.abc import Sequence
from typing import Any

from sweep.errors import Interrupted
from sweep.run import signals
from sweep.run.mpi import launched
from sweep.system import STOP_SIGNALS, note_start_up_stop, take_start_up_stop

__all__ = ["FIRST", "LATE", "catch", "release"]

#: The first stop signal of the start-up (raised once; a repeat is the same request: the
#: guard forwards what the process group got too).
FIRST: list[int] = []
#: Stop signals after the campaign's own handlers were done.
LATE: list[int] = []
_CALLERS: dict[int, Any] = {}  # the handlers catch() replaced, for release()
_UNRAISABLE: list[Any] = []  # the unraisable hook _quiet passes the others to


def _handle(signum: int, frame: Any) -> None:
    if signals.campaign_over:  # nothing left to stop: the command ends as it would
        LATE.append(signum)
        return
    if FIRST:
        return
    FIRST.append(signum)
    note_start_up_stop(signal.Signals(signum).name)  # taken up if this raise is lost
    raise Interrupted(f"stopped by {signal.Signals(signum).name} during start-up, before"
                      " the store was opened; nothing was changed — the campaign is resumable:"
                      " run the same command again")


def _quiet(unraisable: Any) -> None:
    """``sys.unraisablehook`` of a command: the lost start-up stop is not reported as
    "Exception ignored" (it is taken up later); any other exception is, as before."""
    if isinstance(unraisable.exc_value, Interrupted) and FIRST:
        return
    _UNRAISABLE[0](unraisable)


def catch(argv: Sequence[str], command_line: bool) -> None:
    """Start the start-up of the command ``argv`` (``run`` and ``merge`` only)."""
    if not argv or argv[0] not in ("run", "merge"):
        return
    signals.campaign_over = False  # a new command: its stops stop it
    FIRST.clear()
    LATE.clear()
    take_start_up_stop()
    if launched():
        return
    if command_line and sys.unraisablehook is not _quiet:
        _UNRAISABLE[:] = [sys.unraisablehook]
        sys.unraisablehook = _quiet
    for sig in STOP_SIGNALS:
        old = signal.signal(sig, _handle)
        _CALLERS.setdefault(sig, old)


def release() -> None:
    """The end of an in-process command: the handlers :func:`catch` replaced come back,
    and a stop recorded and not taken up belongs to no later command."""
    take_start_up_stop()
    for sig, old in _CALLERS.items():
        signal.signal(sig, signal.SIG_DFL if old is None else old)
    _CALLERS.clear()
