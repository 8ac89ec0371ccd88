"""Repairing a store from its journal: rebuilt, replayed, bad lines set aside, gaps journaled.

:class:`JournalRepair` is the part of :class:`sweep.store.store.Store` that brings the
HDF5 file and the journal back into agreement on open (the journal is the durable
truth); it uses the store's ``path``, ``journal``, ``scan`` and ``report``.
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py

from sweep.errors import BadJournalLineError, StoreError, UnstorableError
from sweep.store import reader
from sweep.store.cells import text
from sweep.store.files import H5_ERRORS, InodeLock, check_space, oserror
from sweep.store.journal import Journal, JournalScan, decode
from sweep.store.record import Record
from sweep.store.schema import STATUSES
from sweep.store.verify import differences
from sweep.store.writer import H5Writer
from sweep.system import fsync_dir, fsync_path, utc_now

__all__ = ["JournalRepair", "REPLAY_BATCH"]

#: Journal records written per batch while rebuilding or replaying.
REPLAY_BATCH = 256



class JournalRepair:
    """Rebuild, replay and set-aside steps of a store's open (a mixin of ``Store``)."""

    path: Path
    journal: Journal
    scan: JournalScan
    model_version: str
    report: Callable[[str], None]
    notes: list[str]
    set_aside: list[str]
    damaged_kept: str
    repaired_from_journal: bool
    _grid: frozenset[str] | None
    _inode: InodeLock

    def _note(self, message: str) -> None:
        self.notes.append(message)
        self.report(message)

    def _verified(self, state: str, info: dict[str, Any]) -> tuple[str, dict[str, Any]]:
        """``--verify``: the clean file against the journal. Values that differ make it
        damaged (rebuilt from the journal), unless it holds points the journal lacks
        (a rebuild would drop them: they are journaled first, the next --verify
        rebuilds)."""
        try:
            found, _, missing = differences(self.path, self.journal)
        except H5_ERRORS as exc:
            return "damaged", {"why": f"cannot be compared with its journal:"
                                      f" {type(exc).__name__}: {exc}"}
        if not found:
            self._note(f"{self.path}: verified: every stored value is its journal's")
            return state, info
        if missing:
            self._note(f"{self.path}: {len(found)} value(s) differ from the journal (e.g."
                       f" {found[0]}) but {len(missing)} stored point(s) are not in it:"
                       " not rebuilt now (they are journaled first; run --verify again)")
            return state, info
        return "damaged", {"why": f"{len(found)} value(s) differ from the journal's"
                                  f" checksummed records, e.g. {found[0]}"}

    def _set_aside(self, bad: list[tuple[int, int, str]]) -> None:
        try:
            self.journal.set_aside(bad)
        except OSError as exc:
            raise oserror(self.journal.path, exc, "setting journal lines aside") from None
        # offsets moved
        self.scan = self.journal.scan(self.model_version, STATUSES, self._grid)
        reasons: dict[str, int] = {}
        for _, _, reason in bad:
            reasons[reason] = reasons.get(reason, 0) + 1
        detail = "; ".join(f"{n} x {r}" for r, n in reasons.items())
        self.set_aside.extend(r for _, _, r in bad)
        self._note(f"{self.journal.path}: {len(bad)} journal line(s) set aside to"
                   f" {self.journal.rejected} ({detail}); their points are computed again")

    def _rebuild(self, campaign: Any, scan: JournalScan, state: str,
                 info: dict[str, Any]) -> None:
        """Build the store from the journal into a temporary file, then replace."""
        tmp = self.path.with_name(f".{self.path.name}.rebuild-{os.getpid()}.tmp")
        size = self.path.stat().st_size if self.path.exists() else 0
        check_space(self.path, max(size, self.journal.size() // 2), "rebuilding the store")
        w: H5Writer | None = None
        try:
            w = H5Writer.create(tmp, campaign)
            w.prepare()
            quarantined = self._write_records(w, {off for _, off, _ in scan.latest.values()})
            self._copy_runs(w.file)
            w.trim()
            w.file.attrs["rebuilt_from_journal"] = utc_now()
            w.durable()
            w.close()
            w = None
            fsync_path(tmp)
            if state == "damaged":
                stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%S")
                aside = self.path.with_name(f"{self.path.name}.damaged-{stamp}-{os.getpid()}")
                try:
                    os.link(self.path, aside)  # the damaged file stays where it is too
                except OSError:
                    os.replace(self.path, aside)
                self.damaged_kept = str(aside)
            self._inode.hold(tmp)  # the new file is held before it has the store's name
            os.replace(tmp, self.path)
            fsync_dir(self.path)
        except BaseException as exc:
            if w is not None:
                w.close()
            with contextlib.suppress(OSError):
                tmp.unlink()
            if isinstance(exc, OSError) and not isinstance(exc, StoreError):
                raise oserror(self.path, exc, "rebuilding the store from its journal"
                               ) from None
            raise
        self.repaired_from_journal = True
        n = len(scan.latest) - quarantined
        if state == "damaged":
            self._note(f"{self.path}: damaged ({info.get('why', '?')}); kept as"
                       f" {self.damaged_kept}; rebuilt from the journal ({n} points)")
        elif state == "unclean":
            self._note(f"{self.path}: its last writer did not close it (killed?); rebuilt"
                       f" from the journal ({n} points)")
        elif n:
            self._note(f"{self.path}: missing; rebuilt from the journal ({n} points)")

    def _copy_runs(self, new: Any) -> None:
        """Keep the ``/runs`` history of the file being rebuilt, when it can be read
        (an unclean file; a damaged one may not be); a run still "running" there died."""
        if not self.path.is_file():
            return
        try:
            with h5py.File(self.path, "r", locking=False) as old:
                if "runs" not in old:
                    return
                for name in old["runs"]:
                    old.copy(old["runs"][name], new["runs"], name=name)
                    g = new["runs"][name]
                    if text(g.attrs.get("outcome", "")) == "running":
                        g.attrs["outcome"] = "died (its writer did not close the store)"
        except H5_ERRORS:
            pass  # the history is lost with the damaged file (kept aside)

    def _write_records(self, w: H5Writer, offsets: set[int]) -> int:
        """Write the journal records at ``offsets``; set aside those that cannot be
        written (once, with the reason). Returns how many were set aside."""
        bad: list[tuple[int, int, str]] = []
        batch: list[Record] = []
        if not offsets:
            return 0
        for offset, line in self.journal.lines():
            if offset not in offsets:
                continue
            try:
                obj, _ = decode(line, require_checksum=False)
                batch.append(Record.coerce(obj))
            except (BadJournalLineError, UnstorableError) as exc:
                bad.append((offset, len(line), f"cannot be written to HDF5: {exc}"))
                continue
            if len(batch) >= REPLAY_BATCH:
                w.write_many(batch)
                batch = []
        w.write_many(batch)
        if bad:
            self._set_aside(bad)
        return len(bad)

    def _backfill_journal(self, w: H5Writer) -> None:
        """Journal the committed rows the journal lacks (it was deleted, or predates
        them): the journal is what a rebuild uses, so it must hold every stored point."""
        missing = [h for h in w.rows if h not in self.scan.latest]
        if not missing:
            return
        lines = [rec.journal_line()
                 for rec in reader.iter_records(w.file, set(missing), normalise=False)]
        self.journal.open_for_append()
        check_space(self.journal.path, 2 * sum(map(len, lines)), "journaling stored points")
        try:
            self.journal.append(lines)
        except OSError as exc:
            raise oserror(self.journal.path, exc, "writing the journal") from None
        self._note(f"{self.journal.path}: {len(missing)} stored point(s) were not in the"
                   " journal (removed or older than it); journaled again from the store")
        self.scan = self.journal.scan(self.model_version, STATUSES, self._grid)
