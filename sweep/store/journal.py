"""The journal beside a store: ``<store>.journal``, the durable truth of a campaign.

One line per event, appended by the store's writer, ``fsync``-ed before the HDF5 file is:

- a **campaign line** ``{"journal": "sweep-journal", "version": 3, "campaign_hash": ...,
  "campaign_json": ..., "time": ...}`` written when the journal is created and whenever
  the campaign changes (``--extend``); the last one is the journal's identity, checked
  against the campaign like the store's own attributes;
- a **point record** ``{"row": {column: value}, "profiles": {name: array},
  "residual_history": array}`` per stored point (the whole record). Since version 3 an
  array is ``{"f8": "<base64>", "shape": [...]}``: the base64 of its float64 values,
  little-endian, in C order (:mod:`sweep.store.packed`), exact to the bit, NaN payloads
  included; before, a JSON list of numbers, which is still read. Decoding one is a copy;
  writing one about a sixth of the list's (``benchmarks/store_commit.py``);
- a **hand-out** ``{"handout": hash, "run": n, "worker": rank, "alone": bool}`` per point
  given to a worker, and a **release** ``{"release": hash}`` per point abandoned by a stop
  or whose run's writer died (written, not fsynced: they count the attempts of points
  that kill their worker, ``[run] max_attempts``: :mod:`sweep.store.attempts`).

Every line ends in a checksum: the JSON object's last member is ``"crc32": "<8 hex>"``,
the CRC-32 of the line's bytes with that member removed (so the line stays plain JSON).
A line that fails its checksum, does not parse, lacks a field, or whose ``config_json``
does not hash to its ``hash`` is *set aside*: appended to ``<store>.journal.rejected``
with its reason, removed from the journal, reported, and its point recomputed (unless an
earlier good record of the point exists). Journals written before checksums existed (no
campaign line before their records) are read without the checksum check; the hash re-check
still applies. A torn last line (a writer killed in its write: unacknowledged) is cut off.
"""
from __future__ import annotations

import contextlib
import json
import os
import time
import zlib
from collections.abc import Container, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sweep.errors import BadJournalLineError, StoreError, StoreLockedError
from sweep.identity import HASH_LENGTH, config_hashes_to
from sweep.store.lock import KILLED_WRITER_WAIT, flock_waiting, holders_of
from sweep.store.packed import packed, unpack_record
from sweep.system import fsync_dir, utc_now

__all__ = ["Journal", "JournalScan", "journal_path", "rejected_path",
           "encode", "decode", "check_record", "check_version", "HEADER_KIND",
           "JOURNAL_VERSION"]

HEADER_KIND = "sweep-journal"
#: 3: a record's arrays as base64 float64 (:mod:`sweep.store.packed`); 2: checksummed
#: lines and campaign lines, arrays as JSON lists (still read); 1: neither
JOURNAL_VERSION = 3
_CRC = b',"crc32":"'
_HEX = set("0123456789abcdef")


def journal_path(path: str | Path) -> Path:
    """The journal kept beside a store."""
    return Path(str(path) + ".journal")


def rejected_path(path: str | Path) -> Path:
    """Where journal lines that were set aside go (beside the journal of store ``path``)."""
    return Path(str(path) + ".journal.rejected")


def encode(obj: dict[str, Any]) -> bytes:
    """One journal line: compact JSON ending in its CRC-32 member, and a newline. Arrays
    (``numpy.ndarray``) are packed (:mod:`sweep.store.packed`): a decoded line encodes
    again."""
    body = json.dumps(obj, separators=(",", ":"), default=packed).encode()
    return body[:-1] + b'%s%08x"}\n' % (_CRC, zlib.crc32(body))


def decode(line: bytes, *, require_checksum: bool = True) -> tuple[dict[str, Any], bool]:
    """Parse one journal line; returns ``(object, checksummed)``. A point record's arrays
    are float64 arrays if packed (version 3), lists if not.

    Raises
    ------
    BadJournalLineError
        When the checksum is wrong or missing (``require_checksum``) or the line is not
        a JSON object.
    """
    line = line.rstrip(b"\n")
    i = line.rfind(_CRC)
    checked = i >= 0 and line.endswith(b'"}') and len(line) - i == len(_CRC) + 10
    if checked:
        body = line[:i] + b"}"
        try:
            crc = int(line[i + len(_CRC): i + len(_CRC) + 8], 16)
        except ValueError:
            raise BadJournalLineError("unreadable checksum") from None
        if zlib.crc32(body) != crc:
            raise BadJournalLineError("checksum mismatch (the line was altered after it was"
                                      " written)")
    elif require_checksum:
        raise BadJournalLineError("no checksum")
    else:
        body = line
    try:
        obj = json.loads(body)
    except (ValueError, RecursionError) as exc:
        raise BadJournalLineError(f"not JSON: {exc}") from None
    if not isinstance(obj, dict):
        raise BadJournalLineError("not a JSON object")
    if "row" in obj:
        unpack_record(obj)
    return obj, checked


def _is_hash(h: Any) -> bool:
    return isinstance(h, str) and len(h) == HASH_LENGTH and set(h) <= _HEX


def check_record(obj: dict[str, Any], model_version: str, statuses: tuple[str, ...]) -> str:
    """Why a parsed point record cannot be used ("" when it can).

    Checks the fields a record needs (row, hash, seq, status, profiles) and that its
    ``config_json`` (when present) hashes to its ``hash`` under ``model_version``.
    """
    row = obj.get("row")
    if not isinstance(row, dict):
        return "no 'row' object"
    h = row.get("hash")
    if not _is_hash(h):
        return f"'hash' {str(h)[:80]!r} is not a {HASH_LENGTH}-character hex hash"
    seq = row.get("seq")
    if not isinstance(seq, int) or isinstance(seq, bool) or seq < 0:
        return f"'seq' {seq!r} is not a non-negative integer"
    if row.get("status") not in statuses:
        return f"unknown 'status' {str(row.get('status'))[:40]!r}"
    profiles = obj.get("profiles", {})
    if not isinstance(profiles, dict) or not all(isinstance(v, (list, np.ndarray))
                                                 for v in profiles.values()):
        return "'profiles' is not an object of arrays"
    if not isinstance(obj.get("residual_history", []), (list, np.ndarray)):
        return "'residual_history' is not an array"
    config_json = row.get("config_json")
    if config_json:
        if not isinstance(config_json, str):
            return "'config_json' is not a string"
        if not config_hashes_to(config_json, h, model_version):
            return f"its config does not hash to its hash {h[:12]}"
    return ""


def check_version(scan: JournalScan, path: Path) -> None:
    """Refuse (:class:`StoreError`) a journal with a campaign line of a version beyond
    :data:`JOURNAL_VERSION`: its records may not read here, and none may be set aside."""
    newer = [v for hd in scan.headers if isinstance(v := hd.get("version"), int)
             and not isinstance(v, bool) and v > JOURNAL_VERSION]
    if newer:
        raise StoreError(f"{path}: written by a newer sweep (journal version {max(newer)};"
                         f" this one reads versions up to {JOURNAL_VERSION}); nothing was"
                         " set aside, rebuilt or written: use that sweep")


@dataclass
class JournalScan:
    """What one pass over a journal found."""

    #: campaign lines, in order (the last is the journal's identity)
    headers: list[dict[str, Any]] = field(default_factory=list)
    #: per point hash: (seq, byte offset, status) of its last good record
    latest: dict[str, tuple[int, int, str]] = field(default_factory=dict)
    #: hand-outs per point hash since its last record: [(run, worker, alone), ...]
    handouts: dict[str, list[tuple[int, int, bool]]] = field(default_factory=dict)
    #: lines to set aside: (byte offset, length, reason)
    bad: list[tuple[int, int, str]] = field(default_factory=list)
    records: int = 0
    max_seq: int = -1
    #: the highest run index a record or hand-out names (a rebuilt file's next run
    #: continues from it)
    max_run: int = -1
    legacy: int = 0  # records read without a checksum (journals of before version 2)
    #: a line with a checksum member was seen (the journal is of version 2 or later)
    checksummed: bool = False

    @property
    def identity(self) -> dict[str, Any] | None:
        return self.headers[-1] if self.headers else None


class Journal:
    """Reading, checking, appending and repairing the journal of one store.

    Parameters
    ----------
    path : the journal file (``<store>.journal``).
    rejected : where set-aside lines go (default ``<journal>.rejected``).
    """

    def __init__(self, path: str | Path, rejected: str | Path | None = None) -> None:
        self.path = Path(path)
        self.rejected = Path(rejected) if rejected else Path(str(self.path) + ".rejected")
        self._fh: Any = None
        self.trimmed = 0  # bytes of a torn last line cut off on open

    # ------------------------------------------------------------------ state
    def exists(self) -> bool:
        return self.path.exists()

    def size(self) -> int:
        try:
            return self.path.stat().st_size
        except FileNotFoundError:
            return 0

    def _check_path(self) -> None:
        if self.path.is_dir():
            raise StoreError(f"{self.path}: the journal path is a directory")
        try:
            self.path.stat()
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise StoreError(f"{self.path}: cannot use the journal: {exc.strerror or exc}"
                             ) from None

    # ------------------------------------------------------------------ writing
    def open_for_append(self) -> None:
        """Open (creating) the journal for appending and ``flock`` it.

        Raises :class:`StoreLockedError` when another live process holds it: the second
        guard against two writers (the lock file may have been deleted).
        """
        self._check_path()
        if self._fh is not None:
            return
        fh = self._open_locked(self.path)
        self._fh = fh

    def _open_locked(self, path: Path) -> Any:
        try:
            fh = open(path, "ab")
        except OSError as exc:
            raise StoreError(f"{path}: cannot open the journal: {exc.strerror or exc}"
                             ) from None
        try:
            flock_waiting(fh.fileno(), time.monotonic() + KILLED_WRITER_WAIT)
        except BlockingIOError:

            pids = [p for p in holders_of(path) if p != os.getpid()]
            fh.close()
            raise StoreLockedError(
                f"{path}: the journal is held by a live writer"
                f" ({'pid ' + ', '.join(map(str, pids)) if pids else 'another process'};"
                " its lock file was removed?); wait for it to finish or stop it first"
            ) from None
        except OSError:
            pass  # no flock on this filesystem: the lock file's identity check decides
        return fh

    def append(self, lines: list[bytes], sync: bool = True) -> None:
        """Append complete lines; ``fsync`` them unless ``sync`` is false."""
        if not lines:
            return
        assert self._fh is not None, "open_for_append first"
        self._fh.write(b"".join(lines))
        self._fh.flush()
        if sync:
            os.fsync(self._fh.fileno())

    def write_header(self, campaign_hash: str, campaign_json: str) -> None:
        """Append (and sync) a campaign line."""
        self.append([encode({"journal": HEADER_KIND, "version": JOURNAL_VERSION,
                             "campaign_hash": campaign_hash, "campaign_json": campaign_json,
                             "time": utc_now()})])

    def close(self) -> None:
        if self._fh is not None:
            with contextlib.suppress(OSError):
                self._fh.close()  # closing drops the flock
            self._fh = None

    # ------------------------------------------------------------------ reading
    def trim_torn_tail(self) -> int:
        """Cut a torn last line (a writer killed inside its journal write).

        That point was never acknowledged; left in place, the next record appended would
        be glued to it and unreadable. Returns the bytes cut.
        """
        self._check_path()
        if not self.path.exists():
            return 0
        with open(self.path, "rb+") as fh:
            size = fh.seek(0, os.SEEK_END)
            if size == 0:
                return 0
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return 0
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
        self.trimmed = size - end
        return self.trimmed

    def lines(self) -> Iterator[tuple[int, bytes]]:
        """(byte offset, line) of every complete line."""
        if not self.path.exists():
            return
        offset = 0
        with open(self.path, "rb") as fh:
            for line in fh:
                if not line.endswith(b"\n"):
                    break
                yield offset, line
                offset += len(line)

    def scan(self, model_version: str, statuses: tuple[str, ...],
             grid: Container[str] | None = None) -> JournalScan:
        """One pass over the journal: identity, last good record per point, hand-outs,
        and the lines to set aside (with their reasons).

        The last good record of a point is the one with the highest ``seq`` (not the
        last in the file: a block of old lines appended again must not revert a point).
        With ``grid`` (the hashes of the campaign's grid points), a record of any other
        point is set aside too, wherever it stands and whatever became of the campaign
        lines (one that fails its checksum is set aside itself, and must not make the
        records after it legacy ones): a line of another campaign. Only the records of
        a journal of before version 2 (no line of it checksummed) are read without a
        checksum and without the grid check; such a journal is checked whole by
        :func:`sweep.store.campaign_check.check_legacy_journal`. A journal with any
        checksummed line is read strictly: every line needs its checksum."""
        out = self._scan(model_version, statuses, grid, strict=False)
        if out.legacy and out.checksummed:  # not a legacy journal: read it strictly
            out = self._scan(model_version, statuses, grid, strict=True)
        return out

    def _scan(self, model_version: str, statuses: tuple[str, ...],
              grid: Container[str] | None, strict: bool) -> JournalScan:
        out = JournalScan()
        for offset, line in self.lines():
            if not line.strip():
                continue
            if not out.checksummed and line.rstrip(b"\n").rfind(_CRC) >= 0:
                out.checksummed = True  # a line of version 2 or later (good or not)
            try:
                obj, checked = decode(line, require_checksum=strict or bool(out.headers))
            except BadJournalLineError as exc:
                out.bad.append((offset, len(line), str(exc)))
                continue
            if "journal" in obj:
                if obj.get("journal") != HEADER_KIND or not _is_hash(obj.get("campaign_hash")) \
                        or not isinstance(obj.get("campaign_json"), str):
                    out.bad.append((offset, len(line), "malformed campaign line"))
                else:
                    out.headers.append(obj)
                continue
            if "release" in obj:
                out.handouts.pop(obj["release"], None)
                continue
            if "handout" in obj:
                h = obj["handout"]
                if _is_hash(h):
                    with contextlib.suppress(TypeError, ValueError):
                        out.max_run = max(out.max_run, int(obj.get("run", -1)))
                    out.handouts.setdefault(h, []).append((int(obj.get("run", -1)),
                                                           int(obj.get("worker", -1)),
                                                           bool(obj.get("alone", False))))
                continue
            reason = check_record(obj, model_version, statuses)
            if reason:
                out.bad.append((offset, len(line), reason))
                continue
            row = obj["row"]
            h, seq = row["hash"], int(row["seq"])
            if grid is not None and checked and h not in grid:
                out.bad.append((offset, len(line), f"point {h[:12]} is not in this"
                                " campaign's grid (a line of another campaign?)"))
                continue
            out.records += 1
            out.legacy += not checked
            out.max_seq = max(out.max_seq, seq)
            run = row.get("run")
            if isinstance(run, int) and not isinstance(run, bool):
                out.max_run = max(out.max_run, run)
            if seq > out.latest.get(h, (-1,))[0]:  # by seq, not by file order
                out.latest[h] = (seq, offset, str(row["status"]))
                out.handouts.pop(h, None)
        return out

    def read(self, offsets: set[int] | None = None) -> Iterator[dict[str, Any]]:
        """The parsed records at ``offsets`` (all point records when ``None``), in file
        order; profiles and history as :func:`decode` gives them (arrays, or lists in a
        record of before version 3)."""
        for offset, line in self.lines():
            if offsets is not None and offset not in offsets:
                continue
            try:
                obj, _ = decode(line, require_checksum=False)
            except BadJournalLineError:
                continue
            if "row" in obj:
                yield obj

    def set_aside(self, entries: list[tuple[int, int, str]]) -> None:
        """Move the lines at ``(offset, length, reason)`` to the rejected file, with
        their reasons, and rewrite the journal without them (atomically)."""
        if not entries:
            return
        drop = {off: reason for off, _, reason in entries}
        tmp = self.path.with_name(f".{self.path.name}.rewrite-{os.getpid()}.tmp")
        with open(self.rejected, "ab") as rej:
            for offset, line in self.lines():
                if offset in drop:
                    rej.write(json.dumps({"time": utc_now(), "reason": drop[offset],
                                          "journal_offset": offset,
                                          "line": line.decode("utf-8", "backslashreplace")
                                          .rstrip("\n")}).encode() + b"\n")
            rej.flush()
            os.fsync(rej.fileno())
        try:
            new = self._open_locked(tmp)
            for offset, line in self.lines():  # copy what is kept
                if offset not in drop:
                    new.write(line)
            new.flush()
            os.fsync(new.fileno())
            os.replace(tmp, self.path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
        fsync_dir(self.path)
        had = self._fh is not None
        self.close()
        if had:
            self._fh = new
        else:
            new.close()
