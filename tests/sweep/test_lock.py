"""sweep.store.lock: one live writer per store; a lock left by a dead writer is taken over."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time

import pytest

from sweep.errors import StoreLockedError
from sweep.store.lock import KILLED_WRITER_WAIT, Lock, lock_path, pid_alive
from tests import forkserver


def test_a_second_writer_is_refused_while_the_first_holds_the_lock(tmp_path, refused_at_once):
    path = lock_path(tmp_path / "s.h5")
    first = Lock(path)
    first.acquire()
    try:
        with pytest.raises(StoreLockedError, match=str(os.getpid())):
            Lock(path).acquire()
    finally:
        first.release()
    second = Lock(path)
    second.acquire()  # free again
    second.release()


def _holder(path):
    """Another process that holds the lock ``path`` (for 60 s), once it holds it."""
    holder = forkserver.popen(
        [], code="import sys, time; from sweep.store.lock import Lock;"
        f" Lock({str(path)!r}).acquire(); print('held', flush=True); time.sleep(60)",
        stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    return holder


def test_a_lock_held_by_another_process_is_refused(tmp_path, refused_at_once):
    path = lock_path(tmp_path / "s.h5")
    holder = _holder(path)
    try:
        with pytest.raises(StoreLockedError):
            Lock(path).acquire()
    finally:
        holder.kill()
        holder.wait()
    lock = Lock(path)  # its holder died: the flock went with it, the file is stale
    lock.acquire()
    assert str(holder.pid) in lock.stale_owner
    lock.release()


def test_a_holder_killed_during_the_wait_is_not_refused(tmp_path):
    """A held lock is tried again for KILLED_WRITER_WAIT (1 s) before it is refused: a
    holder killed 0.7 s into the wait (a writer still exiting) lets the next one in.
    (That the wait ends: the refusals of a live holder, here and in test_store*.py.)"""
    path = lock_path(tmp_path / "s.h5")
    holder = _holder(path)
    killer = threading.Timer(0.7, os.kill, (holder.pid, signal.SIGKILL))
    try:
        t0 = time.monotonic()
        killer.start()
        lock = Lock(path)
        lock.acquire()
        waited = time.monotonic() - t0
        lock.release()
    finally:
        killer.cancel()
        holder.kill()
    assert holder.wait(timeout=60) == -signal.SIGKILL
    assert 0.65 < waited < KILLED_WRITER_WAIT, waited


def test_pid_alive():
    assert pid_alive(os.getpid())
    p = forkserver.popen([], code="pass")
    p.wait()
    assert not pid_alive(p.pid)


def test_the_lock_file_names_its_holder(tmp_path):
    path = lock_path(tmp_path / "s.h5")
    lock = Lock(path)
    lock.acquire()
    try:
        who = json.loads(path.read_text())
        assert who["pid"] == os.getpid() and who["host"]
    finally:
        lock.release()


def test_a_lock_naming_a_pid_now_held_by_a_later_process_is_not_a_live_writer(
        tmp_path, monkeypatch):
    """A writer killed by SIGKILL leaves its lock file behind; the kernel may give its pid
    to a later process (pid_max is 32768 on these machines). That process is not the
    writer: ``writer_alive`` (``sweep status``'s "running" or "died") says no, and where
    flock is unavailable a new writer takes the lock over instead of refusing it. The
    lock names the same live process with a ``since`` after its start: alive, refused."""
    import datetime as dt
    import errno
    import socket

    from sweep.store import lock as lk
    store = tmp_path / "s.h5"
    path = lock_path(store)
    later = forkserver.popen([], code="import time; time.sleep(60)")
    try:
        now = dt.datetime.now(dt.UTC)

        def name(since):
            path.write_text(json.dumps({"pid": later.pid, "host": socket.gethostname(),
                                        "since": since.isoformat(timespec="seconds")}))
        name(now - dt.timedelta(hours=1))          # its writer took the lock an hour ago
        assert pid_alive(later.pid) and not lk.writer_alive(store)
        name(now + dt.timedelta(seconds=5))        # the live process took it
        assert lk.writer_alive(store)

        def no_flock(fd, op):
            raise OSError(errno.ENOLCK, "No locks available")
        monkeypatch.setattr(lk.fcntl, "flock", no_flock)
        with pytest.raises(StoreLockedError, match="flock is not available"):
            Lock(path).acquire()
        name(now - dt.timedelta(hours=1))
        lock = Lock(path)
        lock.acquire()
        assert str(later.pid) in lock.stale_owner and not lock.flock
        lock.release()
    finally:
        later.kill()
        later.wait()
