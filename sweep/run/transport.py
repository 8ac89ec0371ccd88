"""How the master talks to its workers: the in-process and the MPI transport.

- :class:`InProcessTransport`: one worker, the master's own process (plain ``python``);
- :class:`MPITransport`: mpi4py, MPI-1 point-to-point only (``isend``/``Iprobe``/``recv``):
  rank 0 is the master and the only process that opens the store, ranks 1..N-1 run
  :func:`sweep.run.worker.worker_loop`; the messages are :mod:`sweep.protocol`'s.

Waiting is never a hot spin: :class:`Backoff` sleeps between probes, from
:data:`POLL_MIN` doubling up to :data:`POLL_MAX` (MPICH's blocking ``recv`` polls at
100% CPU; this costs about 1% of a core and adds a few milliseconds of latency).
"""
from __future__ import annotations

import collections
import math
import os
import sys
import time
from collections.abc import Callable
from typing import Any, Protocol

from sweep.errors import WorkerError
from sweep.protocol import TAG_RESULT, TAG_TASK, Kind, Task, WarmUp
from sweep.provenance import environment
from sweep.run.compute import DEFAULT_COMPUTE, compute_in_child, compute_point, resolve_compute
from sweep.run.warmup import warm_up

__all__ = ["Transport", "InProcessTransport", "MPITransport", "Backoff", "wait_message",
           "send_message", "POLL_MIN", "POLL_MAX"]

POLL_MIN, POLL_MAX = 0.0005, 0.005  # [s] backoff of the waiting loops
#: MPICH's Iprobe makes progress on one call and sees the message on the next, so each
#: wake-up probes a few times (measured: 1 probe per wake-up waits ~3 backoff periods).
_PROBES_PER_WAKE = 4


class Backoff:
    """Exponential backoff between probes: sleep ``low``, then twice as long each time up
    to ``high``; back to ``low`` once something arrived."""

    def __init__(self, low: float = POLL_MIN, high: float = POLL_MAX) -> None:
        self.low, self.high = low, high
        self.delay = low

    def wait(self, ready: Callable[[], bool], deadline: float = math.inf) -> bool:
        """Probe ``ready()`` until it holds (True; the delay starts again at ``low``) or
        ``deadline`` (``time.monotonic``) passes (False; the delay is kept)."""
        while not ready():
            if deadline != math.inf:
                now = time.monotonic()
                if now >= deadline:
                    return False
                time.sleep(min(self.delay, deadline - now))
            else:
                time.sleep(self.delay)
            self.delay = min(2 * self.delay, self.high)
        self.delay = self.low
        return True


def _probe(comm: Any, source: int, tag: int, status: Any = None) -> bool:
    return any(comm.Iprobe(source=source, tag=tag, status=status)
               for _ in range(_PROBES_PER_WAKE))


def wait_message(comm: Any, source: int, tag: int, status: Any = None) -> None:
    """Block until a message is available (:class:`Backoff` between probes)."""
    Backoff().wait(lambda: _probe(comm, source, tag, status))


def send_message(comm: Any, obj: Any, dest: int, tag: int) -> None:
    """Send ``obj`` and return once it is sent, sleeping (:class:`Backoff`) between tests:
    a result too large for MPI's eager protocol waits until the master receives it, and a
    blocking ``send`` would spin at 100 % of a core meanwhile (oversubscribed, on the
    master's)."""
    req = comm.isend(obj, dest=dest, tag=tag)
    Backoff().wait(req.Test)


class Transport(Protocol):
    """How the master talks to its workers."""

    workers: list[int]
    worker_env: dict[int, dict[str, Any]]

    def send(self, worker: int, task: Task) -> None: ...

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]: ...

    def poll(self, timeout: float) -> tuple[int, Kind, Any] | None: ...

    def shutdown(self) -> None: ...

    def abort(self, code: int) -> None: ...


class InProcessTransport:
    """The master's own process is the only worker: ``poll`` computes the task."""

    def __init__(self, compute: str = DEFAULT_COMPUTE) -> None:
        self.fn = resolve_compute(compute)
        self.compute = compute
        self.workers = [0]
        self.worker_env = {0: environment(with_git=False)}
        self._tasks: collections.deque[Task] = collections.deque()

    def send(self, worker: int, task: Task) -> None:
        self._tasks.append(task)

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]:
        """Compile the kernels of ``configs`` here (:mod:`sweep.run.warmup`)."""
        return warm_up(configs, self.compute)

    def poll(self, timeout: float) -> tuple[int, Kind, Any] | None:
        if not self._tasks:
            return None
        task = self._tasks.popleft()
        if task.timeout and hasattr(os, "fork"):  # a limit: in a child process
            return 0, Kind.RESULT, compute_in_child(task, self.fn, 0)
        return 0, Kind.RESULT, compute_point(task, self.fn, 0)

    def shutdown(self) -> None:
        self._tasks.clear()

    def abort(self, code: int) -> None:
        self._tasks.clear()


class MPITransport:
    """Rank 0's side of the MPI master/worker protocol (MPI-1 point-to-point)."""

    def __init__(self, comm: Any, compute: str = DEFAULT_COMPUTE) -> None:
        from mpi4py import MPI  # lazy: initialises MPI; in-process runs use none

        self.MPI = MPI
        self.comm = comm
        self.workers = list(range(1, comm.Get_size()))
        self.worker_env: dict[int, dict[str, Any]] = {}
        self.compute = compute
        self._status = MPI.Status()
        self._backoff = Backoff()
        #: the task sends not yet seen complete, in order (each holds its pickled task)
        self._sends: collections.deque[Any] = collections.deque()

    def start(self) -> None:
        """Collect every worker's hello (its environment, or its start-up failure)."""
        errors = []
        for _ in self.workers:
            wait_message(self.comm, self.MPI.ANY_SOURCE, TAG_RESULT, self._status)
            kind, payload = self.comm.recv(source=self._status.Get_source(), tag=TAG_RESULT)
            if kind == Kind.ERROR:
                errors.append(payload)
            else:
                self.worker_env[self._status.Get_source()] = payload
        if errors:
            e = errors[0]
            raise WorkerError(f"worker rank {e.rank} on {e.host} failed to start:"
                              f" {e.message}" + (f"\n{e.traceback}" if e.traceback else ""))

    def send(self, worker: int, task: Task) -> None:
        """Send ``task`` without waiting for its worker to take it (``isend``: a blocking
        send took 44 % of the master's time at 64 ranks, docs/cluster.md); MPI keeps the
        order of one sender's messages to one worker. The sends are tested later."""
        self._sends.append(self.comm.isend(task, dest=worker, tag=TAG_TASK))
        self._completed()

    def _completed(self) -> None:
        """Drop the sends that completed (oldest first: they complete about in order)."""
        while self._sends and self._sends[0].Test():
            self._sends.popleft()

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]:
        """Every worker compiles the kernels of ``configs`` (:mod:`sweep.run.warmup`); returns
        the longest time and the first problem reported."""
        if not configs:
            return 0.0, ""
        for w in self.workers:
            self.comm.send(WarmUp(tuple(configs)), dest=w, tag=TAG_TASK)
        longest, problem = 0.0, ""
        for _ in self.workers:
            wait_message(self.comm, self.MPI.ANY_SOURCE, TAG_RESULT, self._status)
            source = self._status.Get_source()
            kind, payload = self.comm.recv(source=source, tag=TAG_RESULT)
            if kind != Kind.WARM:  # pragma: no cover - a protocol error
                raise WorkerError(f"worker rank {source}: expected its warm-up reply, got"
                                  f" {kind!r}")
            longest = max(longest, payload[0])
            problem = problem or (f"rank {source}: {payload[1]}" if payload[1] else "")
        return longest, problem

    def poll(self, timeout: float) -> tuple[int, Kind, Any] | None:
        self._completed()
        if not self._backoff.wait(
                lambda: _probe(self.comm, self.MPI.ANY_SOURCE, TAG_RESULT, self._status),
                time.monotonic() + timeout):
            return None
        source = self._status.Get_source()
        kind, payload = self.comm.recv(source=source, tag=TAG_RESULT)
        return source, kind, payload

    def shutdown(self) -> None:
        for w in self.workers:
            self.comm.send(None, dest=w, tag=TAG_TASK)
        end = time.monotonic() + 10.0
        for req in self._sends:  # every worker took its tasks before its stop
            Backoff().wait(req.Test, end)
        self._sends.clear()

    def abort(self, code: int) -> None:
        sys.stdout.flush()
        sys.stderr.flush()
        # rank 0's message reaches the terminal through the launcher's forwarding, which
        # MPI_Abort tears down: give it a moment (seen: the message lost once under load)
        time.sleep(0.5)
        self.comm.Abort(code)
