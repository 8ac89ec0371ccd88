"""The writer process's side of :mod:`sweep.run.store_process`: it opens the store,
journals the hand-outs and releases, builds and commits the results in groups, reports
what it stored and closes the store (:func:`serve`, run in the forked child).

Its replies to the master (``OK`` after a hand-out, a ``COMMIT`` or a ``CLOSE``;
``STORED`` after each group commit; ``FAIL`` with the first error, after which nothing
more is stored) go over :mod:`sweep.run.pipe`'s frames.
"""
from __future__ import annotations

import contextlib
import os
import pickle
import time
from typing import Any

from sweep.errors import StoreError
from sweep.protocol import Outcome
from sweep.run.pipe import (
    ADD,
    CLOSE,
    COMMIT,
    FAIL,
    HANDOUT,
    OK,
    RELEASE,
    RESULT,
    STORED,
    Channel,
    dumps,
    error_bytes,
)
from sweep.run.sink import Provenance
from sweep.store.attempts import running
from sweep.store.cells import text
from sweep.store.record import Record

__all__ = ["serve", "ORPHANED", "GROUP_WINDOW", "GROUP_MAX"]

#: [s] how long a staged result may wait for others to share its commit (a group commit
#: costs about 7 ms of CPU, each point in it about 2.5 ms: docs/cluster.md section 4b)
GROUP_WINDOW = 0.05
#: results that are committed at once, whatever the window
GROUP_MAX = 512
#: the outcome recorded when the master's pipe closed without a ``CLOSE``
ORPHANED = "error: the master ended without closing the store"


class _Writer:
    """The writer process's side: one open store, the campaign's points, provenance."""

    def __init__(self, chan: Channel, store: Any, campaign: Any,
                 worker_env: dict[int, dict[str, Any]], git: dict[str, Any]) -> None:
        self.chan = chan
        self.store = store
        self.points = {p.hash: p for p in campaign.points()}
        self.provenance = Provenance(worker_env, git)
        self.staged: list[str] = []   # statuses of the results staged, in order
        self.failed = False           # an error was sent: nothing more is stored

    def _tell(self, kind: int, payload: bytes = b"") -> None:
        """Send the master a frame; a master gone (its pipe closed) is no error here: the
        end of its pipe ends the loop, after what it sent is stored."""
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            self.chan.write(kind, payload)

    def commit(self) -> None:
        if self.failed:
            return
        self.store.commit()
        if self.staged:
            self._tell(STORED, dumps(self.staged))
            self.staged = []

    def handle(self, kind: int, body: bytes) -> str | None:
        """Act on one frame; the run's outcome once it is a ``CLOSE``."""
        if kind == RESULT:
            if not self.failed:
                out: Outcome = pickle.loads(body)
                point = self.points.get(out.hash)
                if point is None:
                    raise StoreError(f"the store's writer process: a result of point"
                                     f" {out.hash[:12]}, which is not in the campaign"
                                     " (protocol error)")
                rec = Record.from_outcome(point, out, None, self.provenance)
                self.store.add(rec)
                self.staged.append(rec.status)
        elif kind == ADD:
            if not self.failed:
                self.store.add(pickle.loads(body))
        elif kind == HANDOUT:
            pairs, alone = pickle.loads(body)
            self.store.handout(pairs, alone=alone)
            self._tell(OK)
        elif kind == RELEASE:
            self.store.release(pickle.loads(body))
        elif kind == COMMIT:
            self.commit()
            self._tell(OK)
        elif kind == CLOSE:
            return pickle.loads(body)
        else:
            raise StoreError(f"the store's writer process: unknown frame kind {kind}")
        return None

    def loop(self) -> None:
        """Serve frames until ``CLOSE`` (or the end of the pipe). Results are committed
        in groups: once :data:`GROUP_WINDOW` has passed since the first staged one, or
        :data:`GROUP_MAX` are staged, or the master asks (``COMMIT``, ``CLOSE``);
        hand-outs are journaled and acknowledged as they come, meanwhile."""
        wall0, cpu0 = time.monotonic(), time.process_time()  # the wall span encloses the CPU's
        first = 0.0  # when the oldest staged result was staged
        while True:
            wait = (None if not self.staged else
                    max(0.0, first + GROUP_WINDOW - time.monotonic()))
            had = len(self.staged)
            frames = self.chan.read(wait)
            outcome = None
            for kind, body in frames:
                try:
                    outcome = self.handle(kind, body)
                except Exception as exc:  # noqa: BLE001 - reported to the master
                    self._fail(exc)
                if outcome is not None:
                    break
            if outcome is None and self.chan.eof:
                outcome = ORPHANED
            if self.staged and not had:
                first = time.monotonic()
            if outcome is not None or (self.staged and (
                    len(self.staged) >= GROUP_MAX or time.monotonic() >= first + GROUP_WINDOW)):
                try:
                    self.commit()
                except Exception as exc:  # noqa: BLE001 - reported to the master
                    self._fail(exc)
            if outcome is not None:
                self.store.close(outcome)
                if outcome != ORPHANED:
                    cpu = time.process_time() - cpu0
                    self._tell(OK, dumps((cpu, time.monotonic() - wall0)))
                return

    def _fail(self, exc: BaseException) -> None:
        if not self.failed:
            self.failed = True
            self.staged = []
            with contextlib.suppress(OSError):
                self._tell(FAIL, error_bytes(exc))


def serve(chan: Channel, opener: Any, args: dict[str, Any]) -> int:
    """The writer process: open the store (``opener(path, campaign, ...)``, as
    :class:`sweep.store.store.Store`), reply what the master asks of it, serve, close."""
    try:
        store = opener(args["path"], args["campaign"], extend=args["extend"],
                       run_info=args["run_info"], verify=args["verify"])
    except BaseException as exc:  # noqa: BLE001 - reported to the master
        chan.write(FAIL, error_bytes(exc))
        return 1
    try:
        column = store.file["table"]["status"][:] if len(store) else []
        statuses = {h: text(column[i]) for h, i in store.rows.items()}
        writer = _Writer(chan, store, args["campaign"], args["worker_env"], args["git"])
        chan.write(OK, dumps({"path": str(store.path), "run_index": store.run_index,
                               "statuses": statuses, "pid": os.getpid(),
                               "handouts": dict(store.scan.handouts),
                               "suspects": running(store.scan)}))
    except BaseException as exc:  # noqa: BLE001 - reported to the master
        with contextlib.suppress(Exception):
            chan.write(FAIL, error_bytes(exc))
        store.close(f"error: {type(exc).__name__}: {exc}")
        return 1
    writer.loop()
    return 0
