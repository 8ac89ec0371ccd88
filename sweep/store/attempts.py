"""Which points a run that ended without their results may have been running.

A point's hand-out is journaled before its task goes out (:mod:`sweep.store.journal`);
a hand-out with no record after it is a point the run did not finish. Every such point may
have been the one running when the run died, and :func:`running` names them all (the
master computes each alone, so that a death while it runs is its attempt, ``[run]
max_attempts``). Only the earliest unfinished hand-out of each worker cannot be told
apart from the rest: a worker computes its tasks in the order they were sent, but results
are committed in groups, so the tasks before the one that killed the run may have
finished with their results not yet committed, and look queued (the store torture's
"exit 0 in a point", tests/sweep/test_store_holes.py: with only the earliest as the
suspect, the point that exits was never computed alone and the campaign never finished).

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
    """The points that may have been running when a run died: every point with a
    hand-out not finished (its result not stored, and not released)."""
    return {h for h, tries in scan.handouts.items() if tries}


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
