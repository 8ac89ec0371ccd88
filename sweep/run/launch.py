"""Run a campaign: :func:`run_campaign` opens the store, prefills the points whose
outcome is known without a worker, runs the master over a transport, and decides what an
error ends (under MPI: the whole job while workers are busy).

The parts: :mod:`sweep.run.compute` (compute one point), :mod:`sweep.run.worker` (the MPI
worker loop), :mod:`sweep.run.transport` (in-process and MPI), :mod:`sweep.run.master`
(scheduling and group commits), :mod:`sweep.run.signals` (stop signals and the grace
period), :mod:`sweep.run.mpi` (the launch checks), :mod:`sweep.protocol` (the messages).
"""
from __future__ import annotations

import contextlib
import sys
import time
from typing import Any

from sweep.config import Campaign, Point
from sweep.errors import Interrupted, SweepError
from sweep.protocol import Outcome
from sweep.provenance import environment
from sweep.run.compute import DEFAULT_COMPUTE
from sweep.run.master import Master, RunSummary
from sweep.run.progress import Progress, log_line
from sweep.run.signals import GraceExpired, StopSignals, Unanswered
from sweep.run.sink import InlineSink, ResultSink
from sweep.run.store_process import StoreProcess
from sweep.run.transport import InProcessTransport, MPITransport, Transport
from sweep.run.warmup import warm_up_configs
from sweep.run.worker import worker_loop
from sweep.store.store import Store

__all__ = ["run_campaign"]

#: Stored statuses that ``--retry-failed`` computes again.
_RETRIED = ("failed", "crashed", "timeout")

def run_campaign(campaign: Campaign, store_path: str, *, compute: str = DEFAULT_COMPUTE,
                 retry_failed: bool = False, extend: bool = False, comm: Any = None,
                 progress_bar: bool | None = None, command: str = "",
                 point_timeout: float | None = None,
                 verify: bool = False) -> RunSummary | None:
    """Run (or resume) ``campaign`` into the store at ``store_path``.

    With ``comm`` (an MPI communicator of size > 1) rank 0 is the master and the other
    ranks are workers (they return ``None``); otherwise the campaign runs in-process.
    ``point_timeout`` [s] overrides ``[run] point_timeout`` (0: none); ``verify``:
    compare the store with its journal on opening (:class:`sweep.store.store.Store`).
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
        transport = _open_transport(comm, compute, mpi)
        info = environment(with_mpi=comm is not None)
        info.update(mpi_size=comm.Get_size() if comm is not None else 1, command=command,
                    compute=compute)
        if campaign.shard_of is not None:      # what `sweep status` counts a shard against
            info.update(shard="{}/{}".format(*campaign.shard_of), shard_points=campaign.size)
        summary = RunSummary(total=campaign.size, in_process=not mpi)
        with StopSignals(campaign.run.grace_period, in_process=not mpi) as signals:
            git = {"git_commit": info["git_commit"], "git_dirty": info["git_dirty"],
                   "sweep_version": info["sweep_version"]}
            try:
                store = _open_sink(store_path, campaign,
                                   campaign.run.writer if mpi else "inline", extend=extend,
                                   run_info=info, verify=verify,
                                   worker_env=transport.worker_env, git=git, stop=signals)
            except Unanswered:  # the writer, stuck while opening, was killed (said so)
                raise Interrupted(f"campaign stopped by {signals.requested} while the store"
                                  " was being opened; nothing was lost — the campaign is"
                                  " resumable: run the same command again") from None
            outcome = "complete"
            try:
                if signals.requested:
                    signals.quiet()
                    raise Interrupted(f"campaign stopped by {signals.requested} while the"
                                      " store was being opened; nothing was lost — the"
                                      " campaign is resumable: run the same command again")
                limit = campaign.run.point_timeout if point_timeout is None else point_timeout
                master = Master(store, transport, compute, limit)
                _run_points(campaign, store, master, signals, summary, retry_failed,
                            progress_bar)
                summary.elapsed = time.monotonic() - t0
            except Interrupted:
                outcome = "interrupted (resumable)"
                raise
            except Unanswered:  # the writer, stuck after a stop, was killed (said so)
                outcome = "interrupted (resumable)"
                raise Interrupted(f"campaign stopped by {signals.requested}: the store's"
                                  " writer did not answer; the campaign is resumable: run"
                                  " the same command again") from None
            except BaseException as exc:
                outcome = f"error: {type(exc).__name__}: {exc}"
                raise
            finally:
                signals.quiet()
                if master is not None:  # in flight at a stop or an error: no attempt
                    with contextlib.suppress(Exception):
                        master.release_abandoned()
                store.close(outcome)
                # the writer's CPU once its store was open (opening it, which expands
                # the grid, is start-up, as for an inline master); else its whole life's
                summary.writer_cpu, summary.writer_wall = store.store_cpu, store.store_wall
    except BaseException as exc:
        if mpi and transport is not None:
            _end_mpi_job(exc, transport, master)
        raise
    if mpi:
        transport.shutdown()
    return summary


def _open_sink(store_path: str, campaign: Campaign, writer: str, *, extend: bool,
               run_info: dict[str, Any], verify: bool,
               worker_env: dict[int, dict[str, Any]], git: dict[str, Any],
               stop: StopSignals | None = None) -> ResultSink:
    """The open store as the master's :class:`sweep.run.sink.ResultSink`: written by a
    writer process (``writer`` "process": the master only schedules) or by the master
    itself ("inline")."""
    if writer == "process":
        return StoreProcess(store_path, campaign, extend=extend, run_info=run_info,
                            verify=verify, worker_env=worker_env, git=git, opener=Store,
                            stop=stop)
    return InlineSink(Store(store_path, campaign, extend=extend, run_info=run_info,
                            verify=verify), worker_env, git)


def _open_transport(comm: Any, compute: str, mpi: bool) -> Transport:
    """The MPI transport once every worker said hello (or its start-up failure is
    raised: before the store is touched), or the in-process one."""
    if not mpi:
        return InProcessTransport(compute)
    transport = MPITransport(comm, compute)
    transport.start()
    return transport


def _end_mpi_job(exc: BaseException, transport: Transport, master: Master | None) -> None:
    """The MPI policy when the master fails (the store is closed): idle workers are told
    to stop; busy ones cannot be, so the job is aborted (status of ``exc``)."""
    busy = master is not None and master.outstanding > 0
    if not busy:
        with contextlib.suppress(Exception):
            transport.shutdown()
        return
    print(f"[sweep] {exc}" if isinstance(exc, SweepError) else
          f"[sweep] error: {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
    print("[sweep] store closed; aborting the MPI job (workers still busy)",
          file=sys.stderr, flush=True)
    transport.abort(getattr(exc, "exit_status", 1))


def _warm_up(master: Master, todo: list[Point], signals: StopSignals,
             summary: RunSummary) -> None:
    """Compile the kernels on every worker before the progress clock starts, and say how
    long it took on a line of its own (:mod:`sweep.run.warmup`)."""
    configs = warm_up_configs(todo, master.compute)
    if not configs:
        return
    try:
        seconds, problem = master.transport.warm_up(configs)
    except GraceExpired:
        signals.requested = signals.requested or "signal"
        return  # the master loop stops at once (resumable)
    summary.warm_up = seconds
    n = len(master.transport.workers)
    note = f"; warm-up problem (the points will report theirs): {problem}" if problem else ""
    log_line(f"kernels ready in {seconds:.1f} s on {n} worker{'s' if n != 1 else ''}"
             f" ({len(configs)} kernel variant{'s' if len(configs) != 1 else ''}: compiled,"
             f" or loaded from the numba cache){note}")


def _run_points(campaign: Campaign, store: ResultSink, master: Master,
                signals: StopSignals, summary: RunSummary, retry_failed: bool,
                progress_bar: bool | None) -> None:
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
        known = _known_outcomes(todo, store, master, campaign.run.max_attempts,
                                retry_failed)
        for p, status, message in known:
            store.add(master.record(p, Outcome.known(p.hash, status, message)))
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


def _known_outcomes(todo: list[Point], store: ResultSink, master: Master,
                    limit: int, retry_failed: bool) -> list[tuple[Point, str, str]]:
    """The points whose outcome is known without a worker, as ``(point, status,
    message)``: impossible points (``invalid``) and points that killed their worker
    ``limit`` (``[run] max_attempts``) times (``crashed``). Points in flight when an
    earlier run died become the master's suspects (each computed alone:
    :func:`sweep.store.attempts.running`)."""
    known = []
    suspects = store.suspects()
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
        elif p.hash in suspects:
            master.suspects.add(p.hash)
    return known
