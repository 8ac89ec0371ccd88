"""The result store: one HDF5 file written only by the master, a journal and a lock.

The parts: :mod:`sweep.store.lock` (who may write), :mod:`sweep.store.journal` (the durable truth,
checksummed lines), :mod:`sweep.store.writer` (the HDF5 file), :mod:`sweep.store.reader` (reading
stored rows back), :mod:`sweep.store.campaign_check` (is this the store's campaign, or an
``--extend`` of it), :mod:`sweep.store.record` (what a point is), :mod:`sweep.store.files`
(the file's state, free space, the inode lock), :mod:`sweep.store.repair` (rebuilding from
the journal). :class:`Store` is the policy that ties them together.

Writing points (group commit): :meth:`Store.add` stages a point (converted to the
schema's kinds; nothing is written); :meth:`Store.commit` makes every staged point
durable at once: (1) append one checksummed journal line per point and ``fsync`` the
journal once; (2) write the profile groups and table rows, raise ``n_rows`` (the
commit); (3) flush and ``fsync`` the HDF5 file. A point counts as stored only when
:meth:`commit` has returned.

Opening (all with stop signals deferred, so a stop can never interrupt it half-way):

1. take the lock; cut a torn last journal line; scan the journal (checksums, hash
   re-check; bad lines are set aside to ``<store>.journal.rejected`` with a message);
2. inspect the file: absent, clean, *unclean* (its ``writer_open`` flag shows its writer
   died), *damaged* (provably a sweep store that cannot be read: an empty file or one
   with the HDF5 signature that HDF5 fails on), or not ours (not HDF5, a directory, no
   permission, another format: refused, never touched);
3. check the campaign against the file's identity *and* the journal's;
4. an absent, unclean or damaged file is **rebuilt from the journal atomically**: into a
   temporary file in the same directory, flushed, ``fsync``-ed, then ``os.replace``-d
   over the store (a damaged file is first kept as ``<store>.damaged-<time>``, and the
   message says so); a kill at any instant leaves the old file or the new one;
5. open the file, set ``writer_open`` *before* changing anything, drop rows and profile
   groups beyond the last commit, write journal records newer than the file (a record
   that cannot be written is set aside once with its reason).
"""
from __future__ import annotations

import contextlib
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py

import floewave
from sweep.errors import (
    SchemaVersionError,
    StoreError,
)
from sweep.identity import canonical_json
from sweep.store.attempts import ends_whole
from sweep.store.campaign_check import check_campaign, check_legacy_journal, grid_hashes
from sweep.store.cells import text
from sweep.store.files import H5_ERRORS, MAX_NAME, InodeLock, check_space, inspect_file, oserror
from sweep.store.journal import (
    JOURNAL_VERSION,
    Journal,
    JournalScan,
    check_version,
    encode,
    journal_path,
    rejected_path,
)
from sweep.store.lock import Lock, lock_path
from sweep.store.migrate import migrate
from sweep.store.record import Record
from sweep.store.repair import JournalRepair
from sweep.store.schema import STATUSES
from sweep.store.writer import (
    H5Writer,
    set_campaign,
)
from sweep.system import fsync_dir, fsync_path, signals_deferred, utc_now

__all__ = ["Store"]

def _stderr(message: str) -> None:
    print(f"sweep: {message}", file=sys.stderr, flush=True)


def _json(text: str) -> dict[str, Any]:
    return json.loads(text)


class Store(JournalRepair):
    """The single writer of a campaign store.

    Parameters
    ----------
    path : the HDF5 file (created if missing).
    campaign : the :class:`sweep.config.Campaign` being run; the store and its journal
        must belong to it (same definition hash) unless ``extend`` is true.
    extend : accept a store of the same base whose swept values are a subset of the
        campaign's (new grid values are added; old points stay).
    lock, journal : injectable parts (tests); default :class:`sweep.store.lock.Lock` of
        ``<path>.lock`` and :class:`sweep.store.journal.Journal` of ``<path>.journal``.
    report : called with one line per notable event of the open (set-aside lines,
        rebuilds, damaged files kept aside); default: printed to stderr.
    verify : compare a clean file with the journal's checksummed records
        (:func:`sweep.store.verify.differences`); a file whose values differ is damaged
        (bit rot) and rebuilt from the journal, kept aside first.

    Raises
    ------
    StoreLockedError, SchemaVersionError, CampaignMismatchError, StoreError
    """

    def __init__(self, path: str | Path, campaign: Any = None, *, extend: bool = False,
                 run_info: dict[str, Any] | None = None, lock: Any = None,
                 journal: Journal | None = None,
                 report: Callable[[str], None] | None = None, verify: bool = False) -> None:
        self._verify = verify
        if len(os.fsencode(Path(path).name)) > MAX_NAME:
            raise StoreError(f"{str(path)[:200]}...: the store's file name is too long (at"
                             f" most {MAX_NAME} bytes: the journal and temporary files"
                             " beside it add to it)")
        if os.path.islink(path) and not os.path.exists(path):
            raise StoreError(f"{path}: a symbolic link to nothing; remove it or use"
                             " another --store")
        # the file reached, not the name given: a symlink and its target are one store
        # (one lock, one journal); hard links are caught by the flock on the file itself
        self.path = Path(os.path.realpath(path))
        self._inode = InodeLock(self.path)
        self.journal = journal or Journal(journal_path(self.path), rejected_path(self.path))
        self.journal_path = self.journal.path
        self._lock = lock or Lock(lock_path(self.path))
        self.report = report or _stderr
        self.notes: list[str] = []
        self.w: H5Writer | None = None
        self.repaired_from_journal = False
        self.replayed = self.orphans_removed = 0
        self.set_aside: list[str] = []
        self.damaged_kept = ""
        self._broken = False
        self._staged: list[Record] = []
        self._lines: list[bytes] = []
        self.scan = JournalScan()
        self._grid: frozenset[str] | None = None
        parent = self.path.parent
        try:
            parent.stat()
        except FileNotFoundError:
            pass
        except OSError as exc:  # a name too long, a loop of symlinks...
            shown = str(path) if len(str(path)) <= 200 else f"{str(path)[:200]}..."
            raise StoreError(f"{shown}: cannot use this path: {exc.strerror or exc}"
                             ) from None
        if not parent.is_dir():
            raise StoreError(f"{self.path}: directory {parent} does not exist")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise StoreError(f"{self.path}: directory {parent} is not writable")
        self._lock.acquire()
        try:
            with signals_deferred():
                self._open(campaign, extend)
                self.run_index = self._start_run(run_info or {})
        except BaseException:
            self._abandon()
            raise

    # ------------------------------------------------------------------ opening
    def _open(self, campaign: Any, extend: bool) -> None:
        journal = self.journal
        journal.trim_torn_tail()
        self.journal_trimmed = journal.trimmed
        if journal.exists():
            journal.open_for_append()  # the second guard against two writers
        self._remove_stale_temps()
        if self.path.is_file():
            self._inode.hold(self.path)
        self.model_version = (_json(campaign_json)["model_version"]
                              if (campaign_json := self._campaign_json(campaign))
                              else floewave.MODEL_VERSION)
        self._grid = grid_hashes(campaign)
        scan = journal.scan(self.model_version, STATUSES, self._grid)
        check_version(scan, journal.path)  # before any line is set aside
        state, info = inspect_file(self.path, bool(scan.records or scan.identity))
        self._file_schema = info.get("schema_version", "?")
        if campaign is None and state != "ok":
            raise StoreError(f"{self.path}: no usable store here")
        # the campaign check, before anything is changed: the file and the journal
        if campaign is not None:
            if info.get("campaign_json"):
                check_campaign(self.path, _json(info["campaign_json"]), campaign, extend,
                               "store", getattr(self, "_file_schema", "?"))
            if scan.identity is not None:
                check_campaign(self.path, _json(scan.identity["campaign_json"]), campaign,
                               extend, "journal", getattr(self, "_file_schema", "?"))
            elif scan.records and state != "ok":
                check_legacy_journal(self.journal.path, scan.latest, campaign)
        self.scan = scan
        if scan.bad:
            self._set_aside(scan.bad)
            scan = self.scan
        if self._verify and state == "ok" and self.scan.records:
            state, info = self._verified(state, info)
        if state == "damaged" and not scan.records:
            raise StoreError(f"{self.path}: damaged ({info['why']}) and its journal holds no"
                             " record to rebuild it from; the file was left as it is")
        if state != "ok":
            self._rebuild(campaign, self.scan, state, info)
        try:
            self._open_in_place(campaign, extend)
        except StoreError:
            raise
        except H5_ERRORS as exc:
            if not self.scan.records or campaign is None:
                raise StoreError(f"{self.path}: cannot be read ({exc}) and there is no"
                                 " journal to rebuild it from") from None
            self._close_writer()
            self._rebuild(campaign, self.scan, "damaged",
                          {"why": f"{type(exc).__name__}: {exc}"})
            self._open_in_place(campaign, extend)
        scan = self.scan
        if campaign is not None and (not journal.exists() or scan.identity is None or
                                     scan.identity["campaign_hash"]
                                     != campaign.definition_hash() or  # or an older format:
                                     scan.identity.get("version") != JOURNAL_VERSION):
            journal.open_for_append()
            try:
                journal.write_header(campaign.definition_hash(), self._campaign_json(campaign))
            except OSError as exc:
                raise oserror(journal.path, exc, "writing the journal") from None

    @staticmethod
    def _campaign_json(campaign: Any) -> str:
        if campaign is None:
            return ""
        return canonical_json(campaign.definition())

    def _remove_stale_temps(self) -> None:
        """Temporary files of a rebuild or journal rewrite killed half-way (we hold the
        lock, so nobody else is writing them)."""
        for pattern in (f".{self.path.name}.rebuild-*.tmp",
                        f".{self.journal.path.name}.rewrite-*.tmp"):
            for tmp in self.path.parent.glob(pattern):
                with contextlib.suppress(OSError):
                    tmp.unlink()

    def _open_in_place(self, campaign: Any, extend: bool) -> None:
        if not self.path.exists():
            tmp = self.path.with_name(f".{self.path.name}.rebuild-{os.getpid()}.tmp")
            H5Writer.create(tmp, campaign).close()
            fsync_path(tmp)
            self._inode.hold(tmp)
            os.replace(tmp, self.path)
            fsync_dir(self.path)
        check_space(self.path, 0, "opening the store")
        self.w = w = H5Writer.open(self.path)
        f = w.file
        f.attrs["writer_open"] = True  # before anything in the file changes
        w.durable()
        self._migrate(f)
        if campaign is not None and text(f.attrs.get("campaign_hash", "")) != \
                campaign.definition_hash():  # --extend (checked above)
            hist = f.require_group("campaign_history")
            hist.create_dataset(str(len(hist)), data=text(f.attrs["campaign_toml"]),
                                dtype=h5py.string_dtype("utf-8"))
            set_campaign(f, campaign)
        self.orphans_removed = w.prepare()
        newer = {off for h, (seq, off, _) in self.scan.latest.items()
                 if seq > w.seq_of.get(h, -1)}
        quarantined = self._write_records(w, newer)
        self.replayed = len(newer) - quarantined
        self.next_seq = max(max(w.seq_of.values(), default=-1), self.scan.max_seq) + 1
        w.durable()
        self._backfill_journal(w)

    def _migrate(self, f: Any) -> None:
        try:
            migrate(f)
        except SchemaVersionError as exc:
            raise SchemaVersionError(f"{self.path}: {exc}") from None

    def _start_run(self, info: dict[str, Any]) -> int:
        assert self.w is not None
        runs = self.w.file.require_group("runs")
        # after the last run the file or the journal knows of (a rebuild from the
        # journal alone, its old file unreadable, must not start again at 0)
        index = max(len(runs), max((int(n) for n in runs if n.isdigit()), default=-1) + 1,
                    self.scan.max_run + 1)
        g = runs.create_group(str(index))
        g.attrs["started"] = utc_now()
        g.attrs["outcome"] = "running"
        for k, v in info.items():
            g.attrs[k] = v if isinstance(v, (int, float, bool)) else str(v)
        if self._lock.stale_owner:
            g.attrs["took_over_stale_lock"] = self._lock.stale_owner
        if self.repaired_from_journal or self.replayed or self.journal_trimmed or \
                self.set_aside:
            g.attrs["repaired"] = (f"rebuilt from journal: {self.repaired_from_journal};"
                                   f" records replayed: {self.replayed}; torn journal"
                                   f" tail cut: {self.journal_trimmed} bytes; journal lines"
                                   f" set aside: {len(self.set_aside)}")
        self.w.durable()
        return index

    # ------------------------------------------------------------------ queries
    @property
    def rows(self) -> dict[str, int]:
        """Row index per stored hash."""
        return self.w.rows if self.w is not None else {}

    @property
    def file(self) -> Any:
        """The open ``h5py.File`` (``None`` once closed)."""
        return self.w.file if self.w is not None else None

    def __contains__(self, h: str) -> bool:
        return h in self.rows

    def status_of(self, h: str) -> str:
        """The stored status of point ``h``."""
        assert self.w is not None
        return self.w.status_of(h)

    def __len__(self) -> int:
        return len(self.rows)

    def handouts(self, h: str) -> list[tuple[int, int, bool]]:
        """Hand-outs of point ``h`` since its last record (each an attempt that ended
        without a result: its worker or the whole job died)."""
        return self.scan.handouts.get(h, [])

    # ------------------------------------------------------------------ writing
    def put(self, record: Record) -> None:
        """Store one point durably (journal, then HDF5, both synced to disk)."""
        self.add(record)
        self.commit()

    def add(self, record: Record | dict[str, Any]) -> None:
        """Stage one point for the next :meth:`commit` (nothing is written yet).

        ``record`` is a :class:`sweep.store.record.Record` (or a dict of its members,
        converted to the schema's kinds first: :class:`sweep.errors.UnstorableError` if a
        value cannot be; nothing is staged then). A staged point is not stored: a crash or
        :meth:`close` before :meth:`commit` loses it (it was never acknowledged).
        """
        rec = Record.coerce(record).stamped(self.next_seq, self.run_index)
        line = rec.journal_line()
        self.next_seq += 1
        self._lines.append(line)
        self._staged.append(rec)

    def handout(self, hashes: list[tuple[str, int]], alone: bool = False) -> None:
        """Journal that points were handed to workers ``[(hash, worker), ...]`` (written,
        not fsynced: a process kill keeps them, only a machine crash may not); ``alone``:
        the only point in flight (a death then counts as its attempt). Refused while the
        free space is short: the margin is kept for the releases of the points in flight."""
        if not hashes or self._broken:
            return
        lines = [encode({"handout": h, "run": self.run_index, "worker": worker,
                         "alone": alone}) for h, worker in hashes]
        check_space(self.path, 2 * sum(map(len, lines)), "handing out points")
        with signals_deferred():
            try:
                self.journal.append(lines, sync=False)
            except OSError as exc:
                self._broken = True
                raise oserror(self.journal.path, exc, "writing the journal") from None

    def release(self, hashes: list[str]) -> None:
        """Journal that handed-out points were abandoned (no attempt): by a stop, or by a
        failed write (then if the journal still ends in a whole line)."""
        if not hashes or (self._broken and not ends_whole(self.journal.path)):
            return
        with signals_deferred(), contextlib.suppress(OSError):
            self.journal.append([encode({"release": h}) for h in hashes], sync=False)

    @property
    def staged(self) -> int:
        """Points added but not yet committed."""
        return len(self._staged)

    def commit(self) -> int:
        """Make every staged point durable together (group commit); return how many.

        One journal append + ``fsync`` for all of them, then their HDF5 profile groups
        and table rows (one write per column), one ``n_rows`` update, one HDF5 flush +
        ``fsync``. When this returns the points are stored: they survive ``kill -9``.
        Stop signals arriving meanwhile are handled once the commit is done.
        """
        if not self._staged:
            return 0
        if self._broken:
            raise StoreError(f"{self.path}: an earlier write failed; nothing more is stored")
        staged, lines = self._staged, self._lines
        self._staged, self._lines = [], []
        assert self.w is not None
        check_space(self.path, 2 * sum(map(len, lines)), "storing points")
        with signals_deferred():
            try:
                self.journal.append(lines)
            except OSError as exc:
                self._broken = True
                raise oserror(self.journal.path, exc, "writing the journal") from None
            try:
                self.w.write_many(staged)
                self.w.durable()
            except H5_ERRORS as exc:
                # journaled: the next open rebuilds the file from the journal
                self._broken = True
                raise oserror(self.path, exc, "writing the store") from None
        return len(staged)

    # ------------------------------------------------------------------ closing
    def _close_writer(self) -> None:
        if self.w is not None:
            self.w.close()
            self.w = None

    def _abandon(self) -> None:
        """Close everything without marking the file clean (an error on open)."""
        self._close_writer()
        self.journal.close()
        self._inode.release()
        self._lock.release()

    def close(self, outcome: str = "complete") -> None:
        """Record the run's end and outcome, close the file, release the lock.

        Points staged but not committed are dropped (they were never acknowledged).
        After a failed write the file is closed without being marked clean, so the
        next open rebuilds it from the journal.
        """
        self._staged, self._lines = [], []
        with signals_deferred():
            if self.w is not None:
                if not self._broken:
                    try:
                        self.w.trim()
                        g = self.w.file["runs"][str(self.run_index)]
                        g.attrs["ended"] = utc_now()
                        g.attrs["outcome"] = outcome
                        self.w.file.attrs["writer_open"] = False
                        self.w.durable()
                    except H5_ERRORS:
                        pass  # left unclean: rebuilt from the journal next time
                self._close_writer()
            self.journal.close()
            self._inode.release()
            self._lock.release()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        if self.w is not None:
            self.close("complete" if exc_type is None else f"error: {exc_type.__name__}")
