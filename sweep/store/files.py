"""The store's file on the filesystem: its state on open, free space, OS errors, inode lock.

:func:`inspect_file` tells an absent, clean, unclean (its writer died) or damaged store
file from one that is not a sweep store (refused, never touched); :func:`check_space`
refuses a write the disk cannot hold; :func:`oserror` words an OS failure in one line;
:class:`InodeLock` write-locks the file itself, so a second writer reaching it under
another name (a hard link) is refused.
"""
from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import re
import stat
import struct
import time
from pathlib import Path
from typing import Any

import h5py

from sweep.errors import SchemaVersionError, StoreError, StoreLockedError
from sweep.store import lock
from sweep.store.cells import text
from sweep.store.migrate import migration_steps
from sweep.store.schema import FORMAT
from sweep.store.writer import HDF5_SIGNATURE

__all__ = ["H5_ERRORS", "IN_USE", "MAX_NAME", "SPACE_RESERVE", "oserror", "check_space",
           "inspect_file", "InodeLock"]

#: Errors h5py raises for a file it cannot read (besides OSError).
H5_ERRORS = (OSError, RuntimeError, ValueError, KeyError, TypeError, IndexError)
#: HDF5 messages that mean "in use", not "damaged".
IN_USE = re.compile(r"\block|already open|temporarily unavailable|\bin use\b", re.I)
#: (HDF5's damage messages name its "sblock" (superblock): "lock" only as a word.)
#: Longest store file name [bytes]: NAME_MAX (255) less what the names beside it add
#: (".NAME.journal.rewrite-<pid>.tmp").
MAX_NAME = 255 - 32
def oserror(path: Path, exc: BaseException, doing: str) -> StoreError:
    """One clear line for an OS-level failure (disk full, permissions...)."""
    errno_ = getattr(exc, "errno", None)
    text = str(exc)
    if errno_ == 28 or "No space left" in text or "errno = 28" in text:
        return StoreError(f"{path}: no space left on the device while {doing}; nothing"
                          " acknowledged was lost: free space and run the same command again")
    return StoreError(f"{path}: {doing} failed: {getattr(exc, 'strerror', None) or text}")


#: Free space [bytes] kept in reserve beyond what a write needs (HDF5 metadata, the
#: journal's next lines): below it a write is refused with one clear line instead of
#: failing half-way inside HDF5 (which can crash the process).
SPACE_RESERVE = 1 << 20


def check_space(path: Path, needed: int, doing: str) -> None:
    """Refuse to start a write that the free space cannot hold (exit 3, one line)."""
    try:
        st = os.statvfs(path.parent)
    except OSError:
        return
    free = st.f_bavail * st.f_frsize
    if free < needed + SPACE_RESERVE:
        raise StoreError(f"{path}: no space left on the device for {doing} ({free >> 10}"
                         f" KiB free, about {(needed + SPACE_RESERVE) >> 10} KiB needed);"
                         " nothing acknowledged was lost: free space and run the same"
                         " command again")


def inspect_file(p: Path, ours: bool) -> tuple[str, dict[str, Any]]:
    """The state of the store file ``p``: ``absent``, ``ok``, ``unclean`` or ``damaged``,
    and what was read (``campaign_json``, ``schema_version``; ``why`` it is damaged).

    ``ours``: its journal holds records or an identity (the file is provably a sweep
    store). Raises :class:`StoreError` for a path that is not (provably) a sweep store.
    """
    try:
        st = os.stat(p)
    except FileNotFoundError:
        if os.path.islink(p):
            raise StoreError(f"{p}: a symbolic link to nothing; remove it or use"
                             " another --store") from None
        return "absent", {}
    except OSError as exc:
        raise StoreError(f"{p}: cannot use this path: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise StoreError(f"{p}: is a directory, not a store file")
    if not stat.S_ISREG(st.st_mode):
        raise StoreError(f"{p}: not a regular file")
    if not os.access(p, os.R_OK | os.W_OK):
        raise StoreError(f"{p}: cannot open the store: permission denied")
    if st.st_size == 0:
        if not ours:
            raise StoreError(f"{p}: an empty file and no journal beside it: not a sweep"
                             " store; remove it or use another --store")
        return "damaged", {"why": "empty file"}
    with open(p, "rb") as fh:
        head = fh.read(8)
    if head != HDF5_SIGNATURE:
        raise StoreError(f"{p}: not an HDF5 file; it was left untouched (use another"
                         " --store)")
    info: dict[str, Any] = {}
    try:
        with h5py.File(p, "r", locking=False) as f:
            fmt = text(f.attrs.get("format", ""))
            if fmt != FORMAT:
                if fmt or not ours:
                    raise StoreError(f"{p}: an HDF5 file but not a sweep store (format"
                                     f" {fmt!r}); it was left untouched")
                return "damaged", {"why": "no format attribute (creation interrupted)"}
            raw = f.attrs.get("schema_version", 0)
            try:
                version = int(raw)
            except (TypeError, ValueError):
                raise StoreError(f"{p}: schema_version {text(raw)!r} is not a version"
                                 " number; it was left untouched") from None
            try:        # a migration path, checked before changes
                migration_steps(version)
            except SchemaVersionError as exc:
                raise SchemaVersionError(f"{p}: {exc}") from None
            info["campaign_json"] = text(f.attrs.get("campaign_json", ""))
            info["schema_version"] = version
            table = f["table"]
            n = int(table.attrs["n_rows"])
            len(table["hash"][:n])  # readable?
            unclean = bool(f.attrs.get("writer_open", False))
    except StoreError:
        raise
    except H5_ERRORS as exc:
        if IN_USE.search(str(exc)):
            raise StoreError(f"{p}: cannot open the store, it is in use ({exc}); close"
                             " the program holding it and run again") from None
        if not ours:
            raise StoreError(f"{p}: cannot be read ({type(exc).__name__}: {exc}) and"
                             " there is no journal to rebuild it from; it was left as"
                             " it is") from None
        return "damaged", {"why": f"{type(exc).__name__}: {exc}"}
    if unclean and ours:
        return "unclean", info
    return "ok", info


class InodeLock:
    """A write lock on the store file itself (its inode), held while a writer has it."""

    def __init__(self, store: Path) -> None:
        self.store = store
        self.fd: int | None = None

    def hold(self, path: Path) -> None:
        """Write-lock the store file itself (its inode) for as long as this writer has
        it: a second writer reaching the same file under another name (a hard link) is
        refused. The lock file and journal are named after the path, which a hard link
        does not share (a symlink is resolved before: ``os.path.realpath``).

        An open-file-description lock (``F_OFD_SETLK``, Linux), not ``flock``: HDF5
        readers that use their file locking take a shared ``flock`` of the file, and
        must still be able to read it during a run; and unlike a POSIX ``lockf`` it is
        not dropped when h5py closes another descriptor of the file in this process.
        Where it is not available (not Linux, ``ENOLCK``...) hard links are not caught.
        """


        cmd = getattr(fcntl, "F_OFD_SETLK", None)
        if cmd is None:
            return
        try:
            fd = os.open(path, os.O_RDWR | os.O_CLOEXEC | os.O_NOFOLLOW)
        except OSError:
            return  # inspect_file says why the path cannot be used
        arg = struct.pack("hhqqi4x", fcntl.F_WRLCK, os.SEEK_SET, 0, 0, 0)
        deadline = time.monotonic() + lock.KILLED_WRITER_WAIT
        while True:
            try:
                fcntl.fcntl(fd, cmd, arg)
                break
            except OSError as exc:
                if exc.errno in (errno.EAGAIN, errno.EACCES) and time.monotonic() < deadline:
                    time.sleep(0.02)  # a writer killed a moment ago may still be exiting
                    continue
                os.close(fd)
                if exc.errno in (errno.EAGAIN, errno.EACCES):
                    raise StoreLockedError(
                        f"{self.store}: the file is being written by another live campaign"
                        " under another name (a hard link to it?); wait for it to finish"
                        " or stop it first") from None
                return  # no such lock on this filesystem
        old, self.fd = self.fd, fd
        if old is not None:
            with contextlib.suppress(OSError):
                os.close(old)

    def release(self) -> None:
        if self.fd is not None:
            with contextlib.suppress(OSError):
                os.close(self.fd)
            self.fd = None
