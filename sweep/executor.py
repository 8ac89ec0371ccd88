"""Run a campaign: a master that schedules and stores, workers that compute.

The master (:class:`Master`) is a small state machine over a pluggable transport:
keep every worker supplied with the costliest pending points, wait (blocking with
backoff, never a hot spin) for a result, take every other result already waiting, store
them all with one group commit (:meth:`sweep.store.Store.commit`: one journal fsync, one
HDF5 flush), count them as stored, repeat; ``None`` is the stop message. A worker holds
one task at a time while points are slow; when points take less than a few commits'
time it is given a short queue of tasks (up to :data:`_MAX_DEPTH`) so that it computes
while the master commits. Two transports share it:

- :class:`InProcessTransport`: one worker, the master's own process (plain ``python``);
- :class:`MPITransport`: mpi4py, MPI-1 point-to-point only (``send``/``Iprobe``/``recv``):
  rank 0 is the master and the only process that opens the store, ranks 1..N-1 run
  :func:`worker_loop`.

Points are computed by a pluggable function ``"module:function"`` taking a
:class:`floewave.ModelConfig` and returning a :class:`floewave.PointResult` (or a dict
like its ``to_dict()``); the default is ``floewave:run_point``. :func:`compute_point`
turns whatever happens into a record: ``invalid`` for
:class:`floewave.InvalidPointError`, ``failed`` for any other exception or NaN results
(the message carries rank, host and traceback), the model's own status otherwise.
"""
from __future__ import annotations

import collections
import contextlib
import importlib
import math
import os
import signal
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

import floewave
from floewave import ModelConfig

from .config import Campaign, Point
from .errors import ConfigError, Interrupted, LaunchError, SweepError, WorkerError
from .progress import Progress, log_line
from .provenance import environment, host
from .record import Record, known_outcome, plain, provenance_json
from .schema import PROFILE_VARS, REPLICA_VARS
from .store import Store, utc_now
from .warmup import warm_up, warm_up_configs

__all__ = ["run_campaign", "compute_point", "worker_loop", "Master", "InProcessTransport",
           "MPITransport", "RunSummary", "resolve_compute", "mpi_world", "check_launch",
           "DEFAULT_COMPUTE"]

DEFAULT_COMPUTE = "floewave:run_point"
MODEL_STATUSES = floewave.results.STATUSES
_TAG_TASK, _TAG_RESULT = 1, 2
#: Stored statuses that ``--retry-failed`` computes again.
_RETRIED = ("failed", "crashed", "timeout")
_POLL_MIN, _POLL_MAX = 0.0005, 0.005  # [s] backoff of the waiting loops
#: MPICH's Iprobe makes progress on one call and sees the message on the next, so each
#: wake-up probes a few times (measured: 1 probe per wake-up waits ~3 backoff periods).
_PROBES_PER_WAKE = 4
#: Group commit: at most this many results per commit, and at most this long [s] between
#: taking the first result of a batch and committing it.
_MAX_BATCH, _BATCH_WINDOW = 512, 0.2
#: Tasks queued per worker at most. The depth is 1 + commit time / (share x point time):
#: 1 for points much longer than a commit, more for quick points, so that commits cost
#: the workers at most about ``_COMMIT_SHARE`` of their time.
_MAX_DEPTH, _COMMIT_SHARE = 64, 0.1
#: Longest interval [s] given to ``setitimer`` (larger values overflow it).
_MAX_TIMER = 1e7


def _probe(comm: Any, source: int, tag: int, status: Any = None) -> bool:
    return any(comm.Iprobe(source=source, tag=tag, status=status)
               for _ in range(_PROBES_PER_WAKE))


class _GraceExpired(BaseException):
    """Raised in-process when the grace period after a stop signal runs out."""


class _PointTimeout(BaseException):
    """Raised in the computing thread when a point runs past its ``point_timeout``."""


#: The hard limit of a point stuck in native code: ``point_timeout`` plus this much
#: (at least ``_HARD_MIN`` s) later the process ends (``faulthandler``; exit 1 and a
#: traceback; under MPI the job ends with it) and the point counts as an attempt.
#: ``SWEEP_HARD_TIMEOUT_MIN`` (seconds) overrides the minimum margin (tests).
_HARD_FACTOR = 1.0
_HARD_MIN = float(os.environ.get("SWEEP_HARD_TIMEOUT_MIN", "30"))
_TIMEOUT_SIGNAL = signal.SIGUSR2


class _Deadline:
    """``point_timeout`` for the computation in the main thread.

    Soft: a timer thread sends SIGUSR2 to the main thread at the limit and its handler
    raises :class:`_PointTimeout` (between bytecodes: at once in Python code or a sleep,
    when a numba kernel call returns). Hard: ``faulthandler`` ends the process a margin
    later if the point is stuck in native code.
    """

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self._timer: Any = None
        self._old: Any = None

    def _raise(self, signum: int, frame: Any) -> None:
        raise _PointTimeout(f"ran longer than point_timeout = {self.seconds:g} s")

    def __enter__(self) -> _Deadline:
        import faulthandler
        import threading

        if threading.current_thread() is not threading.main_thread():
            return self
        self._old = signal.signal(_TIMEOUT_SIGNAL, self._raise)
        main = threading.main_thread().ident
        self._timer = threading.Timer(self.seconds, signal.pthread_kill,
                                      args=(main, _TIMEOUT_SIGNAL))
        self._timer.daemon = True
        self._timer.start()
        hard = self.seconds + max(_HARD_MIN, _HARD_FACTOR * self.seconds)
        faulthandler.dump_traceback_later(min(hard, _MAX_TIMER), exit=True)
        return self

    def __exit__(self, *exc: Any) -> None:
        import faulthandler

        if self._timer is None:
            return
        self._timer.cancel()
        faulthandler.cancel_dump_traceback_later()
        signal.signal(_TIMEOUT_SIGNAL, self._old)
        self._timer = None


# ---------------------------------------------------------------------- worker side
def resolve_compute(spec: str) -> Callable[[ModelConfig], Any]:
    """Import ``"module:function"``."""
    module, _, name = spec.partition(":")
    if not module or not name:
        raise ConfigError(f"--compute {spec!r}: expected 'module:function'")
    try:
        fn = importlib.import_module(module)
        for part in name.split("."):
            fn = getattr(fn, part)
    except Exception as exc:  # noqa: BLE001 - ImportError, AttributeError, its own errors
        raise ConfigError(f"--compute {spec!r}: cannot import it: {type(exc).__name__}:"
                          f" {exc}") from None
    if not callable(fn):
        raise ConfigError(f"--compute {spec!r} is not callable")
    return fn  # type: ignore[return-value]


def compute_point(task: dict[str, Any], fn: Callable[[ModelConfig], Any],
                  rank: int = 0) -> dict[str, Any]:
    """Compute one point and describe the outcome; never raises for a point's fault.

    Returns a dict with ``hash``, ``status``, ``message``, ``scalars``, ``profiles``,
    ``residual_history`` and the provenance fields ``host``, ``rank``, ``pid``,
    ``start_time``, ``end_time``, ``wall_time``.
    """
    start_wall, t0 = utc_now(), time.perf_counter()
    out: dict[str, Any] = {"hash": task["hash"], "status": "failed", "message": "",
                           "scalars": {}, "profiles": {}, "residual_history": np.zeros(0)}
    try:
        cfg = ModelConfig.from_dict(task["config"])
        cfg.check_physics()
        limit = float(task.get("timeout") or 0.0)
        if limit > 0:
            with _Deadline(limit):
                result = fn(cfg)
        else:
            result = fn(cfg)
        data = result.to_dict() if hasattr(result, "to_dict") else dict(result)
        profiles = {k: np.asarray(data[k], dtype=np.float64)
                    for k in (*PROFILE_VARS, *REPLICA_VARS) if k in data}
        out["profiles"] = profiles
        out["residual_history"] = np.asarray(data.get("residual_history", []),
                                             dtype=np.float64)
        out["scalars"] = {k: plain(v) for k, v in data.items()
                          if k not in profiles and k != "residual_history"
                          and np.ndim(v) == 0}
        status = str(data.get("status", ""))
        bad = [k for k in ("a", "x_mean") if k in profiles
               and not np.all(np.isfinite(profiles[k]))]
        if status not in MODEL_STATUSES:
            out["message"] = f"model returned unknown status {status!r}"
        elif "a" not in profiles:
            out["message"] = "model returned no amplitude profile 'a'"
        elif bad:
            out["message"] = "non-finite values (NaN/inf) in " + ", ".join(bad)
        else:
            out["status"] = status
    except floewave.InvalidPointError as exc:
        out["status"] = "invalid"
        out["message"] = f"{type(exc).__name__}: {exc}"
    except _GraceExpired:
        raise  # the in-process grace period ran out: the master stops
    except _PointTimeout as exc:
        out["status"] = "timeout"
        out["scalars"], out["profiles"] = {}, {}
        out["residual_history"] = np.zeros(0)
        out["message"] = f"{exc} (rank {rank}, host {host()}, pid {os.getpid()})"
    except BaseException as exc:  # noqa: BLE001 - a point's failure is data, not a crash
        # SystemExit and KeyboardInterrupt raised by a point are its failure too
        out["status"] = "failed"
        out["scalars"], out["profiles"] = {}, {}
        out["residual_history"] = np.zeros(0)
        out["message"] = (f"{type(exc).__name__}: {exc} (rank {rank}, host {host()},"
                          f" pid {os.getpid()})\n{traceback.format_exc()}")
    out.update(host=host(), rank=rank, pid=os.getpid(), start_time=start_wall,
               end_time=utc_now(), wall_time=time.perf_counter() - t0)
    return out


def _wait_message(comm: Any, source: int, tag: int, status: Any = None) -> None:
    """Block until a message is available, sleeping with exponential backoff.

    MPICH's blocking ``recv`` polls at 100% CPU; this costs about 1% of a core and adds
    a few milliseconds of latency.
    """
    delay = _POLL_MIN
    while not _probe(comm, source, tag, status):
        time.sleep(delay)
        delay = min(2 * delay, _POLL_MAX)


def worker_loop(comm: Any, compute: str = DEFAULT_COMPUTE) -> None:
    """Run on ranks 1..N-1: receive tasks from rank 0 until ``None``, send back results.

    Stop signals are ignored here: the master decides when to stop (grace period).
    """
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1):
        with contextlib.suppress(ValueError, OSError):
            signal.signal(sig, signal.SIG_IGN)
    rank = comm.Get_rank()
    try:
        fn = resolve_compute(compute)
        env = environment(with_git=False, with_mpi=True)
    except Exception as exc:  # noqa: BLE001 - reported to the master, which stops
        plain = isinstance(exc, SweepError)  # its message says it all
        comm.send(("error", {"rank": rank, "host": host(),
                             "message": str(exc) if plain else f"{exc!r}",
                             "traceback": "" if plain else traceback.format_exc()}),
                  dest=0, tag=_TAG_RESULT)
        fn, env = None, {}
    else:
        comm.send(("ready", env), dest=0, tag=_TAG_RESULT)
    while True:
        _wait_message(comm, 0, _TAG_TASK)
        task = comm.recv(source=0, tag=_TAG_TASK)
        if task is None:
            return
        if fn is None:
            continue
        if "warm_up" in task:  # before the campaign's clock starts (sweep.warmup)
            comm.send(("warm", warm_up(task["warm_up"], compute)), dest=0, tag=_TAG_RESULT)
            continue
        comm.send(("result", compute_point(task, fn, rank)), dest=0, tag=_TAG_RESULT)


# ---------------------------------------------------------------------- transports
class Transport(Protocol):
    """How the master talks to its workers."""

    workers: list[int]
    worker_env: dict[int, dict[str, Any]]

    def send(self, worker: int, task: dict[str, Any]) -> None: ...

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]: ...

    def poll(self, timeout: float) -> tuple[int, str, Any] | None: ...

    def shutdown(self) -> None: ...

    def abort(self, code: int) -> None: ...


class InProcessTransport:
    """The master's own process is the only worker: ``poll`` computes the task."""

    def __init__(self, compute: str = DEFAULT_COMPUTE) -> None:
        self.fn = resolve_compute(compute)
        self.compute = compute
        self.workers = [0]
        self.worker_env = {0: environment(with_git=False)}
        self._tasks: collections.deque[dict[str, Any]] = collections.deque()

    def send(self, worker: int, task: dict[str, Any]) -> None:
        self._tasks.append(task)

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]:
        """Compile the kernels of ``configs`` here (:mod:`sweep.warmup`)."""
        return warm_up(configs, self.compute)

    def poll(self, timeout: float) -> tuple[int, str, Any] | None:
        if not self._tasks:
            return None
        return 0, "result", compute_point(self._tasks.popleft(), self.fn, 0)

    def shutdown(self) -> None:
        self._tasks.clear()

    def abort(self, code: int) -> None:
        self._tasks.clear()


class MPITransport:
    """Rank 0's side of the MPI master/worker protocol (MPI-1 point-to-point)."""

    def __init__(self, comm: Any, compute: str = DEFAULT_COMPUTE) -> None:
        from mpi4py import MPI

        self.MPI = MPI
        self.comm = comm
        self.workers = list(range(1, comm.Get_size()))
        self.worker_env: dict[int, dict[str, Any]] = {}
        self.compute = compute
        self._status = MPI.Status()
        self._delay = _POLL_MIN

    def start(self) -> None:
        """Collect every worker's hello (its environment, or its start-up failure)."""
        errors = []
        for _ in self.workers:
            _wait_message(self.comm, self.MPI.ANY_SOURCE, _TAG_RESULT, self._status)
            kind, payload = self.comm.recv(source=self._status.Get_source(), tag=_TAG_RESULT)
            if kind == "error":
                errors.append(payload)
            else:
                self.worker_env[self._status.Get_source()] = payload
        if errors:
            e = errors[0]
            raise WorkerError(f"worker rank {e['rank']} on {e['host']} failed to start:"
                              f" {e['message']}" + (f"\n{e['traceback']}" if e["traceback"]
                                                    else ""))

    def send(self, worker: int, task: dict[str, Any]) -> None:
        self.comm.send(task, dest=worker, tag=_TAG_TASK)

    def warm_up(self, configs: list[dict[str, Any]]) -> tuple[float, str]:
        """Every worker compiles the kernels of ``configs`` (:mod:`sweep.warmup`); returns
        the longest time and the first problem reported."""
        if not configs:
            return 0.0, ""
        for w in self.workers:
            self.comm.send({"warm_up": configs}, dest=w, tag=_TAG_TASK)
        longest, problem = 0.0, ""
        for _ in self.workers:
            _wait_message(self.comm, self.MPI.ANY_SOURCE, _TAG_RESULT, self._status)
            source = self._status.Get_source()
            kind, payload = self.comm.recv(source=source, tag=_TAG_RESULT)
            if kind != "warm":  # pragma: no cover - a protocol error
                raise WorkerError(f"worker rank {source}: expected its warm-up reply, got"
                                  f" {kind!r}")
            longest = max(longest, payload[0])
            problem = problem or (f"rank {source}: {payload[1]}" if payload[1] else "")
        return longest, problem

    def poll(self, timeout: float) -> tuple[int, str, Any] | None:
        deadline = time.monotonic() + timeout
        while not _probe(self.comm, self.MPI.ANY_SOURCE, _TAG_RESULT, self._status):
            now = time.monotonic()
            if now >= deadline:
                return None
            time.sleep(min(self._delay, deadline - now))
            self._delay = min(2 * self._delay, _POLL_MAX)
        self._delay = _POLL_MIN
        source = self._status.Get_source()
        kind, payload = self.comm.recv(source=source, tag=_TAG_RESULT)
        return source, kind, payload

    def shutdown(self) -> None:
        for w in self.workers:
            self.comm.send(None, dest=w, tag=_TAG_TASK)

    def abort(self, code: int) -> None:
        sys.stdout.flush()
        sys.stderr.flush()
        self.comm.Abort(code)


# ---------------------------------------------------------------------- master
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
    #: [s] compiling or loading the kernels before the first point (:mod:`sweep.warmup`)
    warm_up: float = 0.0

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
        return text + f"; master CPU {100 * self.master_cpu_share:.1f}% of a core"


class _StopSignals:
    """SIGINT/SIGTERM/SIGUSR1 set ``requested``; in-process, the grace timer raises."""

    def __init__(self, grace: float, in_process: bool) -> None:
        self.requested = ""
        self.grace = grace
        self.in_process = in_process
        self.active = True
        self._old: dict[int, Any] = {}

    def __enter__(self) -> _StopSignals:
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1):
            with contextlib.suppress(ValueError):  # not the main thread
                self._old[sig] = signal.signal(sig, self._handle)
        if self.in_process:
            with contextlib.suppress(ValueError):
                self._old[signal.SIGALRM] = signal.signal(signal.SIGALRM, self._expire)
        return self

    def quiet(self) -> None:
        """From now on only record signals (no grace timer, nothing raised)."""
        self.active = False
        if self.in_process:
            with contextlib.suppress(ValueError):
                signal.setitimer(signal.ITIMER_REAL, 0)

    def _handle(self, signum: int, frame: Any) -> None:
        name = signal.Signals(signum).name
        if not self.active:
            self.requested = self.requested or name
            return
        if self.requested and self.in_process:
            raise _GraceExpired(name)
        if not self.requested:
            print(f"[sweep] {name} received: no new points are handed out; waiting up to"
                  f" {self.grace:g} s for running ones", file=sys.stderr, flush=True)
        self.requested = self.requested or name
        if self.in_process:
            signal.setitimer(signal.ITIMER_REAL, min(max(self.grace, 1e-3), _MAX_TIMER))

    def _expire(self, signum: int, frame: Any) -> None:
        if self.active:
            raise _GraceExpired("grace period")

    def __exit__(self, *exc: Any) -> None:
        if self.in_process:
            with contextlib.suppress(ValueError):
                signal.setitimer(signal.ITIMER_REAL, 0)
        for sig, old in self._old.items():
            with contextlib.suppress(ValueError, TypeError):
                signal.signal(sig, old)


class Master:
    """Schedules points costliest-first onto idle workers and stores each result.

    Parameters
    ----------
    store : the open :class:`sweep.store.Store` (this process is its only writer).
    transport : :class:`InProcessTransport` or :class:`MPITransport`.
    compute : the compute function spec sent with every task.
    """

    def __init__(self, store: Store, transport: Transport, compute: str = DEFAULT_COMPUTE,
                 git: dict[str, Any] | None = None, point_timeout: float = 0.0) -> None:
        self.store = store
        self.point_timeout = point_timeout
        self.transport = transport
        self.compute = compute
        self.git = git or {}
        self._provenance: dict[tuple[int, str], str] = {}
        self.outstanding = 0  # tasks handed out and not yet stored
        #: points in flight when an earlier run died: each is computed alone, so that a
        #: death while it runs is its attempt (``[run] max_attempts``)
        self.suspects: set[str] = set()
        self._queues: dict[int, collections.deque[tuple[Point, dict[str, Any]]]] = {}
        self.point_time = math.nan  # [s] moving average of a point's compute time
        self.commit_time = math.nan  # [s] moving average of a batch's store time

    @property
    def depth(self) -> int:
        """How many tasks each worker holds (1 until points and commits are timed)."""
        if not (self.point_time >= 0 and self.commit_time >= 0):
            return 1
        ratio = self.commit_time / (_COMMIT_SHARE * max(self.point_time, 1e-6))
        return max(1, min(_MAX_DEPTH, 1 + int(ratio)))

    def record(self, point: Point, out: dict[str, Any],
               config: dict[str, Any] | None = None) -> Record:
        """The :class:`sweep.record.Record` of a worker's outcome (or of
        :func:`sweep.record.known_outcome`) for ``point``."""
        return Record.from_outcome(point, out, config, self._provenance_of)

    def _provenance_of(self, rank: int, kernel_mode: str) -> str:
        """The ``provenance`` column of a point computed by ``rank`` in ``kernel_mode``
        (the same for all its points: built once)."""
        key = (rank, kernel_mode)
        prov = self._provenance.get(key)
        if prov is None:
            prov = self._provenance[key] = provenance_json(
                self.transport.worker_env.get(rank, {}), self.git, kernel_mode)
        return prov

    def run(self, todo: list[Point], progress: Progress, signals: _StopSignals,
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
        self.outstanding = 0
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
                    self.transport.send(worker, {"hash": point.hash, "compute": self.compute,
                                                 "config": queues[worker][-1][1],
                                                 "timeout": self.point_timeout})
                elif not signals.requested and not suspects:
                    depth = self.depth
                    sent: list[tuple[Point, dict[str, Any], int]] = []
                    for worker, queue in queues.items():
                        while len(queue) < depth and pending:
                            point = pending.pop()
                            sent.append((point, point.config.to_dict(), worker))
                            queue.append(sent[-1][:2])
                    # journaled before they go out: a point whose worker dies is counted
                    self.store.handout([(p.hash, w) for p, _, w in sent])
                    for point, config, worker in sent:
                        self.outstanding += 1
                        self.transport.send(worker, {"hash": point.hash,
                                                     "compute": self.compute,
                                                     "config": config,
                                                     "timeout": self.point_timeout})
                if not self.outstanding:
                    break
                if time.monotonic() > stop_at:
                    break
                msg = self.transport.poll(min(1.0, max(stop_at - time.monotonic(), 0.0)))
                progress.tick()
                if msg is None:
                    continue
                batch = [msg]
                window_end = time.monotonic() + _BATCH_WINDOW
                while len(batch) < min(self.outstanding, _MAX_BATCH) and \
                        batch[-1][1] != "error" and time.monotonic() < window_end:
                    more = self.transport.poll(0.0)
                    if more is None:
                        break
                    batch.append(more)
                self.outstanding -= self._store_batch(batch, queues, progress, summary)
        except _GraceExpired:
            summary.interrupted = summary.interrupted or "signal"
        if summary.interrupted:
            summary.abandoned = abandoned = self.outstanding
            raise Interrupted(
                f"campaign stopped by {summary.interrupted}: {summary.computed} points stored"
                f" in this run, {abandoned} running point(s) abandoned, {len(pending)} not"
                " started; the store is closed and consistent — the campaign is resumable:"
                " run the same command again")

    def release_abandoned(self) -> None:
        """Journal that the points still handed out were abandoned by a stop (they did
        not kill their worker: no attempt is counted)."""
        hashes = [p.hash for q in self._queues.values() for p, _ in q]
        self.store.release(hashes)

    def _store_batch(self, batch: list[tuple[int, str, Any]],
                     queues: dict[int, collections.deque[tuple[Point, dict[str, Any]]]],
                     progress: Progress, summary: RunSummary) -> int:
        """Stage the results of ``batch``, commit them together, count them as stored.

        Returns the number of results taken. A worker's error message is raised (as
        :class:`WorkerError`) after the results before it are committed.
        """
        t0 = time.perf_counter()
        statuses: list[str] = []
        error: dict[str, Any] | None = None
        wall = 0.0
        for worker, kind, payload in batch:
            if kind == "error":
                error = payload
                break
            point, config = queues[worker].popleft()
            if payload.get("hash", point.hash) != point.hash:
                raise WorkerError(f"worker rank {worker} returned point"
                                  f" {str(payload.get('hash'))[:12]}, expected"
                                  f" {point.hash[:12]} (protocol error)")
            rec = self.record(point, payload, config)
            self.store.add(rec)
            statuses.append(rec.status)
            wall += float(payload.get("wall_time", 0.0))
        self.store.commit()  # now they are stored: count them
        for status in statuses:
            summary.computed += 1
            summary.counts[status] = summary.counts.get(status, 0) + 1
            progress.update(status)
        if error is not None:
            raise WorkerError(f"worker rank {error['rank']} on {error['host']}:"
                              f" {error['message']}\n{error['traceback']}")
        if statuses:
            self.point_time = _average(self.point_time, wall / len(statuses))
            self.commit_time = _average(self.commit_time, time.perf_counter() - t0)
        return len(statuses)


def _average(old: float, new: float, weight: float = 0.3) -> float:
    """Exponential moving average (``new`` alone when there is no ``old``)."""
    return new if math.isnan(old) else (1 - weight) * old + weight * new


# ---------------------------------------------------------------------- entry points
from .cli import _LAUNCHER_VARS  # noqa: E402 - one list (the CLI checks it early)


def mpi_world() -> Any:
    """``MPI.COMM_WORLD`` when started by an MPI launcher (mpiexec/srun), else ``None``.

    Without a launcher mpi4py is not even imported, so plain ``python`` runs work on
    machines without MPI.
    """
    if not any(v in os.environ for v in _LAUNCHER_VARS):
        return None
    try:
        from mpi4py import MPI
    except ImportError as exc:
        raise LaunchError(f"started by an MPI launcher but mpi4py cannot be imported: {exc};"
                          " pip install 'floewave[mpi]'") from None
    return MPI.COMM_WORLD


def check_launch(size: int, environ: dict[str, str] | None = None) -> None:
    """Refuse an MPI size that differs from ``SLURM_NTASKS`` (the N-singletons launch)."""
    env = os.environ if environ is None else environ
    ntasks = env.get("SLURM_NTASKS")
    if ntasks and ntasks.isdigit() and int(ntasks) != size:
        raise LaunchError(
            f"MPI size is {size} but SLURM_NTASKS={ntasks}: the ranks did not join one MPI"
            " job (N singletons: mpi4py built against another MPI than the launcher's, or"
            " 'sweep run' started without srun/mpiexec); fix the launch, or pass"
            " --ignore-slurm-ntasks if this is intended")


def run_campaign(campaign: Campaign, store_path: str, *, compute: str = DEFAULT_COMPUTE,
                 retry_failed: bool = False, extend: bool = False, comm: Any = None,
                 progress_bar: bool | None = None, command: str = "",
                 point_timeout: float | None = None) -> RunSummary | None:
    """Run (or resume) ``campaign`` into the store at ``store_path``.

    With ``comm`` (an MPI communicator of size > 1) rank 0 is the master and the other
    ranks are workers (they return ``None``); otherwise the campaign runs in-process.
    ``point_timeout`` [s] overrides ``[run] point_timeout`` (0: none).
    The workers' start-up is checked before the store is touched; stop signals are
    caught from before the store is opened (a stop during the open or its rebuild is
    honoured right after it: :class:`Interrupted`).

    Raises
    ------
    ConfigError, StoreError, WorkerError, Interrupted
        See :mod:`sweep.errors`. On an MPI run any failure of the master ends the job:
        idle workers are told to stop, busy ones are aborted with the job.
    """
    if comm is not None and comm.Get_size() > 1 and comm.Get_rank() != 0:
        worker_loop(comm, compute)
        return None
    mpi = comm is not None and comm.Get_size() > 1
    t0 = time.monotonic()
    transport: Any = None
    master: Master | None = None
    try:
        if mpi:
            transport = MPITransport(comm, compute)
            transport.start()  # every worker's hello (or its failure) before the store
        else:
            transport = InProcessTransport(compute)
        info = environment(with_mpi=comm is not None)
        info.update(mpi_size=comm.Get_size() if comm is not None else 1, command=command,
                    compute=compute)
        summary = RunSummary(total=campaign.size, in_process=not mpi)
        with _StopSignals(campaign.run.grace_period, in_process=not mpi) as signals:
            store = Store(store_path, campaign, extend=extend, run_info=info)
            outcome = "complete"
            try:
                if signals.requested:
                    signals.quiet()
                    raise Interrupted(f"campaign stopped by {signals.requested} while the"
                                      " store was being opened; nothing was lost — the"
                                      " campaign is resumable: run the same command again")
                git = {"git_commit": info["git_commit"], "git_dirty": info["git_dirty"],
                       "sweep_version": info["sweep_version"]}
                limit = campaign.run.point_timeout if point_timeout is None else point_timeout
                master = Master(store, transport, compute, git, limit)
                _run_points(campaign, store, master, signals, summary, retry_failed,
                            progress_bar)
                summary.elapsed = time.monotonic() - t0
            except Interrupted:
                outcome = "interrupted (resumable)"
                raise
            except BaseException as exc:
                outcome = f"error: {type(exc).__name__}: {exc}"
                raise
            finally:
                signals.quiet()
                if master is not None:  # in flight at a stop or an error: no attempt
                    with contextlib.suppress(Exception):
                        master.release_abandoned()
                store.close(outcome)
    except BaseException as exc:
        if mpi and transport is not None:
            busy = master is not None and master.outstanding > 0
            if not busy:
                with contextlib.suppress(Exception):
                    transport.shutdown()
            else:
                print(f"[sweep] {exc}" if isinstance(exc, SweepError) else
                      f"[sweep] error: {type(exc).__name__}: {exc}", file=sys.stderr,
                      flush=True)
                print("[sweep] store closed; aborting the MPI job (workers still busy)",
                      file=sys.stderr, flush=True)
                transport.abort(getattr(exc, "exit_status", 1))
        raise
    if mpi:
        transport.shutdown()
    return summary


def _warm_up(master: Master, todo: list[Point], signals: _StopSignals,
             summary: RunSummary) -> None:
    """Compile the kernels on every worker before the progress clock starts, and say how
    long it took on a line of its own (:mod:`sweep.warmup`)."""
    configs = warm_up_configs(todo, master.compute)
    if not configs:
        return
    try:
        seconds, problem = master.transport.warm_up(configs)
    except _GraceExpired:
        signals.requested = signals.requested or "signal"
        return  # the master loop stops at once (resumable)
    summary.warm_up = seconds
    n = len(master.transport.workers)
    note = f"; warm-up problem (the points will report theirs): {problem}" if problem else ""
    log_line(f"kernels ready in {seconds:.1f} s on {n} worker{'s' if n != 1 else ''}"
             f" ({len(configs)} kernel variant{'s' if len(configs) != 1 else ''}: compiled,"
             f" or loaded from the numba cache){note}")


def _run_points(campaign: Campaign, store: Store, master: Master, signals: _StopSignals,
                summary: RunSummary, retry_failed: bool, progress_bar: bool | None) -> None:
    """The campaign loop of :func:`run_campaign` (the store is open)."""
    todo = []
    for p in campaign.points():
        if p.hash in store and not (retry_failed and
                                    store.status_of(p.hash) in _RETRIED):
            summary.skipped += 1
            continue
        todo.append(p)
    _warm_up(master, todo, signals, summary)
    progress = Progress(len(todo), interval=campaign.run.progress_interval,
                        bar=progress_bar, skipped=summary.skipped)
    try:
        # known outcomes first: impossible points (no worker needed) and points that
        # killed their worker max_attempts times
        limit = campaign.run.max_attempts
        known = []
        for p in todo:
            if p.invalid:
                known.append((p, "invalid", p.invalid))
                continue
            tries = [t for t in store.handouts(p.hash) if t[2]]
            if limit and len(tries) >= limit and not retry_failed:
                where = ", ".join(sorted({f"rank {w}" for _, w, _ in tries}))
                known.append((p, "crashed", f"the job died {len(tries)} times while this"
                              f" point was the only one being computed ({where}); not tried"
                              f" again ([run] max_attempts = {limit}); --retry-failed tries"
                              " it again"))
            elif store.handouts(p.hash):
                master.suspects.add(p.hash)
        for p, status, message in known:
            store.add(master.record(p, known_outcome(p.hash, status, message)))
        store.commit()  # one group commit for all of them
        for _, status, _ in known:
            summary.computed += 1
            summary.counts[status] = summary.counts.get(status, 0) + 1
            progress.update(status)
        done = {p.hash for p, _, _ in known}
        loop0, cpu0 = time.monotonic(), time.process_time()
        try:
            master.run([p for p in todo if p.hash not in done], progress, signals, summary)
        finally:
            summary.loop_elapsed = time.monotonic() - loop0
            summary.master_cpu = time.process_time() - cpu0
    finally:
        progress.close()
