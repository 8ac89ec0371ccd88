"""sweep.store.lock: one live writer per store; a lock left by a dead writer is taken over."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from sweep.errors import StoreLockedError
from sweep.store.lock import Lock, lock_path, pid_alive
from tests import forkserver


def test_a_second_writer_is_refused_while_the_first_holds_the_lock(tmp_path):
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


def test_a_lock_held_by_another_process_is_refused(tmp_path):
    path = lock_path(tmp_path / "s.h5")
    holder = forkserver.popen(
        [], code="import sys, time; from sweep.store.lock import Lock;"
        f" Lock({str(path)!r}).acquire(); print('held', flush=True); time.sleep(60)",
        stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(StoreLockedError):
            Lock(path).acquire()
    finally:
        holder.kill()
        holder.wait()
    lock = Lock(path)  # its holder died: the flock went with it, the file is stale
    lock.acquire()
    assert str(holder.pid) in lock.stale_owner
    lock.release()


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
