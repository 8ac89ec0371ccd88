"""Which points a run that ended without their results may have been running.

A point's hand-out is journaled before its task goes out (:mod:`sweep.store.journal`);
a hand-out with no record after it is a point the run did not finish. A worker computes
its tasks in the order they were sent, so of the unfinished hand-outs of one worker in
one run only the earliest can have been running when the run died; the ones after it were
queued behind it, not started, and cannot have caused the death. :func:`running` names
those points (the master computes each alone, so that a death while it runs is its
attempt, ``[run] max_attempts``); the others are computed as any point is.

A point whose run ended by a failure of the store (a full disk, a write error, its writer
process killed) did not kill its worker: the master journals its release
(:meth:`sweep.store.store.Store.release`; a writer process being dead, the master itself
does, :func:`release_orphaned`), and no attempt is counted.
"""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

from sweep.errors import StoreError
from sweep.store.journal import Journal, JournalScan, encode, journal_path

__all__ = ["running", "ends_whole", "release_orphaned"]


def running(scan: JournalScan) -> set[str]:
    """Per run and worker, the point of the earliest hand-out not finished (its result
    not stored, and not released)."""
    first: dict[tuple[int, int], tuple[int, str]] = {}
    for h, tries in scan.handouts.items():
        for run, worker, _ in tries:
            at = scan.handout_at.get((h, run, worker), -1)
            if (run, worker) not in first or at < first[(run, worker)][0]:
                first[(run, worker)] = (at, h)
    return {h for _, h in first.values()}


def ends_whole(path: Path) -> bool:
    """The journal at ``path`` ends with a whole line (or is empty): a line appended now
    is not glued to a torn one."""
    try:
        with open(path, "rb") as fh:
            size = fh.seek(0, os.SEEK_END)
            return size == 0 or os.pread(fh.fileno(), 1, size - 1) == b"\n"
    except OSError:
        return False


def release_orphaned(store_path: Path, hashes: list[str]) -> bool:
    """Journal the release of ``hashes`` in the journal of the store at ``store_path``,
    whose writer process ended without closing it (the master knows it died: its points
    did not kill it). Only under the journal's ``flock`` (a live writer holds it: nothing
    is written) and after a whole line; returns whether they were written."""
    if not hashes:
        return False
    journal = Journal(journal_path(store_path))
    try:
        journal.open_for_append()
    except (StoreError, OSError):
        return False
    try:
        if not ends_whole(journal.path):
            return False
        with contextlib.suppress(OSError):
            journal.append([encode({"release": h}) for h in hashes], sync=False)
            return True
        return False
    finally:
        journal.close()
