"""Operating-system helpers every layer of sweep may use: time stamps, fsync, deferred signals.

This module imports nothing of sweep: it is the bottom layer.
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
import signal
from collections.abc import Iterator
from pathlib import Path

__all__ = ["utc_now", "fsync_path", "fsync_dir", "signals_deferred", "STOP_SIGNALS",
           "DEFERRED_SIGNALS", "note_start_up_stop", "take_start_up_stop"]

#: The signals that ask a command to stop (Ctrl-C, ``kill``, Slurm's warning signal), in
#: the order their handlers are installed.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
#: Signals whose Python handlers must not run in the middle of a commit, an open or a
#: rebuild (the in-process grace timer raises from its handler; a default action would
#: kill the process half-way): they are delivered when that is done.
DEFERRED_SIGNALS = frozenset({*STOP_SIGNALS, signal.SIGALRM})


#: The stop signal a command received during its start-up, by name (see
#: :func:`note_start_up_stop`).
_start_up_stop: list[str] = []


def note_start_up_stop(name: str) -> None:
    """Record the stop signal ``name`` that arrived during a command's start-up. Its handler
    raises (:mod:`sweep.run.startup`), but an exception raised where Python can only report it (in a
    weakref callback or a finaliser that runs inside an import) is lost: the campaign's and
    the merge's own stop handlers then take it up (:func:`take_start_up_stop`) as their
    first request."""
    _start_up_stop[:] = [name]


def take_start_up_stop() -> str:
    """The start-up stop recorded and not yet taken (``""`` if none), now taken."""
    name = _start_up_stop[0] if _start_up_stop else ""
    _start_up_stop.clear()
    return name


def utc_now() -> str:
    """The current time, ISO 8601 UTC with microseconds."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="microseconds")


def fsync_path(path: str | Path) -> None:
    """``fsync`` a file (or directory) by path."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(path: str | Path) -> None:
    """``fsync`` the directory holding ``path`` (makes a rename durable); errors ignored."""
    with contextlib.suppress(OSError):
        fsync_path(Path(path).parent)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Block the stop signals (and SIGALRM) in this thread; pending ones arrive after."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, DEFERRED_SIGNALS)
    except (AttributeError, OSError, ValueError):  # pragma: no cover - no pthread_sigmask
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
