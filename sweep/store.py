"""The result store: one HDF5 file written only by the master, plus a journal and a lock.

Writing points (group commit): :meth:`Store.add` stages a point (nothing is written);
:meth:`Store.commit` makes every staged point durable at once:

1. append one JSON line per point (the whole record) to ``<store>.journal`` and ``fsync``
   it once;
2. write each point's profile group ``/profiles/<hh>/<hash>`` (replacing a leftover), then
   the table rows (one slice write per column; the datasets grow in chunks, so they may
   be longer than ``n_rows``), then raise ``/table.attrs["n_rows"]`` (the commit);
3. ``flush`` the HDF5 file and ``fsync`` it once.

A point counts as stored (acknowledged) only when :meth:`commit` has returned;
:meth:`Store.put` is ``add`` + ``commit`` of one point. The journal format is one line per
point, as before, whatever the batch size. On open, rows and profile groups beyond the
last commit are removed, a torn last journal line (a writer killed inside its journal
write; never acknowledged) is cut off so the next record starts on a line of its own, and
journal records missing from the file are written again, so a
point is either wholly present or absent after any crash; if HDF5 left the file
unreadable (``kill -9`` during a metadata write) it is moved aside and rebuilt from the
journal; so is a file whose ``writer_open`` flag shows its writer died (HDF5 may then
hold metadata that opens but reads wrong). ``<store>.lock`` is held with ``flock`` by
the live writer, so a second writer is refused and the lock of a killed writer (whose
flock the kernel released) is taken over.
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import fcntl
import json
import os
import signal
import socket
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from h5py import h5a, h5d, h5g, h5s, h5t

from .errors import CampaignMismatchError, SchemaVersionError, StoreError, StoreLockedError
from .schema import (
    COLUMNS,
    FORMAT,
    HISTORY_VAR,
    MIGRATIONS,
    PROFILE_VARS,
    SCHEMA_VERSION,
    profile_path,
)

__all__ = ["Store", "Record", "journal_path", "lock_path", "utc_now", "read_journal"]

Record = dict[str, Any]
"""A point record: ``{"row": {column: value}, "profiles": {name: array},
"residual_history": array}``."""

_STR = h5py.string_dtype("utf-8")
_DTYPES = {"float": np.float64, "int": np.int64, "str": _STR}
_NP_DTYPES = {"float": np.float64, "int": np.int64, "str": object}
#: The table datasets grow by whole chunks (rows beyond ``n_rows`` are not committed).
_TABLE_CHUNK = 1024
#: Signals whose Python handlers must not run in the middle of a commit (the in-process
#: grace timer raises from its handler); they are delivered when the commit is done.
_DEFERRED_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGUSR1, signal.SIGALRM}


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, _DEFERRED_SIGNALS)
    except (AttributeError, OSError, ValueError):  # pragma: no cover - no pthread_sigmask
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def utc_now() -> str:
    """The current time, ISO 8601 UTC with microseconds."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="microseconds")


def journal_path(path: str | Path) -> Path:
    """The journal kept beside a store."""
    return Path(str(path) + ".journal")


def lock_path(path: str | Path) -> Path:
    """The lock file kept beside a store."""
    return Path(str(path) + ".lock")


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


class _Lock:
    """An flock-held lock file; a lock file nobody holds is stale and taken over."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fd: int | None = None
        self.stale_owner = ""

    def acquire(self) -> None:
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = os.pread(fd, 4096, 0).decode(errors="replace").strip() or "owner unknown"
            os.close(fd)
            raise StoreLockedError(
                f"{self.path}: the store is being written by a live campaign ({owner});"
                " wait for it to finish or stop it first") from None
        self.stale_owner = os.pread(fd, 4096, 0).decode(errors="replace").strip()
        info = json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                           "since": utc_now()})
        os.ftruncate(fd, 0)
        os.pwrite(fd, info.encode(), 0)
        os.fsync(fd)
        self.fd = fd

    def release(self) -> None:
        if self.fd is not None:
            with contextlib.suppress(OSError):
                os.unlink(self.path)
            fcntl.flock(self.fd, fcntl.LOCK_UN)
            os.close(self.fd)
            self.fd = None


def _journal_lines(path: Path) -> Iterator[dict[str, Any]]:
    """The complete records of a journal as parsed JSON (a torn last line is skipped)."""
    if not path.exists():
        return
    with open(path, "rb") as fh:
        for line in fh:
            if not line.endswith(b"\n"):
                break  # torn write of a killed master: that point was never acknowledged
            try:
                yield json.loads(line)
            except ValueError:
                continue


def _with_arrays(rec: dict[str, Any]) -> Record:
    """A parsed journal record with its profiles and history as float64 arrays."""
    rec["profiles"] = {k: np.asarray(v, dtype=np.float64)
                       for k, v in rec.get("profiles", {}).items()}
    rec["residual_history"] = np.asarray(rec.get("residual_history", []), dtype=np.float64)
    return rec


def read_journal(path: str | Path) -> Iterator[Record]:
    """Yield the complete records of a journal (a torn last line is skipped)."""
    for rec in _journal_lines(Path(path)):
        yield _with_arrays(rec)


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _text(value: Any) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def _cell(col: Any, row: dict[str, Any]) -> Any:
    value = row.get(col.name, col.fill)
    if value is None:
        return col.fill
    if isinstance(value, bytes):
        return value.decode()
    return value


_F64 = h5t.IEEE_F64LE
_STR_TYPE = h5t.py_create(_STR, logical=True)
_DCPL = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
_DCPL.set_obj_track_times(False)  # as h5py's create_dataset does by default


def _write_rows(dsid: Any, mtype: Any, start: int, values: np.ndarray) -> None:
    """Write ``values`` to rows ``start, start + 1, ...`` of a 1-D dataset (low level)."""
    fspace = dsid.get_space()
    fspace.select_hyperslab((start,), (len(values),))
    dsid.write(h5s.create_simple((len(values),)), fspace, values, mtype=mtype)


def _dataset(gid: Any, name: str, data: Any) -> None:
    """A contiguous float64 dataset ``name`` in group ``gid`` holding ``data``."""
    arr = np.ascontiguousarray(data, dtype=np.float64)
    space = h5s.create_simple(arr.shape) if arr.ndim else h5s.create(h5s.SCALAR)
    dset = h5d.create(gid, name.encode(), _F64, space, dcpl=_DCPL)
    if arr.size:
        dset.write(h5s.ALL, h5s.ALL, arr)


class Store:
    """The single writer of a campaign store.

    Parameters
    ----------
    path : the HDF5 file (created if missing).
    campaign : the :class:`sweep.config.Campaign` being run; the store must belong to it
        (same definition hash) unless ``extend`` is true.
    extend : accept a store of the same base whose swept values are a subset of the
        campaign's (new grid values are added; old points stay).

    Raises
    ------
    StoreLockedError, SchemaVersionError, CampaignMismatchError, StoreError
    """

    def __init__(self, path: str | Path, campaign: Any = None, *, extend: bool = False,
                 run_info: dict[str, Any] | None = None) -> None:
        self.path = Path(path)
        self.journal_path = journal_path(self.path)
        self.journal_trimmed = 0  # bytes of a torn last journal line cut off on open
        self._lock = _Lock(lock_path(self.path))
        if not self.path.parent.is_dir():
            raise StoreError(f"{self.path}: directory {self.path.parent} does not exist")
        self._lock.acquire()
        try:
            self._trim_journal()
            self._open(campaign, extend)
            try:
                self._repair()
            except OSError as exc:
                if isinstance(exc, StoreError) or not self.journal_path.exists() or \
                        campaign is None:
                    raise
                self._close_file()  # reads fail: rebuild from the journal
                os.replace(self.path, self.path.with_name(self.path.name + ".unclean"))
                self.repaired_from_journal = True
                self._create(campaign)
                self._repair()
            self.run_index = self._start_run(run_info or {})
        except BaseException:
            self._close_file()
            self._lock.release()
            raise
        self._journal = open(self.journal_path, "ab")
        self._staged: list[Record] = []
        self._lines: list[bytes] = []

    # ------------------------------------------------------------------ opening
    def _trim_journal(self) -> None:
        """Cut a torn last line (a writer killed inside its journal write) from the journal.

        That point was never acknowledged; left in place, the next record appended would
        be glued to it, unreadable, and lost if the store were ever rebuilt from the journal.
        """
        path = self.journal_path
        if not path.exists():
            return
        with open(path, "rb+") as fh:
            size = fh.seek(0, os.SEEK_END)
            if size == 0:
                return
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return
            end = size  # find the last newline, reading backwards in blocks
            while end > 0:
                start = max(0, end - 65536)
                fh.seek(start)
                block = fh.read(end - start)
                i = block.rfind(b"\n")
                if i >= 0:
                    end = start + i + 1
                    break
                end = start
            fh.truncate(end)
            fh.flush()
            os.fsync(fh.fileno())
        self.journal_trimmed = size - end

    def _open(self, campaign: Any, extend: bool) -> None:
        self.repaired_from_journal = False
        self.file: h5py.File | None = None
        if self.path.exists():
            try:
                self.file = h5py.File(self.path, "r+")
            except OSError:
                if not self.journal_path.exists():
                    raise StoreError(f"{self.path}: not a readable HDF5 store and no journal"
                                     f" {self.journal_path.name} to rebuild it from") from None
                aside = self.path.with_name(f"{self.path.name}.corrupt-{os.getpid()}")
                os.replace(self.path, aside)
                self.file = None
                self.repaired_from_journal = True
            else:
                self._check_version()
                if bool(self.file.attrs.get("writer_open", False)) and \
                        self.journal_path.exists():
                    # the last writer died without closing: HDF5 may hold half-written
                    # metadata that opens but reads wrong, so rebuild from the journal
                    self._close_file()
                    os.replace(self.path, self.path.with_name(self.path.name + ".unclean"))
                    self.repaired_from_journal = True
        if self.file is None:
            if campaign is None:
                raise StoreError(f"{self.path}: no store here")
            self._create(campaign)
        elif campaign is not None:
            self._check_campaign(campaign, extend)
            self._migrate()

    def _check_version(self) -> None:
        assert self.file is not None
        fmt = _text(self.file.attrs.get("format", ""))
        if fmt != FORMAT:
            raise StoreError(f"{self.path}: not a sweep store (format {fmt!r})")
        version = int(self.file.attrs.get("schema_version", 0))
        if version > SCHEMA_VERSION:
            raise SchemaVersionError(
                f"{self.path}: store schema version {version} is newer than this sweep's"
                f" schema version {SCHEMA_VERSION}; upgrade sweep to use it")
        while version < SCHEMA_VERSION:
            if version not in MIGRATIONS:
                raise SchemaVersionError(f"{self.path}: no migration from schema version"
                                         f" {version} to {SCHEMA_VERSION}")
            version = MIGRATIONS[version][0]

    def _migrate(self) -> None:
        """Migrate an older store step by step (only once the campaign check passed: a
        refused store is left as it was)."""
        assert self.file is not None
        version = int(self.file.attrs.get("schema_version", 0))
        while version < SCHEMA_VERSION:
            version, _, migrate = MIGRATIONS[version]
            migrate(self.file)
            self.file.attrs["schema_version"] = version
            self.file.flush()

    def _create(self, campaign: Any) -> None:
        f = h5py.File(self.path, "w")
        f.attrs["schema_version"] = SCHEMA_VERSION
        f.attrs["format"] = FORMAT
        f.attrs["created"] = utc_now()
        self._set_campaign(f, campaign)
        table = f.create_group("table")
        table.attrs["n_rows"] = 0
        for col in COLUMNS:
            table.create_dataset(col.name, shape=(0,), maxshape=(None,), chunks=(_TABLE_CHUNK,),
                                 dtype=_DTYPES[col.kind])
        f.create_group("profiles")
        f.create_group("runs")
        f.flush()
        self.file = f
        _fsync_dir(self.path)

    @staticmethod
    def _set_campaign(f: h5py.File, campaign: Any) -> None:
        from .identity import canonical_json

        f.attrs["campaign_toml"] = campaign.text
        f.attrs["campaign_json"] = canonical_json(campaign.definition())
        f.attrs["campaign_hash"] = campaign.definition_hash()
        f.attrs["swept_fields"] = json.dumps(list(campaign.swept_fields))

    def _check_campaign(self, campaign: Any, extend: bool) -> None:
        assert self.file is not None
        stored_hash = _text(self.file.attrs.get("campaign_hash", ""))
        if stored_hash == campaign.definition_hash():
            return
        old = json.loads(_text(self.file.attrs["campaign_json"]))
        new = campaign.definition()
        if not extend:
            diff = sorted(k for k in set(old["base"]) | set(new["base"])
                          if old["base"].get(k) != new["base"].get(k))
            sweep_diff = sorted(k for k in set(old["sweep"]) | set(new["sweep"])
                                if old["sweep"].get(k) != new["sweep"].get(k))
            what = ", ".join([f"[base] {k}" for k in diff] + [f"[sweep] {k}" for k in
                                                              sweep_diff]) or "model_version"
            raise CampaignMismatchError(
                f"{self.path}: the store belongs to a different campaign (differs in {what});"
                " use another --store, or --extend to add grid values to this one")
        problems = []
        if old["base"] != new["base"] or old["model_version"] != new["model_version"]:
            problems.append("its [base] (or model version) differs")
        if set(old["sweep"]) != set(new["sweep"]):
            problems.append("its swept dimensions differ")
        else:
            for k, values in old["sweep"].items():
                missing = [v for v in values if v not in new["sweep"][k]]
                if missing:
                    problems.append(f"[sweep] {k} drops {missing}")
        if problems:
            raise CampaignMismatchError(f"{self.path}: cannot --extend this store: "
                                        + "; ".join(problems))
        hist = self.file.require_group("campaign_history")
        hist.create_dataset(str(len(hist)), data=_text(self.file.attrs["campaign_toml"]),
                            dtype=_STR)
        self._set_campaign(self.file, campaign)
        self.file.flush()

    def _repair(self) -> None:
        """Drop uncommitted rows/groups, then write journal records the file lacks."""
        f = self.file
        assert f is not None
        self._parents: dict[str, Any] = {}  # /profiles/<hh> group ids, by hh
        table = f["table"]
        n = int(table.attrs["n_rows"])
        for col in COLUMNS:
            if table[col.name].shape[0] != n:
                table[col.name].resize((n,))
        # low-level ids of the table columns with their memory types (h5py's high-level
        # indexing costs ~50 us per write; ~10 us this way)
        self._columns = [(col, table[col.name].id, _NP_DTYPES[col.kind],
                          h5t.py_create(np.dtype(_DTYPES[col.kind]) if col.kind != "str"
                                        else _STR))
                         for col in COLUMNS]
        hashes = [_text(h) for h in table["hash"][:n]]
        self.rows: dict[str, int] = {h: i for i, h in enumerate(hashes)}
        seqs = table["seq"][:n]
        seq_of = {h: int(s) for h, s in zip(hashes, seqs, strict=False)}
        removed = []
        for hh in list(f["profiles"]):
            for h in list(f["profiles"][hh]):
                if h not in self.rows:
                    del f["profiles"][hh][h]
                    removed.append(h)
        self.next_seq = max(seq_of.values(), default=-1) + 1
        # the last journal record of each hash, kept only while it is newer than the
        # table's row (streamed: the already committed records are not held in memory)
        latest: dict[str, dict[str, Any]] = {}
        for rec in _journal_lines(self.journal_path):
            h, seq = rec["row"]["hash"], int(rec["row"]["seq"])
            self.next_seq = max(self.next_seq, seq + 1)
            if seq > seq_of.get(h, -1):
                latest[h] = rec
            else:
                latest.pop(h, None)
        missing = [_with_arrays(rec) for rec in latest.values()]
        self._write_many(missing)
        self.replayed = len(missing)
        self.orphans_removed = len(removed)
        f.flush()

    def _start_run(self, info: dict[str, Any]) -> int:
        assert self.file is not None
        self.file.attrs["writer_open"] = True
        runs = self.file.require_group("runs")
        index = len(runs)
        g = runs.create_group(str(index))
        g.attrs["started"] = utc_now()
        g.attrs["outcome"] = "running"
        for k, v in info.items():
            g.attrs[k] = v if isinstance(v, (int, float, bool)) else str(v)
        if self._lock.stale_owner:
            g.attrs["took_over_stale_lock"] = self._lock.stale_owner
        if self.repaired_from_journal or self.replayed or self.journal_trimmed:
            g.attrs["repaired"] = (f"rebuilt from journal: {self.repaired_from_journal};"
                                   f" records replayed: {self.replayed}; torn journal"
                                   f" tail cut: {self.journal_trimmed} bytes")
        self._durable()
        return index

    # ------------------------------------------------------------------ queries
    def __contains__(self, h: str) -> bool:
        return h in self.rows

    def status_of(self, h: str) -> str:
        """The stored status of point ``h``."""
        return _text(self.file["table"]["status"][self.rows[h]])

    def __len__(self) -> int:
        return len(self.rows)

    # ------------------------------------------------------------------ writing
    def put(self, record: Record) -> None:
        """Store one point durably (journal, then HDF5, both synced to disk)."""
        self.add(record)
        self.commit()

    def add(self, record: Record) -> None:
        """Stage one point for the next :meth:`commit` (nothing is written yet).

        A staged point is not stored: it is not in the store (``in``, ``len``) and a
        crash or :meth:`close` before :meth:`commit` loses it (it was never
        acknowledged).
        """
        row = dict(record["row"])
        row["seq"] = self.next_seq
        row["run"] = self.run_index
        record = {"row": row, "profiles": record.get("profiles") or {},
                  "residual_history": record.get("residual_history", np.zeros(0))}
        line = json.dumps({"row": {k: _jsonable(v) for k, v in row.items()},
                           "profiles": {k: _jsonable(v) for k, v in
                                        record["profiles"].items()},
                           "residual_history": _jsonable(record["residual_history"])},
                          separators=(",", ":"))
        self.next_seq += 1
        self._lines.append(line.encode() + b"\n")
        self._staged.append(record)

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
        staged, lines = self._staged, self._lines
        self._staged, self._lines = [], []
        with _signals_deferred():
            self._journal.write(b"".join(lines))
            self._journal.flush()
            os.fsync(self._journal.fileno())
            self._write_many(staged)
            self._durable()
        return len(staged)

    def _write_many(self, records: list[Record]) -> None:
        """Write records to the HDF5 file (profiles, then rows, then ``n_rows``); no sync."""
        if not records:
            return
        f = self.file
        assert f is not None
        table = f["table"]
        n = int(table.attrs["n_rows"])
        new_rows: list[dict[str, Any]] = []  # appended at n, n + 1, ...
        old_rows: dict[int, dict[str, Any]] = {}  # committed rows written again
        index_of: dict[str, int] = {}
        for rec in records:
            row = rec["row"]
            h = row["hash"]
            index = index_of.get(h, self.rows.get(h))
            self._write_profiles(rec, replace=index is not None)
            if index is None:
                index = n + len(new_rows)
                new_rows.append(row)
            elif index >= n:
                new_rows[index - n] = row
            else:
                old_rows[index] = row
            index_of[h] = index
        k = len(new_rows)
        for col, dsid, dtype, mtype in self._columns:
            if k:
                if dsid.shape[0] < n + k:
                    dsid.set_extent((-(-(n + k) // _TABLE_CHUNK) * _TABLE_CHUNK,))
                _write_rows(dsid, mtype, n, np.array([_cell(col, row) for row in new_rows],
                                                     dtype=dtype))
            for index, row in old_rows.items():
                _write_rows(dsid, mtype, index, np.array([_cell(col, row)], dtype=dtype))
        if k:
            table.attrs["n_rows"] = n + k  # the commit point of the rows
        for rec in records:
            h = rec["row"]["hash"]
            self.rows[h] = index_of[h]

    def _write_profiles(self, record: Record, replace: bool) -> None:
        """Write ``/profiles/<hh>/<hash>`` (low-level h5py: ~2x faster per point)."""
        f = self.file
        assert f is not None
        h = record["row"]["hash"]
        if replace:
            name = profile_path(h)
            if name in f:
                del f[name]
        profiles = record.get("profiles") or {}
        if not profiles:
            return
        parent = self._parents.get(h[:2])
        if parent is None:
            group = f["profiles"].get(h[:2])
            if group is None:
                group = f["profiles"].create_group(h[:2])
            parent = self._parents[h[:2]] = group.id
        try:
            gid = h5g.create(parent, h.encode())
        except ValueError:  # a leftover of a failed commit
            parent.unlink(h.encode())
            gid = h5g.create(parent, h.encode())
        attr = h5a.create(gid, b"hash", _STR_TYPE, h5s.create(h5s.SCALAR))
        attr.write(np.array(h, dtype=_STR))  # as h5py's attrs["hash"] = h writes it
        for name in PROFILE_VARS:
            _dataset(gid, name, profiles.get(name, ()))
        _dataset(gid, HISTORY_VAR[0], record.get("residual_history", ()))

    def _durable(self) -> None:
        assert self.file is not None
        self.file.flush()
        with contextlib.suppress(Exception):
            os.fsync(self.file.id.get_vfd_handle())

    # ------------------------------------------------------------------ closing
    def _close_file(self) -> None:
        f = getattr(self, "file", None)
        if f is not None:
            with contextlib.suppress(Exception):
                f.close()
            self.file = None

    def close(self, outcome: str = "complete") -> None:
        """Record the run's end and outcome, close the file, release the lock.

        Points staged but not committed are dropped (they were never acknowledged).
        """
        self._staged, self._lines = [], []
        if self.file is not None:
            table = self.file["table"]
            n = int(table.attrs["n_rows"])
            for col in COLUMNS:  # trim the chunk-sized growth
                if table[col.name].shape[0] != n:
                    table[col.name].resize((n,))
            g = self.file["runs"][str(self.run_index)]
            g.attrs["ended"] = utc_now()
            g.attrs["outcome"] = outcome
            self.file.attrs["writer_open"] = False
            self._durable()
            self._close_file()
        if not self._journal.closed:
            self._journal.close()
        self._lock.release()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        if self.file is not None:
            self.close("complete" if exc_type is None else f"error: {exc_type.__name__}")
