"""Computing one point, whatever happens, into an Outcome: run, timed out, failed or crashed.

Points are computed by a pluggable function ``"module:function"`` (:func:`resolve_compute`)
taking a :class:`floewave.ModelConfig` and returning a :class:`floewave.PointResult` (or a
dict like its ``to_dict()``); the default is ``floewave:run_point``. :func:`compute_point`
turns whatever happens into an outcome: ``invalid`` for
:class:`floewave.InvalidPointError`, ``failed`` for any other exception or NaN results
(the message carries rank, host and traceback), ``timeout`` past ``point_timeout``, the
model's own status otherwise: a :class:`sweep.protocol.Outcome`, which the master makes a
:class:`sweep.store.record.Record`.
"""
from __future__ import annotations

import contextlib
import ctypes
import faulthandler
import importlib
import os
import pickle
import select
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from typing import Any

import numpy as np

import floewave
from floewave import ModelConfig
from sweep.errors import ConfigError, SweepError
from sweep.protocol import Outcome, Task, plain
from sweep.provenance import host
from sweep.run.signals import GraceExpired
from sweep.store.schema import PROFILE_VARS, REPLICA_VARS
from sweep.system import STOP_SIGNALS, utc_now

__all__ = ["DEFAULT_COMPUTE", "MODEL_STATUSES", "PointTimeout", "resolve_compute",
           "compute_point", "compute_in_child"]

DEFAULT_COMPUTE = "floewave:run_point"
MODEL_STATUSES = floewave.results.STATUSES
#: Longest interval [s] given to ``faulthandler`` (larger values overflow it).
_MAX_TIMER = 1e7


class PointTimeout(BaseException):
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
    raises :class:`PointTimeout` (between bytecodes: at once in Python code or a sleep,
    when a numba kernel call returns). Hard: ``faulthandler`` ends the process a margin
    later if the point is stuck in native code.
    """

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self._timer: Any = None
        self._old: Any = None

    def _raise(self, signum: int, frame: Any) -> None:
        raise PointTimeout(f"ran longer than point_timeout = {self.seconds:g} s")

    def __enter__(self) -> _Deadline:
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
        if self._timer is None:
            return
        self._timer.cancel()
        faulthandler.cancel_dump_traceback_later()
        signal.signal(_TIMEOUT_SIGNAL, self._old)
        self._timer = None


def resolve_compute(spec: str) -> Callable[[ModelConfig], Any]:
    """Import ``"module:function"``."""
    module, _, name = spec.partition(":")
    if not module or not name:
        raise ConfigError(f"--compute {spec!r}: expected 'module:function'")
    try:
        fn = importlib.import_module(module)
        for part in name.split("."):
            fn = getattr(fn, part)
    except SweepError:  # a stop signal during the import (Interrupted) is not bad input
        raise
    except Exception as exc:  # noqa: BLE001 - ImportError, AttributeError, its own errors
        raise ConfigError(f"--compute {spec!r}: cannot import it: {type(exc).__name__}:"
                          f" {exc}") from None
    if not callable(fn):
        raise ConfigError(f"--compute {spec!r} is not callable")
    return fn  # type: ignore[return-value]


def compute_point(task: Task, fn: Callable[[ModelConfig], Any], rank: int = 0) -> Outcome:
    """Compute one point and describe the :class:`~sweep.protocol.Outcome`; never raises
    for a point's fault."""
    start_wall, t0 = utc_now(), time.perf_counter()
    out: dict[str, Any] = {"status": "failed", "message": "", "scalars": {},
                           "profiles": {}, "residual_history": np.zeros(0)}
    try:
        # not checked again here: the master checked every point's physics when it
        # expanded the grid (sweep.config), and impossible points never reach a worker
        cfg = ModelConfig.from_dict(task.config)
        limit = float(task.timeout or 0.0)
        if limit > 0:
            with _Deadline(limit):
                result = fn(cfg)
        else:
            result = fn(cfg)
        data = result.to_dict() if hasattr(result, "to_dict") else dict(result)
        complex_ = [k for k in (*PROFILE_VARS, *REPLICA_VARS, "residual_history")
                    if k in data and np.iscomplexobj(data[k])]
        if complex_:  # np.asarray(..., float64) would drop the imaginary part
            raise TypeError("complex values in " + ", ".join(complex_) + " (the schema"
                            " holds real numbers)")
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
    except GraceExpired:
        raise  # the in-process grace period ran out: the master stops
    except PointTimeout as exc:
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
    return Outcome(hash=task.hash, **out, host=host(), rank=rank, pid=os.getpid(),
                   start_time=start_wall, end_time=utc_now(),
                   wall_time=time.perf_counter() - t0)


#: In-process, a point with a ``point_timeout`` runs in a child process killed this long
#: after its limit if it has not returned (its soft timeout ignored, as by a point that
#: catches ``BaseException`` in a loop): max(_CHILD_MARGIN, 5 % of the limit) [s].
_CHILD_MARGIN = float(os.environ.get("SWEEP_CHILD_MARGIN", "1.0"))


def compute_in_child(task: Task, fn: Callable[[ModelConfig], Any], rank: int = 0) -> Outcome:
    """:func:`compute_point` in a forked child process (in-process runs with a
    ``point_timeout``): the child is killed a margin after the limit if it has not
    returned, so a point that ignores its timeout is ``timeout`` in this run; a child
    that dies (``os._exit``, a crash) makes the point ``crashed`` in this run. The
    campaign's process is never at the point's mercy. Stop signals are the parent's: the
    child ignores them; a :class:`GraceExpired` in the parent kills the child."""
    limit = float(task.timeout or 0.0)
    hard = limit + max(_CHILD_MARGIN, 0.05 * limit)
    sys.stdout.flush()
    sys.stderr.flush()
    r, w = os.pipe()
    start_wall, t0 = utc_now(), time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child: compute, send, leave without any of the parent's exit work
        code = 0
        try:
            os.close(r)
            for sig in STOP_SIGNALS:
                signal.signal(sig, signal.SIG_IGN)
            with contextlib.suppress(Exception):
                ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
            data = pickle.dumps(compute_point(task, fn, rank), pickle.HIGHEST_PROTOCOL)
            view = memoryview(data)
            while view:
                view = view[os.write(w, view):]
        except BaseException:  # noqa: BLE001 - the parent says what happened
            code = 1
        finally:
            with contextlib.suppress(Exception):
                sys.stdout.flush()
                sys.stderr.flush()
            os._exit(code)
    os.close(w)
    chunks: list[bytes] = []
    killed = False
    try:
        deadline = time.monotonic() + hard
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                os.kill(pid, signal.SIGKILL)
                killed = True
                break
            ready, _, _ = select.select([r], [], [], min(left, 1.0))
            if ready:
                chunk = os.read(r, 1 << 20)
                if not chunk:
                    break
                chunks.append(chunk)
    except BaseException:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
        raise
    finally:
        os.close(r)
        _, status = os.waitpid(pid, 0)
    where = f"rank {rank}, host {host()}, pid {pid}"
    if chunks and not killed:
        try:
            return pickle.loads(b"".join(chunks))
        except Exception:  # noqa: BLE001 - a torn result: the child died writing it
            pass
    if killed:
        kind, message = "timeout", (f"ran longer than point_timeout = {limit:g} s and did"
                                    f" not stop: its process was killed after {hard:g} s"
                                    f" ({where})")
    else:
        how = (f"by signal {signal.Signals(os.WTERMSIG(status)).name}"
               if os.WIFSIGNALED(status) else
               f"with status {os.waitstatus_to_exitcode(status)}")
        kind, message = "crashed", (f"its process ended {how} while computing it, without"
                                    f" a result (a crash, or exit() in the model) ({where})")
    return Outcome(hash=task.hash, status=kind, message=message, host=host(), rank=rank,
                   pid=pid, start_time=start_wall, end_time=utc_now(),
                   wall_time=time.perf_counter() - t0)
