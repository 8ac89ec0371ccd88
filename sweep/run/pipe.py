"""Frames over a pair of pipes, for :mod:`sweep.run.store_process` (the master and its
store's writer process), and the forked writer's pid.

A frame is a 5-byte header (the payload's length, uint32 little-endian, and a kind byte)
and a payload: a pickle, or a result's bytes as the worker packed them. The master's side
never blocks on a full pipe while the writer may be writing to it (its writes are
non-blocking and read the writer's frames meanwhile), so neither side can deadlock; and
it waits in slices of :data:`SLICE`, calling its :attr:`Channel.on_wait` between them (the
master's stop signals: a writer that does not answer cannot make it deaf).
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import pickle
import select
import signal
import struct
import subprocess
import time
import traceback
from collections.abc import Callable
from typing import Any

from sweep.errors import StoreError, SweepError
from sweep.system import STOP_SIGNALS

__all__ = ["Channel", "Child", "become_writer", "dumps", "error_bytes", "ADD", "RESULT",
           "HANDOUT", "COMMIT", "RELEASE", "CLOSE", "OK", "STORED", "FAIL"]

_HEAD = struct.Struct("<IB")
# master -> writer
ADD, RESULT, HANDOUT, COMMIT, RELEASE, CLOSE = range(1, 7)
# writer -> master
OK, STORED, FAIL = 10, 11, 12
_PIPE_SIZE = 1 << 20  # [bytes] asked for both pipes (F_SETPIPE_SZ; Linux, best effort)
_F_SETPIPE_SZ = 1031
#: [s] the longest single wait of a channel with an ``on_wait`` check
SLICE = 0.1

def dumps(obj: Any) -> bytes:
    return pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)


class Channel:
    """Frames over a pair of pipe descriptors (``fd_in`` read, ``fd_out`` written)."""

    def __init__(self, fd_in: int, fd_out: int, *, nonblocking_writes: bool) -> None:
        self.fd_in, self.fd_out = fd_in, fd_out
        self.buf = bytearray()
        self.eof = False
        self.nonblocking_writes = nonblocking_writes
        #: called between the slices of a wait (it may raise to end the wait)
        self.on_wait: Callable[[], None] | None = None
        for fd in (fd_in, fd_out):
            with contextlib.suppress(OSError, AttributeError):
                fcntl.fcntl(fd, _F_SETPIPE_SZ, _PIPE_SIZE)
        if nonblocking_writes:
            os.set_blocking(fd_out, False)

    def _fill(self, timeout: float | None) -> bool:
        """Read what is there (waiting up to ``timeout`` [s], ``None``: forever); False
        when nothing came."""
        if self.eof:
            return False
        ready, _, _ = select.select([self.fd_in], [], [], timeout)
        if not ready:
            return False
        chunk = os.read(self.fd_in, 1 << 20)
        if not chunk:
            self.eof = True
            return False
        self.buf += chunk
        return True

    def _frames(self) -> list[tuple[int, bytes]]:
        frames = []
        buf, pos = self.buf, 0
        while len(buf) - pos >= _HEAD.size:
            size, kind = _HEAD.unpack_from(buf, pos)
            end = pos + _HEAD.size + size
            if len(buf) < end:
                break
            frames.append((kind, bytes(buf[pos + _HEAD.size:end])))
            pos = end
        if pos:
            del buf[:pos]
        return frames

    def read(self, timeout: float | None = None) -> list[tuple[int, bytes]]:
        """The frames that arrived, waiting up to ``timeout`` for the first (``[]`` on
        timeout or at the end of the pipe: :attr:`eof`)."""
        frames = self._frames()
        deadline = None if timeout is None else time.monotonic() + timeout
        while not frames and not self.eof:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if self.on_wait is not None:
                left = SLICE if left is None else min(left, SLICE)
            if not self._fill(left):
                if self.eof or (deadline is not None and time.monotonic() >= deadline):
                    break
                if self.on_wait is not None:
                    self.on_wait()
                continue
            frames = self._frames()
        while self._fill(0.0):  # and whatever else is already there
            pass
        return frames + self._frames()

    def write(self, kind: int, payload: bytes = b"") -> None:
        """Send one frame. Non-blocking writes read the other side's frames while the
        pipe is full (they stay buffered for :meth:`read`)."""
        data = memoryview(_HEAD.pack(len(payload), kind) + payload)
        while data:
            if self.nonblocking_writes:
                rd, wr, _ = select.select([] if self.eof else [self.fd_in], [self.fd_out],
                                          [], None if self.on_wait is None else SLICE)
                if rd:
                    self._fill(0.0)
                if not wr:
                    if not rd and self.on_wait is not None:
                        self.on_wait()
                    continue
                try:
                    n = os.write(self.fd_out, data)
                except BlockingIOError:
                    continue
            else:
                n = os.write(self.fd_out, data)
            data = data[n:]

    def close(self) -> None:
        for fd in (self.fd_in, self.fd_out):
            with contextlib.suppress(OSError):
                os.close(fd)


def error_bytes(exc: BaseException) -> bytes:
    """``exc`` pickled for the master (with the writer's traceback as a note when it is
    not one of sweep's own errors); a :class:`StoreError` naming it when it cannot be."""
    if not isinstance(exc, SweepError):
        with contextlib.suppress(Exception):
            exc.add_note("in the store's writer process:\n" + "".join(
                traceback.format_exception(exc)))
    try:
        data = dumps(exc)
        pickle.loads(data)
        return data
    except Exception:  # noqa: BLE001 - an exception that does not survive pickling
        return dumps(StoreError(f"the store's writer process: {type(exc).__name__}: {exc}"))


class Child:
    """A forked child's pid, with :class:`subprocess.Popen`'s ``poll``/``wait``/``kill``
    and its CPU time (:attr:`cpu`, from the kernel's accounting when it is reaped)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.returncode: int | None = None
        #: [s] the child's CPU time, user and system, from its whole life (once reaped)
        self.cpu = 0.0

    def poll(self) -> int | None:
        if self.returncode is None:
            with contextlib.suppress(ChildProcessError):
                pid, status, usage = os.wait4(self.pid, os.WNOHANG)
                if pid == self.pid:
                    self.returncode = os.waitstatus_to_exitcode(status)
                    self.cpu = usage.ru_utime + usage.ru_stime
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        delay = 0.001
        while self.poll() is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise subprocess.TimeoutExpired(f"pid {self.pid}", timeout or 0.0)
            time.sleep(delay)
            delay = min(2 * delay, 0.05)
        return self.returncode  # type: ignore[return-value]

    def kill(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.kill(self.pid, signal.SIGKILL)


def become_writer(keep: tuple[int, int]) -> None:
    """In the forked child: stop signals ignored (the master decides when to stop), no
    signal wake-up descriptor, and no descriptor of the master's kept open (MPI's among
    them) but stdin/stdout/stderr and the two pipe ends ``keep``."""
    for sig in STOP_SIGNALS:
        with contextlib.suppress(ValueError, OSError):
            signal.signal(sig, signal.SIG_IGN)
    with contextlib.suppress(ValueError, OSError):
        signal.set_wakeup_fd(-1)
    try:
        fds = [int(name) for name in os.listdir("/proc/self/fd")]
    except OSError:
        fds = list(range(3, 1024))
    for fd in fds:
        if fd > 2 and fd not in keep:
            with contextlib.suppress(OSError):
                os.close(fd)
