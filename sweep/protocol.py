"""The worker protocol: the Task a master hands out, the Outcome a worker returns, the kinds.

The master (:mod:`sweep.run.master`) sends a :class:`Task` (or a :class:`WarmUp`, or
``None``: stop) to a worker on :data:`TAG_TASK`; a worker answers on :data:`TAG_RESULT`
with a ``(kind, payload)`` pair, ``kind`` a :class:`Kind`:

=========== ====================================================================
``READY``   the worker started; payload: its environment (a dict, for provenance)
``ERROR``   it failed outside a point (start-up, import); payload: :class:`WorkerFailure`
``RESULT``  one point computed; payload: its :class:`Packed` outcome (an
            :class:`Outcome` from the in-process transport)
``WARM``    the warm-up is done; payload: (seconds, problem or ``""``)
=========== ====================================================================

A worker sends its outcome :class:`Packed`: a small header (hash, status, wall time) and
the outcome's pickled bytes, which a master whose store is written by another process
(:mod:`sweep.run.store_process`) passes on unread. The in-process transport passes the
:class:`Outcome` itself, without pickling it. An
:class:`Outcome` becomes one stored row through :meth:`sweep.store.record.Record.from_outcome`.
"""
from __future__ import annotations

import dataclasses
import enum
import os
import pickle
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sweep.provenance import host
from sweep.system import utc_now

__all__ = ["Kind", "Task", "WarmUp", "Outcome", "Packed", "WorkerFailure", "TAG_TASK",
           "TAG_RESULT", "plain", "unpacked"]

#: MPI tags: master -> worker (tasks), worker -> master (replies).
TAG_TASK, TAG_RESULT = 1, 2


class Kind(enum.StrEnum):
    """The kind of a worker's reply (a ``str``, so it prints and compares as its value)."""

    READY = "ready"
    ERROR = "error"
    RESULT = "result"
    WARM = "warm"


@dataclass(frozen=True)
class Task:
    """One point to compute: its ``hash``, its configuration (``ModelConfig.to_dict()``)
    and its ``timeout`` [s] (0: no limit)."""

    hash: str
    config: dict[str, Any]
    timeout: float = 0.0


@dataclass(frozen=True)
class WarmUp:
    """Compile the kernels of these shrunken configurations (:mod:`sweep.run.warmup`)."""

    configs: tuple[dict[str, Any], ...]


@dataclass(frozen=True)
class WorkerFailure:
    """A worker's failure outside a point, with where it happened and its traceback."""

    rank: int
    host: str
    message: str
    traceback: str = ""


def plain(value: Any) -> Any:
    """A value as plain Python (numpy scalars and arrays to Python numbers and lists)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


@dataclass(frozen=True)
class Outcome:
    """What became of one point: its ``status`` and ``message``, the model's scalar
    results, profiles [name -> float64 array] and residual history, and where and when
    it ran (``host``, ``rank``, ``pid``, ``start_time``/``end_time`` ISO 8601 UTC,
    ``wall_time`` [s])."""

    hash: str
    status: str
    message: str = ""
    scalars: dict[str, Any] = field(default_factory=dict)
    profiles: dict[str, np.ndarray] = field(default_factory=dict)
    residual_history: np.ndarray = field(default_factory=lambda: np.zeros(0))
    host: str = ""
    rank: int = 0
    pid: int = 0
    start_time: str = ""
    end_time: str = ""
    wall_time: float = 0.0

    @classmethod
    def known(cls, h: str, status: str, message: str) -> Outcome:
        """The outcome of a point the master decides without computing it (``invalid``:
        its configuration is impossible; ``crashed``: it killed its worker
        ``max_attempts`` times), stamped with the master's host, pid and time."""
        now = utc_now()
        return cls(hash=h, status=status, message=message, host=host(), rank=0,
                   pid=os.getpid(), start_time=now, end_time=now, wall_time=0.0)

    def without_results(self, status: str, message: str) -> Outcome:
        """This outcome as a point without results: no scalars, profiles or history."""
        return dataclasses.replace(self, status=status, message=message, scalars={},
                                   profiles={}, residual_history=np.zeros(0))


@dataclass(frozen=True)
class Packed:
    """An :class:`Outcome` as a worker sends it: the header the master reads (``hash``,
    ``status``, ``wall_time``) and the outcome's pickled bytes (``data``), which the master
    unpickles (:meth:`outcome`) or passes on unread to the store's writer process."""

    hash: str
    status: str
    wall_time: float
    data: bytes

    @classmethod
    def of(cls, out: Outcome) -> Packed:
        return cls(out.hash, out.status, float(out.wall_time),
                   pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL))

    def outcome(self) -> Outcome:
        return pickle.loads(self.data)


def unpacked(payload: Outcome | Packed) -> Outcome:
    """The :class:`Outcome` of a ``RESULT`` payload, packed or not."""
    return payload.outcome() if isinstance(payload, Packed) else payload
