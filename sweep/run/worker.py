"""The MPI worker loop: receive Tasks from the master, send back Outcomes, until told to stop.

A worker (ranks 1..N-1) first reports :attr:`~sweep.protocol.Kind.READY` with its
environment (or :attr:`~sweep.protocol.Kind.ERROR` if its compute function cannot be
imported), then answers each :class:`~sweep.protocol.Task` with a
:attr:`~sweep.protocol.Kind.RESULT` (:func:`sweep.run.compute.compute_point`, its outcome
:class:`~sweep.protocol.Packed`) and each
:class:`~sweep.protocol.WarmUp` with :attr:`~sweep.protocol.Kind.WARM`; ``None`` ends it.
"""
from __future__ import annotations

import contextlib
import signal
import traceback
from typing import Any

from sweep.errors import SweepError
from sweep.protocol import TAG_RESULT, TAG_TASK, Kind, Packed, WarmUp, WorkerFailure
from sweep.provenance import environment, host
from sweep.run.compute import DEFAULT_COMPUTE, compute_point, resolve_compute
from sweep.run.transport import send_message, wait_message
from sweep.run.warmup import warm_up
from sweep.system import STOP_SIGNALS

__all__ = ["worker_loop", "stop_workers"]


def worker_loop(comm: Any, compute: str = DEFAULT_COMPUTE) -> None:
    """Run on ranks 1..N-1: receive tasks from rank 0 until ``None``, send back results.

    Stop signals are ignored here: the master decides when to stop (grace period).
    """
    for sig in STOP_SIGNALS:
        with contextlib.suppress(ValueError, OSError):
            signal.signal(sig, signal.SIG_IGN)
    rank = comm.Get_rank()
    try:
        fn = resolve_compute(compute)
        env = environment(with_git=False, with_mpi=True)
    except Exception as exc:  # noqa: BLE001 - reported to the master, which stops
        plain = isinstance(exc, SweepError)  # its message says it all
        comm.send((Kind.ERROR, WorkerFailure(rank, host(), str(exc) if plain else f"{exc!r}",
                                             "" if plain else traceback.format_exc())),
                  dest=0, tag=TAG_RESULT)
        fn, env = None, {}
    else:
        comm.send((Kind.READY, env), dest=0, tag=TAG_RESULT)
    while True:
        wait_message(comm, 0, TAG_TASK)
        task = comm.recv(source=0, tag=TAG_TASK)
        if task is None:
            return
        if fn is None:
            continue
        if isinstance(task, WarmUp):  # before the campaign's clock starts (sweep.run.warmup)
            send_message(comm, (Kind.WARM, warm_up(list(task.configs), compute)), 0,
                         TAG_RESULT)
            continue
        send_message(comm, (Kind.RESULT, Packed.of(compute_point(task, fn, rank))), 0,
                     TAG_RESULT)


def stop_workers(comm: Any) -> None:
    """From rank 0 before any task (the campaign could not be read): every worker's
    :func:`worker_loop` ends (``None``), the job with rank 0's status."""
    for w in range(1, comm.Get_size()):
        with contextlib.suppress(Exception):
            comm.send(None, dest=w, tag=TAG_TASK)
