"""Which points a run that ended without their results may have been running.

A point's hand-out is journaled before its task goes out (:mod:`sweep.store.journal`);
a hand-out with no record after it is a point the run did not finish. A worker computes
its tasks in the order they were sent, so of the unfinished hand-outs of one worker in
one run only the earliest can have been running when the run died; the ones after it were
queued behind it, not started, and cannot have caused the death. :func:`running` names
those points (the master computes each alone, so that a death while it runs is its
attempt, ``[run] max_attempts``); the others are computed as any point is.
"""
from __future__ import annotations

from sweep.store.journal import JournalScan

__all__ = ["running"]


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
