"""The store's writer in a process of its own: the master schedules, this process stores.

Under MPI the master (rank 0) forks one child process before any task goes out. It opens
the campaign's :class:`sweep.store.store.Store` and is its only writer: it takes the lock,
journals every hand-out and result, commits the results in groups and closes the store.
The master keeps its scheduling path only: it reads each result's header
(:class:`sweep.protocol.Packed`), passes the result's bytes on unread, and hands a worker
its next task once the writer has journaled the hand-out (measured in docs/cluster.md,
"The store's writer process").

The store's guarantees are kept, across the two processes:

- a hand-out is journaled before its task goes out: :meth:`StoreProcess.handout` returns
  once the writer has written it;
- a result counts as stored (``sweep run``'s counts and progress) only when the writer
  reports it committed (a ``STORED`` frame, sent after :meth:`Store.commit` returned);
- the writer ignores stop signals, like a worker: the master decides when to stop, waits
  for the results in flight and closes the store;
- kill -9 of the whole job kills the writer with it (it is in the job's process group and
  cgroup): a kill inside a commit, which the journal and the rebuild on the next open
  already cover (the kill -9 torture tests);
- a master that ends without closing the store (killed alone): the writer sees its pipe
  close, commits the results it was given (each a whole result) and closes the store,
  the run's outcome saying so;
- a writer that dies: the master's next call raises :class:`StoreError` (exit status 3),
  and the next open rebuilds the store from its journal.

The pipe and its frames: :mod:`sweep.run.pipe`; the writer's side: :mod:`sweep.run.store_writer`.
"""
from __future__ import annotations

import contextlib
import os
import pickle
import subprocess
import sys
import time
import traceback
from pathlib import Path
from typing import Any, Literal

from sweep.config import Point
from sweep.errors import StoreError
from sweep.protocol import Outcome, Packed
from sweep.run.pipe import (
    ADD,
    CLOSE,
    COMMIT,
    FAIL,
    HANDOUT,
    RELEASE,
    RESULT,
    SLICE,
    STORED,
    Channel,
    Child,
    become_writer,
    dumps,
)
from sweep.run.signals import Unanswered
from sweep.run.sink import Provenance
from sweep.run.store_writer import ORPHANED, serve
from sweep.store.attempts import release_orphaned
from sweep.store.store import Store

__all__ = ["StoreProcess", "serve", "ORPHANED", "WRITER_MODES"]

#: ``[run] writer``: "process" (a writer process beside the master, MPI runs) or "inline"
#: (the master writes the store itself, as an in-process run always does).
WRITER_MODES = ("process", "inline")

#: [s] how long :meth:`StoreProcess.close` waits for the writer to close the store
CLOSE_WAIT = 600.0
#: [s] past a stop's grace period, how long the writer may still take to answer (a commit
#: or the close under way) before it is taken for stuck (a hung write) and killed; a
#: writer that is stopped (SIGSTOP) is taken for stuck at once
ANSWER_MARGIN = 5.0
#: [s] how long a killed writer is waited for (in a hung write it ends when the write does)
KILL_WAIT = 5.0


def _stopped(pid: int) -> bool:
    """Process ``pid`` is stopped (SIGSTOP) or traced (Linux's /proc; False elsewhere)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            return fh.read().rpartition(b")")[2].split()[0] in (b"T", b"t")
    except (OSError, IndexError):
        return False


class StoreProcess:
    """The master's side: a :class:`sweep.store.store.Store` written by a child process
    (a :class:`sweep.run.sink.ResultSink`).

    It answers what the campaign loop asks of a store before the run (``h in store``,
    :meth:`status_of`, :meth:`handouts`), stages and commits the master's own records
    (:meth:`add`, :meth:`commit`), journals hand-outs and releases, passes results on
    (:meth:`submit`, :meth:`forward`) and reports which are stored (:meth:`settle`,
    :meth:`take_stored`, :meth:`wait`, :meth:`sync`).

    Raises (on opening, as :class:`Store` does)
    ------
    StoreLockedError, SchemaVersionError, CampaignMismatchError, StoreError
    """

    #: a worker waits for its next hand-out to be journaled; results are committed by
    #: the writer meanwhile
    waits_for: Literal["handout", "commit"] = "handout"

    def __init__(self, path: str | Path, campaign: Any, *, extend: bool = False,
                 run_info: dict[str, Any] | None = None, verify: bool = False,
                 worker_env: dict[int, dict[str, Any]] | None = None,
                 git: dict[str, Any] | None = None, opener: Any = None,
                 stop: Any = None) -> None:
        opener = Store if opener is None else opener
        #: the run's :class:`sweep.run.signals.StopSignals`: after a stop request, every
        #: wait on the writer ends with its grace period (:meth:`_check_stop`)
        self.stop = stop
        self._gave_up = False
        args = {"path": str(path), "campaign": campaign, "extend": extend,
                "run_info": run_info or {}, "verify": verify,
                "worker_env": worker_env or {}, "git": git or {}}
        to_writer = os.pipe()
        to_master = os.pipe()
        for stream in (sys.stdout, sys.stderr):  # not written twice by the child
            with contextlib.suppress(Exception):
                stream.flush()
        try:
            pid = os.fork()
        except OSError as exc:
            for fd in (*to_writer, *to_master):
                os.close(fd)
            raise StoreError(f"{path}: cannot start the store's writer process: {exc}"
                             ) from None
        if pid == 0:  # the writer: never returns
            code = 1
            try:
                become_writer(keep=(to_writer[0], to_master[1]))
                code = serve(Channel(to_writer[0], to_master[1], nonblocking_writes=False),
                             opener, args)
            except BaseException:  # noqa: BLE001 - a writer that cannot report it
                with contextlib.suppress(Exception):
                    traceback.print_exc()
            finally:
                with contextlib.suppress(Exception):
                    sys.stderr.flush()
                os._exit(code)  # no atexit handlers: MPI belongs to the master
        self.proc = Child(pid)
        os.close(to_writer[0])
        os.close(to_master[1])
        self._chan = Channel(to_master[0], to_writer[1], nonblocking_writes=True)
        self._chan.on_wait = self._check_stop
        #: the master's own records' provenance (the writer builds the workers')
        self.provenance = Provenance(args["worker_env"], args["git"])
        self._stored: list[str] = []
        self._closed = False
        #: [s] the writer's CPU, its whole life (open and close in it), once it ended
        self.writer_cpu = 0.0
        #: [s] the writer's CPU from the store's open to the ``CLOSE`` (its own count), and
        #: the wall time of that span
        self.loop_cpu = self.loop_wall = 0.0
        self.label = str(path)
        try:
            info = self._reply()
        except BaseException:
            self._reap()
            raise
        self.path = Path(info["path"])
        self.label = str(self.path)
        self.run_index = info["run_index"]
        self._statuses: dict[str, str] = info["statuses"]
        self._handouts: dict[str, list[tuple[int, int, bool]]] = info["handouts"]
        self._suspects: set[str] = info["suspects"]

    # ------------------------------------------------------------------ queries
    def __contains__(self, h: str) -> bool:
        return h in self._statuses

    def __len__(self) -> int:
        return len(self._statuses)

    def status_of(self, h: str) -> str:
        return self._statuses[h]

    def handouts(self, h: str) -> list[tuple[int, int, bool]]:
        return self._handouts.get(h, [])

    def suspects(self) -> set[str]:
        return set(self._suspects)

    @property
    def pid(self) -> int:
        return self.proc.pid

    # ------------------------------------------------------------------ the pipe
    def _died(self) -> StoreError:
        self._closed = True
        code = self.proc.poll()
        if code is None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                code = self.proc.wait(5.0)
        how = ("is still running" if code is None else
               f"was killed by signal {-code}" if code < 0 else f"exited with status {code}")
        return StoreError(f"{self.label}: the store's writer process (pid {self.proc.pid})"
                          f" {how}; what it committed is stored, and the next run opens the"
                          " store from its journal")

    def _stuck(self) -> bool:
        """A stop's grace period is over and the writer has not answered: it is stopped,
        or :data:`ANSWER_MARGIN` more has passed (not while it opens the store: a stop
        waits for an open or a rebuild, however long, unless the writer is stopped)."""
        stop = self.stop
        if stop is None or not stop.requested:
            return False
        now = time.monotonic()
        late = now >= stop.deadline + ANSWER_MARGIN and hasattr(self, "path")
        return now >= stop.deadline and (late or _stopped(self.proc.pid))

    def _check_stop(self) -> None:
        """Between the slices of every wait on the writer: a stuck writer (:meth:`_stuck`)
        is killed, said so, and :class:`Unanswered` raised (the run stops, resumable: the
        journal holds what it committed)."""
        if not self._stuck():
            return
        self._gave_up = self._closed = True
        self.proc.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(KILL_WAIT)
        print(f"sweep: {self.label}: the store's writer process (pid {self.proc.pid}) did"
              f" not answer within the grace period after {self.stop.requested}; it was"
              " killed: what it committed is stored, and the next run opens the store"
              " from its journal", file=sys.stderr, flush=True)
        raise Unanswered(self.stop.requested)

    def _send(self, kind: int, payload: bytes = b"") -> None:
        if self._closed:
            raise StoreError(f"{self.label}: the store's writer process has ended")
        try:
            self._chan.write(kind, payload)
        except (BrokenPipeError, ConnectionResetError):
            raise self._died() from None

    def _take(self, frames: list[tuple[int, bytes]]) -> list[tuple[int, bytes]]:
        """Keep the ``STORED`` frames' statuses, raise a ``FAIL``; return the rest."""
        rest = []
        for kind, body in frames:
            if kind == STORED:
                self._stored += pickle.loads(body)
            elif kind == FAIL:
                raise pickle.loads(body)
            else:
                rest.append((kind, body))
        return rest

    def _reply(self) -> Any:
        """Wait for the writer's ``OK`` (keeping the ``STORED`` frames before it)."""
        while True:
            frames = self._take(self._chan.read())
            if frames:
                kind, body = frames[0]
                # frames after an OK: only STORED/FAIL can follow unasked (kept above)
                return pickle.loads(body) if body else None
            if self._chan.eof:
                raise self._died()

    # ------------------------------------------------------------------ writing
    def add(self, record: Any) -> None:
        """Stage one record built by the master (``invalid``, ``crashed``)."""
        self._send(ADD, dumps(record))

    def commit(self) -> int:
        """Wait until everything sent so far is committed (group commit in the writer)."""
        if self._gave_up:  # killed as stuck after a stop: nothing more is committed
            return 0
        self._send(COMMIT)
        self._reply()
        return 0

    def forward(self, payload: Packed | Outcome) -> None:
        """Pass one result on to the writer (its bytes as the worker packed them)."""
        data = payload.data if isinstance(payload, Packed) else dumps(payload)
        self._send(RESULT, data)

    def submit(self, point: Point, payload: Packed | Outcome,
               config: dict[str, Any] | None = None) -> None:
        """Pass one worker's result on to the writer, which builds and stores its
        record (:meth:`forward`)."""
        self.forward(payload)

    def settle(self, everything: bool) -> list[str]:
        """:meth:`sync` if ``everything``, else :meth:`take_stored`: the writer commits
        in groups of its own."""
        return self.sync() if everything else self.take_stored()

    def handout(self, hashes: list[tuple[str, int]], alone: bool = False) -> None:
        """Journal hand-outs ``[(hash, worker), ...]``; returns once they are written."""
        if not hashes:
            return
        self._send(HANDOUT, dumps((hashes, alone)))
        self._reply()

    def release(self, hashes: list[str]) -> None:
        """Journal that handed-out points were abandoned (no attempt): by the writer, or
        by the master once the writer has ended without closing the store (it died: the
        points did not kill it; :func:`sweep.store.attempts.release_orphaned`)."""
        if not hashes:
            return
        if not self._closed:
            with contextlib.suppress(StoreError, Unanswered):  # then it has ended
                self._send(RELEASE, dumps(hashes))
                return
        if hasattr(self, "path") and self.proc.poll() is not None:
            release_orphaned(self.path, hashes)

    def take_stored(self) -> list[str]:
        """The statuses of the results committed since the last call (not waiting)."""
        if not self._closed:
            self._take(self._chan.read(0.0))
            if self._chan.eof:
                raise self._died()
        stored, self._stored = self._stored, []
        return stored

    def wait(self, timeout: float) -> list[str]:
        """:meth:`take_stored`, waiting up to ``timeout`` [s] for a commit."""
        if not self._stored and not self._closed:
            self._take(self._chan.read(timeout))
            if self._chan.eof:
                raise self._died()
        return self.take_stored()

    def sync(self) -> list[str]:
        """Wait until every result sent is committed; their statuses (and earlier ones
        not yet taken)."""
        self.commit()
        return self.take_stored()

    # ------------------------------------------------------------------ closing
    @property
    def store_cpu(self) -> float:
        """[s] the writer's CPU from the store's open to its close (its whole life's if
        it did not say)."""
        return self.loop_cpu or self.writer_cpu

    @property
    def store_wall(self) -> float:
        """[s] the wall time of the writer's own count (0.0 without it: its whole life's
        CPU is over no span measured)."""
        return self.loop_wall if self.loop_cpu else 0.0

    def close(self, outcome: str = "complete") -> None:
        """Have the writer commit what it was given, record the run's outcome and close
        the store; wait for it to end. A writer that already ended is only reaped."""
        if not self._closed:
            try:
                self._send(CLOSE, dumps(outcome))
                self.loop_cpu, self.loop_wall = map(float, self._reply() or (0.0, 0.0))
            except StoreError as exc:
                print(f"sweep: {exc}", file=sys.stderr, flush=True)
            except Unanswered:
                pass  # said so
            except Exception as exc:  # noqa: BLE001 - the writer's error at the close
                print(f"sweep: {self.label}: closing the store: {exc}", file=sys.stderr,
                      flush=True)
            self._closed = True
        self._reap()

    def _reap(self) -> None:
        self._closed = True
        self._chan.close()
        end = time.monotonic() + CLOSE_WAIT
        while self.proc.poll() is None:  # up to CLOSE_WAIT, or a stop's grace period
            if time.monotonic() >= end or self._stuck():
                self.proc.kill()
                with contextlib.suppress(subprocess.TimeoutExpired):
                    self.proc.wait(KILL_WAIT)
                break
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(SLICE)
        self.writer_cpu = self.proc.cpu

    def __enter__(self) -> StoreProcess:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        self.close("complete" if exc_type is None else f"error: {exc_type.__name__}")

