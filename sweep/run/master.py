"""The master of a campaign run: schedules points onto workers, stores each result.

The master (:class:`Master`) is a small state machine over a transport
(:mod:`sweep.run.transport`): keep every worker supplied with the costliest pending points,
wait (blocking with backoff, never a hot spin) for a result, take every other result
already waiting, store them all with one group commit (:meth:`sweep.store.store.Store.commit`:
one journal fsync, one HDF5 flush), count them as stored, repeat; ``None`` is the stop
message. A worker holds one task at a time while points are slow; when points take less
than a few commits' time it is given a short queue of tasks (up to :data:`_MAX_DEPTH`)
so that it computes while the master commits.

The results go to a :class:`sweep.run.sink.ResultSink`: the master writing the store
itself (:class:`sweep.run.sink.InlineSink`: each result becomes one
:class:`sweep.store.record.Record`, a batch one group commit), or a writer process
(:class:`sweep.run.store_process.StoreProcess`, MPI runs by default: the master passes
each result's bytes on unread and hands its worker the next task once the hand-out is
journaled; the writer commits in groups and reports what it stored). Either way a point
counts as stored only once its sink says so.
"""
from __future__ import annotations

import collections
import math
import time
from dataclasses import dataclass, field
from typing import Any

from sweep.config import Point
from sweep.errors import Interrupted, WorkerError
from sweep.protocol import Kind, Outcome, Task, WorkerFailure
from sweep.run.compute import DEFAULT_COMPUTE
from sweep.run.progress import Progress
from sweep.run.signals import GraceExpired, StopSignals, Unanswered
from sweep.run.sink import ResultSink
from sweep.run.transport import Transport
from sweep.store.record import Record

__all__ = ["Master", "RunSummary"]

#: Group commit: at most this many results per commit, and at most this long [s] between
#: taking the first result of a batch and committing it.
_MAX_BATCH, _BATCH_WINDOW = 512, 0.2
#: Tasks queued per worker at most. The depth is 1 + commit time / (share x point time):
#: 1 for points much longer than a commit, more for quick points, so that commits cost
#: the workers at most about ``_COMMIT_SHARE`` of their time.
_MAX_DEPTH, _COMMIT_SHARE = 64, 0.1


@dataclass
class RunSummary:
    """What one ``sweep run`` did."""

    total: int = 0
    skipped: int = 0
    computed: int = 0
    counts: dict[str, int] = field(default_factory=dict)
    interrupted: str = ""
    abandoned: int = 0
    elapsed: float = 0.0
    master_cpu: float = 0.0
    loop_elapsed: float = 0.0
    #: the master computed the points itself (no MPI workers): its CPU share is the
    #: computation's, not the scheduling overhead, and is not reported
    in_process: bool = False
    #: [s] compiling or loading the kernels before the first point (:mod:`sweep.run.warmup`)
    warm_up: float = 0.0
    #: CPU seconds of the store's writer process from its store's open to its close (0: the
    #: master wrote the store itself), and the wall seconds of that span (0: not measured)
    writer_cpu: float = 0.0
    writer_wall: float = 0.0

    @property
    def master_cpu_share(self) -> float:
        """CPU seconds of the master per wall second of the scheduling loop (start-up
        -- imports, grid expansion, store opening -- excluded)."""
        return self.master_cpu / self.loop_elapsed if self.loop_elapsed > 0 else 0.0

    def __str__(self) -> str:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(self.counts.items())) or "none"
        noun = "grid point" if self.total == 1 else "grid points"
        text = (f"{self.total} {noun}: {self.skipped} already stored, {self.computed}"
                f" stored now ({counts}) in {self.elapsed:.2f} s")
        if self.in_process:
            return text + " (computed in-process)"
        text += f"; master CPU {100 * self.master_cpu_share:.1f}% of a core"
        if self.writer_cpu and self.writer_wall > 0:  # over the span it was measured on
            text += f", its store writer {100 * self.writer_cpu / self.writer_wall:.1f}%"
        return text


class Master:
    """Schedules points costliest-first onto idle workers and stores each result.

    Parameters
    ----------
    store : where the results go (:class:`sweep.run.sink.ResultSink`: the open store
        written by this process, :class:`sweep.run.sink.InlineSink`, or by a writer
        process, :class:`sweep.run.store_process.StoreProcess`).
    transport : :class:`sweep.run.transport.InProcessTransport` or
        :class:`sweep.run.transport.MPITransport`.
    compute : the compute function spec (its kernels are warmed up before the run).
    """

    def __init__(self, store: ResultSink, transport: Transport,
                 compute: str = DEFAULT_COMPUTE, point_timeout: float = 0.0) -> None:
        self.store = store
        self.point_timeout = point_timeout
        self.transport = transport
        self.compute = compute
        self.outstanding = 0  # tasks handed out and not yet stored
        #: points in flight when an earlier run died: each is computed alone, so that a
        #: death while it runs is its attempt (``[run] max_attempts``)
        self.suspects: set[str] = set()
        self._queues: dict[int, collections.deque[tuple[Point, dict[str, Any]]]] = {}
        self.point_time = math.nan  # [s] moving average of a point's compute time
        #: [s] moving average of what a worker waits for at the store (its hand-out or its
        #: batch's commit: ``store.waits_for``)
        self.commit_time = math.nan
        self.at_workers = 0  # tasks sent whose results have not arrived
        #: results handed to the store and not yet reported stored, in order
        self._unstored: collections.deque[str] = collections.deque()

    @property
    def depth(self) -> int:
        """How many tasks each worker holds (1 until points and commits are timed)."""
        if not (self.point_time >= 0 and self.commit_time >= 0):
            return 1
        ratio = self.commit_time / (_COMMIT_SHARE * max(self.point_time, 1e-6))
        return max(1, min(_MAX_DEPTH, 1 + int(ratio)))

    def _task(self, point: Point, config: dict[str, Any]) -> Task:
        """The :class:`~sweep.protocol.Task` of ``point`` (``config``: its configuration
        as a dict, kept with the worker's queue)."""
        return Task(point.hash, config, float(self.point_timeout or 0.0))

    def record(self, point: Point, out: Outcome,
               config: dict[str, Any] | None = None) -> Record:
        """The :class:`sweep.store.record.Record` of a worker's outcome (or of
        :meth:`sweep.protocol.Outcome.known`) for ``point``."""
        return Record.from_outcome(point, out, config, self.store.provenance)

    def _timed(self, step: str, t0: float) -> None:
        """Average the time since ``t0`` (``time.perf_counter``) into
        :attr:`commit_time` if ``step`` ("handout", "commit") is what a worker waits for
        at the store."""
        if step == self.store.waits_for:
            self.commit_time = _average(self.commit_time, time.perf_counter() - t0)

    def run(self, todo: list[Point], progress: Progress, signals: StopSignals,
            summary: RunSummary) -> None:
        """Compute and store every point of ``todo`` (or stop on a signal).

        Results are stored by group commit: the first result that arrives, plus every
        result already waiting (at most :data:`_MAX_BATCH`, taken within
        :data:`_BATCH_WINDOW`), are staged and committed together; only then are they
        counted as stored and are their workers given new tasks.
        """
        suspects = sorted((p for p in todo if p.hash in self.suspects),
                          key=lambda p: (-p.cost, p.index), reverse=True)
        pending = sorted((p for p in todo if p.hash not in self.suspects),
                         key=lambda p: (-p.cost, p.index))
        pending.reverse()  # pop() from the end takes the costliest
        # per worker, its tasks in the order sent (MPI keeps the order of one sender)
        queues: dict[int, collections.deque[tuple[Point, dict[str, Any]]]] = {
            w: collections.deque() for w in self.transport.workers}
        self._queues = queues
        self.outstanding = self.at_workers = 0
        self._unstored.clear()
        stop_at = math.inf
        try:
            while pending or suspects or self.outstanding:
                if signals.requested and stop_at == math.inf:
                    stop_at = time.monotonic() + signals.grace
                    summary.interrupted = signals.requested
                    pending += suspects  # not started: counted as not started
                    suspects = []
                if not signals.requested and suspects and not self.outstanding:
                    point = suspects.pop()  # alone: nothing else is in flight
                    worker = self.transport.workers[0]
                    queues[worker].append((point, point.config.to_dict()))
                    self.store.handout([(point.hash, worker)], alone=True)
                    self.outstanding += 1
                    self.at_workers += 1
                    self.transport.send(worker, self._task(point, queues[worker][-1][1]))
                elif not signals.requested and not suspects:
                    depth = self.depth
                    sent: list[tuple[Point, dict[str, Any], int]] = []
                    for worker, queue in queues.items():
                        while len(queue) < depth and pending:
                            point = pending.pop()
                            sent.append((point, point.config.to_dict(), worker))
                            queue.append(sent[-1][:2])
                    # journaled before they go out: a point whose worker dies is counted
                    t0 = time.perf_counter()
                    self.store.handout([(p.hash, w) for p, _, w in sent])
                    if sent:
                        self._timed("handout", t0)
                    for point, config, worker in sent:
                        self.outstanding += 1
                        self.at_workers += 1
                        self.transport.send(worker, self._task(point, config))
                if not self.outstanding:
                    break
                if time.monotonic() > stop_at:
                    break
                wait = min(1.0, max(stop_at - time.monotonic(), 0.0))
                if not self.at_workers:  # only the store has them (a writer process)
                    self.outstanding -= self._count(self.store.wait(wait), progress, summary)
                    continue
                msg = self.transport.poll(wait)
                progress.tick()
                if msg is None:
                    self.outstanding -= self._count(self.store.take_stored(), progress,
                                                    summary)
                    continue
                batch = [msg]
                window_end = time.monotonic() + _BATCH_WINDOW
                while len(batch) < min(self.outstanding, _MAX_BATCH) and \
                        batch[-1][1] != Kind.ERROR and time.monotonic() < window_end:
                    more = self.transport.poll(0.0)
                    if more is None:
                        break
                    batch.append(more)
                self.outstanding -= self._store_batch(batch, queues, progress, summary)
        except GraceExpired as exc:  # Unanswered: the writer, killed as stuck after a stop
            summary.interrupted = summary.interrupted or (
                signals.requested if isinstance(exc, Unanswered) else "") or "signal"
        if self.outstanding:  # results at a writer process: wait for them
            self.outstanding -= self._count(self.store.sync(), progress, summary)
        if summary.interrupted:
            summary.abandoned = abandoned = self.outstanding
            raise Interrupted(
                f"campaign stopped by {summary.interrupted}: {summary.computed} points stored"
                f" in this run, {abandoned} running point(s) abandoned, {len(pending)} not"
                " started; the store is closed and consistent — the campaign is resumable:"
                " run the same command again")

    def release_abandoned(self) -> None:
        """Journal that the points still handed out were abandoned by a stop or an error
        of the master or its store (none of them killed its worker: no attempt is
        counted): those at the workers, and those whose results the store did not report
        stored."""
        hashes = [*self._unstored, *(p.hash for q in self._queues.values() for p, _ in q)]
        self.store.release(hashes)

    def _store_batch(self, batch: list[tuple[int, str, Any]],
                     queues: dict[int, collections.deque[tuple[Point, dict[str, Any]]]],
                     progress: Progress, summary: RunSummary) -> int:
        """Stage the results of ``batch``, commit them together, count them as stored.

        Returns the number of points now stored (those the store reports stored since
        the last call: with a writer process, not yet all of ``batch``). A worker's error
        message is raised (as :class:`WorkerError`) after the results before it are
        stored.
        """
        t0 = time.perf_counter()
        results = 0
        error: WorkerFailure | None = None
        wall = 0.0
        for worker, kind, payload in batch:
            if kind == Kind.ERROR:
                error = payload
                break
            point, config = queues[worker].popleft()
            self.at_workers -= 1
            if kind != Kind.RESULT or payload.hash != point.hash:
                raise WorkerError(f"worker rank {worker} returned {kind} of point"
                                  f" {str(getattr(payload, 'hash', ''))[:12]}, expected the"
                                  f" result of {point.hash[:12]} (protocol error)")
            self._unstored.append(point.hash)  # before: a submit may find the writer dead
            self.store.submit(point, payload, config)
            results += 1
            wall += float(payload.wall_time)
        # a worker's error: raised once the results before it are stored
        stored = self._count(self.store.settle(everything=error is not None), progress,
                             summary)
        if error is not None:
            raise WorkerError(f"worker rank {error.rank} on {error.host}:"
                              f" {error.message}\n{error.traceback}")
        if results:
            self.point_time = _average(self.point_time, wall / results)
            self._timed("commit", t0)
        return stored

    def _count(self, statuses: list[str], progress: Progress, summary: RunSummary) -> int:
        """Count stored points (their statuses, in the order their results were
        submitted) in the summary and the progress."""
        for status in statuses:
            if self._unstored:
                self._unstored.popleft()
            summary.computed += 1
            summary.counts[status] = summary.counts.get(status, 0) + 1
            progress.update(status)
        return len(statuses)


def _average(old: float, new: float, weight: float = 0.3) -> float:
    """Exponential moving average (``new`` alone when there is no ``old``)."""
    return new if math.isnan(old) else (1 - weight) * old + weight * new
