"""The writer's lock: ``<store>.lock``, held with ``flock`` on an open descriptor.

A :class:`Lock` is held by the one process that writes a store (the master of a
``sweep run``, or ``sweep merge``). It is an ``flock`` on the open descriptor of
``<store>.lock``, which holds the writer's identity (host, pid, start time) as JSON;
the kernel drops the flock when the process dies, so the lock of a killed writer is
stale and the next writer takes it over (and records whose it was).

Deleting the lock file of a live run does not let a second writer in: the writer also
holds an ``flock`` on its journal (:meth:`sweep.store.journal.Journal.open_for_append`), and
after taking the lock file's flock a writer checks that the file it locked is still the
one at the path (an unlinked lock file is retried). On filesystems where ``flock`` is
not available (``ENOLCK``/``EOPNOTSUPP``, e.g. NFS without a lock manager) the identity
in the lock file decides: a lock naming another live process on this host, or any
process on another host, is refused; a lock naming a dead process on this host, or a pid
now held by a process that started after the lock was taken (a reused pid), is stale.
HDF5's own file locking is not used (it fails on NFS: h5py issue #1101).
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import fcntl
import json
import os
import socket
import time
from pathlib import Path
from typing import Any

from sweep.errors import StoreError, StoreLockedError

__all__ = ["Lock", "lock_path", "pid_alive", "process_start", "holders_of", "flock_waiting",
           "writer_alive", "KILLED_WRITER_WAIT"]

_NO_FLOCK = {errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL}


#: [s] how long a held lock (or journal) is tried again before it is refused: a writer
#: killed a moment ago releases its flocks within milliseconds.
KILLED_WRITER_WAIT = 1.0


def flock_waiting(fd: int, deadline: float) -> None:
    """``flock(LOCK_EX | LOCK_NB)``, tried again every 20 ms until ``time.monotonic()``
    reaches ``deadline`` (then :class:`BlockingIOError`)."""
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if time.monotonic() >= deadline:
                raise
            time.sleep(0.02)


def lock_path(path: str | Path) -> Path:
    """The lock file kept beside a store."""
    return Path(str(path) + ".lock")


#: [s] how much later than a lock's ``since`` its writer's process may seem to have
#: started (``since`` is cut to the second, the boot time is a whole second).
START_SLACK = 2.0


def process_start(pid: int) -> float | None:
    """When process ``pid`` started, in seconds since the epoch (Linux: ``/proc``), or
    ``None`` where that cannot be read."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        btime = next(int(line.split()[1]) for line in
                     Path("/proc/stat").read_text().splitlines() if line.startswith("btime "))
        return btime + int(fields[19]) / os.sysconf("SC_CLK_TCK")   # field 22, starttime
    except (OSError, IndexError, StopIteration, ValueError):
        return None


def pid_alive(pid: int, since: str | None = None) -> bool:
    """Whether process ``pid`` exists on this host; with ``since`` (a lock's ISO time),
    whether it is the process that took the lock then: the kernel gives a dead writer's
    pid to later processes (pid_max is 32768 on many machines), and one that started
    after ``since`` is another process."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    if since is not None:
        start = process_start(pid)
        try:
            taken = _dt.datetime.fromisoformat(since).timestamp()
        except (TypeError, ValueError):
            return True
        if start is not None and start > taken + START_SLACK:
            return False
    return True


def holders_of(path: str | Path) -> list[int]:
    """Process ids holding an ``flock`` on ``path`` (from ``/proc/locks``; Linux only)."""
    try:
        st = os.stat(path)
        text = Path("/proc/locks").read_text()
    except OSError:
        return []
    inode = f":{st.st_ino}"
    pids = []
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 6 and parts[1] == "FLOCK" and parts[5].endswith(inode):
            with contextlib.suppress(ValueError):
                pids.append(int(parts[4]))
    return pids


def writer_alive(store: str | Path) -> bool:
    """Whether a live process may be writing ``store``: its lock file exists and is
    flock-held, or names a live process on this host, or a process on another host
    (which cannot be checked from here). A writer killed by SIGKILL or a double Ctrl-C
    leaves its lock file behind, held by nobody: not alive."""
    path = lock_path(os.path.realpath(store))
    if holders_of(path):
        return True
    try:
        who = json.loads(path.read_text())
        pid, host = int(who["pid"]), str(who["host"])
    except (OSError, ValueError, KeyError, TypeError):
        return False  # no lock file (released), or one without an identity
    return host != socket.gethostname() or pid_alive(pid, who.get("since"))


def _identity() -> dict[str, Any]:
    return {"pid": os.getpid(), "host": socket.gethostname(),
            "since": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")}


def _describe(text: str) -> str:
    try:
        who = json.loads(text)
        return f"pid {who['pid']} on {who['host']} since {who['since']}"
    except (ValueError, KeyError, TypeError):
        return text.strip() or "owner unknown"


class Lock:
    """An flock-held lock file; a lock file nobody holds is stale and taken over.

    ``stale_owner`` is the identity left by a dead writer whose lock was taken over
    (empty when there was none).
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.fd: int | None = None
        self.stale_owner = ""
        self.flock = True  # False: flock unavailable here, identity check only

    def _open(self) -> int:
        try:
            return os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        except IsADirectoryError:
            raise StoreError(f"{self.path}: the lock file is a directory; remove it") from None
        except OSError as exc:
            raise StoreError(f"{self.path}: cannot create the lock file: {exc.strerror or exc}"
                             ) from None

    def acquire(self) -> None:
        """Take the lock or raise :class:`StoreLockedError` naming its holder.

        A held lock is tried again for :data:`KILLED_WRITER_WAIT` seconds first: a
        writer killed a moment ago may still be exiting (the campaign process of a
        ``sweep run`` whose guard got ``kill -9``, :mod:`sweep.run.guard`)."""
        deadline = time.monotonic() + KILLED_WRITER_WAIT
        for _ in range(20):
            fd = self._open()
            try:
                flock_waiting(fd, deadline)
            except BlockingIOError:
                owner = os.pread(fd, 4096, 0).decode(errors="replace")
                os.close(fd)
                raise StoreLockedError(
                    f"{self.path}: the store is being written by a live campaign"
                    f" ({_describe(owner)}); wait for it to finish or stop it first") from None
            except OSError as exc:
                if exc.errno not in _NO_FLOCK:
                    os.close(fd)
                    raise StoreError(f"{self.path}: cannot lock: {exc.strerror}") from None
                self.flock = False
                self._check_identity(fd)
            # the previous holder may have unlinked the file between our open and flock
            try:
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except OSError:
                same = False
            if not same:
                os.close(fd)
                continue
            self.stale_owner = _describe(os.pread(fd, 4096, 0).decode(errors="replace")) \
                if os.fstat(fd).st_size else ""
            info = json.dumps(_identity()).encode()
            try:
                os.ftruncate(fd, 0)
                os.pwrite(fd, info, 0)
                os.fsync(fd)
            except OSError as exc:  # a full disk, a read-only or failing filesystem
                os.close(fd)
                full = exc.errno in (errno.ENOSPC, errno.EDQUOT)
                raise StoreError(
                    f"{self.path}: cannot write the lock file: {exc.strerror or exc}"
                    + ("; free space and run the same command again (nothing was"
                       " changed)" if full else "")) from None
            self.fd = fd
            return
        raise StoreError(f"{self.path}: the lock file keeps changing; is another writer"
                         " starting?")

    def _check_identity(self, fd: int) -> None:
        """Without flock: refuse a lock that names a live process here or another host."""
        text = os.pread(fd, 4096, 0).decode(errors="replace")
        if not text.strip():
            return
        try:
            who = json.loads(text)
            pid, where = int(who["pid"]), str(who["host"])
        except (ValueError, KeyError, TypeError):
            return
        if where != socket.gethostname() or (pid != os.getpid()
                                             and pid_alive(pid, who.get("since"))):
            os.close(fd)
            raise StoreLockedError(
                f"{self.path}: held by {_describe(text)} and flock is not available on"
                " this filesystem to tell whether that writer is alive; if it is not, remove"
                " the lock file")

    def release(self) -> None:
        """Remove the lock file and drop the flock."""
        if self.fd is None:
            return
        with contextlib.suppress(OSError):
            if os.fstat(self.fd).st_ino == os.stat(self.path).st_ino:
                os.unlink(self.path)
        with contextlib.suppress(OSError):
            fcntl.flock(self.fd, fcntl.LOCK_UN)
        with contextlib.suppress(OSError):
            os.close(self.fd)
        self.fd = None
