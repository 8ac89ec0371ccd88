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

__all__ = ["utc_now", "fsync_path", "fsync_dir", "signals_deferred", "DEFERRED_SIGNALS"]

#: Signals whose Python handlers must not run in the middle of a commit, an open or a
#: rebuild (the in-process grace timer raises from its handler; a default action would
#: kill the process half-way): they are delivered when that is done.
DEFERRED_SIGNALS = frozenset({signal.SIGINT, signal.SIGTERM, signal.SIGUSR1, signal.SIGALRM})


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
