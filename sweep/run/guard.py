"""The guard of ``sweep run``: a parent process that knows whether the campaign ended.

A compute function can end the whole process with status 0 -- ``os._exit(0)``, a C
``exit(0)`` or a Fortran ``STOP`` in a model library -- and no handler of the process
itself can see it happen. A job script would take that status for success with most of
the grid missing. So the ``sweep run`` command forks before anything else: the child
runs the campaign as before and, when ``main`` returns, writes its exit status to a
pipe; the parent (the guard) only waits. A child that ends with status 0 without having
written it did not finish: the guard says so and exits with :data:`EXIT_INTERRUPTED`
(6: stopped, resumable). Any other status of the child is the guard's (a child killed
by signal N makes the guard end by the same signal).

The guard forwards SIGINT, SIGTERM, SIGUSR1 and SIGHUP to the child (a signal sent to
the process group reaches both: :class:`sweep.run.signals.StopSignals` counts a repeat
within :data:`sweep.run.signals.REPEAT_WINDOW` once). The child dies with its guard
(``PR_SET_PDEATHSIG``), so ``kill -9`` of the guard ends the campaign as before.
Under an MPI launcher every rank is guarded: a worker rank that ends with 0 in the
middle of a point makes its guard exit 6, and the launcher ends the job non-zero.

Set ``SWEEP_NO_GUARD=1`` to run without it (one process, as before).
"""
from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys

from sweep.errors import EXIT_INTERRUPTED

__all__ = ["guarded", "report_status", "unblock"]

_FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1, signal.SIGHUP)
_STATUS_FD: int | None = None  # the child's end of the pipe
_MASK: set[int] | None = None  # the child's signal mask before the fork


def _die_with_parent(parent: int) -> None:
    """Linux: this process gets SIGKILL when its parent dies."""
    with contextlib.suppress(Exception):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the guard died before prctl
        os._exit(EXIT_INTERRUPTED)


def report_status(status: int) -> None:
    """In the guarded child: tell the guard that ``main`` returned ``status``."""
    global _STATUS_FD
    if _STATUS_FD is None:
        return
    with contextlib.suppress(OSError):
        os.write(_STATUS_FD, bytes([status & 0xFF]))
        os.close(_STATUS_FD)
    _STATUS_FD = None


def unblock() -> None:
    """In the guarded child: deliver the stop signals again (blocked since the fork, so
    that one forwarded at once finds the command's handlers, not the default action)."""
    global _MASK
    if _MASK is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, _MASK)
        _MASK = None


def guarded() -> bool:
    """Fork the guard; returns True in the child (which goes on), never in the guard
    (which exits with the campaign's status). False when there is no guard (disabled,
    no ``fork``)."""
    global _STATUS_FD, _MASK
    if os.environ.get("SWEEP_NO_GUARD") or not hasattr(os, "fork"):
        return False
    r, w = os.pipe()
    parent = os.getpid()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _FORWARDED)  # until handlers exist
    try:
        pid = os.fork()
    except OSError:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
        os.close(r)
        os.close(w)
        return False
    if pid == 0:
        os.close(r)
        _STATUS_FD = w
        _MASK = old  # the stop signals stay blocked until the caller's handlers exist
        _die_with_parent(parent)
        return True
    os.close(w)
    sys.exit(_guard(pid, r, old))


def _guard(child: int, r: int, mask: set[int]) -> int:
    def forward(signum: int, frame: object) -> None:
        with contextlib.suppress(OSError):
            os.kill(child, signum)

    for sig in _FORWARDED:
        signal.signal(sig, forward)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    while True:
        try:
            _, status = os.waitpid(child, 0)
            break
        except ChildProcessError:  # pragma: no cover - reaped elsewhere
            status = 0
            break
        except InterruptedError:  # pragma: no cover - retried by Python already
            continue
    for sig in _FORWARDED:  # the child is gone: nothing may kill the exit now
        signal.signal(sig, signal.SIG_IGN)
    reported = b""
    with contextlib.suppress(OSError):
        # not blocking: a descendant the campaign forked may still hold the write end
        os.set_blocking(r, False)
        reported = os.read(r, 1)
    os.close(r)
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        if sig != signal.SIGKILL:  # SIGKILL has no handler to reset (EINVAL): it is default
            signal.signal(sig, signal.SIG_DFL)
        sys.stdout.flush()
        sys.stderr.flush()
        os.kill(os.getpid(), sig)
        return 128 + sig
    code = os.waitstatus_to_exitcode(status)
    if code == 0 and not reported:
        print(f"sweep: stopped: the campaign process (pid {child}) ended with exit"
              " status 0 before the campaign finished: something in it called exit"
              " (a compute function's os._exit(0), a model library's exit(0) or Fortran"
              " STOP?); what was stored is kept and the point it was computing counts as"
              " an attempt ([run] max_attempts) -- the campaign is resumable: run the"
              " same command again", file=sys.stderr, flush=True)
        return EXIT_INTERRUPTED
    return code
