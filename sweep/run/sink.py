"""Where the master's results go: :class:`ResultSink`, the one interface of a run's two
writers of its store.

- :class:`InlineSink`: the master writes the store (:class:`sweep.store.store.Store`)
  itself (an in-process run; an MPI run with ``[run] writer = "inline"``): each result
  becomes its record here, and a batch of results is stored when its group commit returns;
- :class:`sweep.run.store_process.StoreProcess`: a writer process writes it (MPI runs by
  default): each result's bytes are passed on unread, and a result is stored when the
  writer reports it committed.

:class:`Provenance` builds a point's ``provenance`` column, once per worker and kernel mode;
both writers use it.
"""
from __future__ import annotations

from typing import Any, Literal, Protocol

from sweep.config import Point
from sweep.protocol import Outcome, Packed, unpacked
from sweep.store.attempts import running
from sweep.store.record import Record, provenance_json
from sweep.store.store import Store

__all__ = ["ResultSink", "InlineSink", "Provenance"]


class Provenance:
    """The ``provenance`` column of a point computed by ``rank`` in ``kernel_mode``:
    ``provenance(rank, kernel_mode)`` (the same for all its points: built once).

    Parameters
    ----------
    worker_env : each worker's environment by rank (the transport's
        ``worker_env``, read when a rank's first point is stored).
    git : the master's git state and sweep version.
    """

    def __init__(self, worker_env: dict[int, dict[str, Any]],
                 git: dict[str, Any] | None = None) -> None:
        self.worker_env = worker_env
        self.git = git or {}
        self._built: dict[tuple[int, str], str] = {}

    def __call__(self, rank: int, kernel_mode: str) -> str:
        key = (rank, kernel_mode)
        prov = self._built.get(key)
        if prov is None:
            prov = self._built[key] = provenance_json(
                self.worker_env.get(rank, {}), self.git, kernel_mode)
        return prov


class ResultSink(Protocol):
    """What the master (:class:`sweep.run.master.Master`) and the campaign loop
    (:func:`sweep.run.launch.run_campaign`) ask of the store they write to."""

    #: builds the ``provenance`` column of the records the master builds itself
    provenance: Provenance
    #: what a worker waits for between handing in a result and getting its next task,
    #: the time that sets how many tasks it holds (:attr:`sweep.run.master.Master.depth`):
    #: "handout" (its next hand-out journaled) or "commit" (its result's group commit)
    waits_for: Literal["handout", "commit"]

    # before the run: what the store holds
    def __contains__(self, h: str) -> bool: ...

    def status_of(self, h: str) -> str: ...

    def handouts(self, h: str) -> list[tuple[int, int, bool]]: ...

    def suspects(self) -> set[str]:
        """The points that may have been running when an earlier run died
        (:func:`sweep.store.attempts.running`)."""

    # the master's own records (``invalid``, ``crashed``), one group commit
    def add(self, record: Record) -> None: ...

    def commit(self) -> int: ...

    def handout(self, hashes: list[tuple[str, int]], alone: bool = False) -> None:
        """Journal hand-outs ``[(hash, worker), ...]``; returns once they are written."""

    def submit(self, point: Point, payload: Packed | Outcome,
               config: dict[str, Any] | None = None) -> None:
        """Take one worker's result of ``point`` (``config``: its configuration as
        handed out)."""

    def settle(self, everything: bool) -> list[str]:
        """The end of a batch of :meth:`submit`: the statuses of the results stored
        since the last call; ``everything``: once every result submitted is stored."""

    def take_stored(self) -> list[str]:
        """The statuses of the results stored since the last call, not waiting."""

    def wait(self, timeout: float) -> list[str]:
        """:meth:`take_stored`, waiting up to ``timeout`` [s] for a result to be stored."""

    def sync(self) -> list[str]:
        """Wait until every result submitted is stored; their statuses (and those of
        earlier ones not yet taken)."""

    def release(self, hashes: list[str]) -> None:
        """Journal that handed-out points were abandoned by a stop (no attempt)."""

    def close(self, outcome: str = "complete") -> None:
        """Record the run's outcome and close the store."""

    @property
    def store_cpu(self) -> float:
        """[s] CPU of a writer beside the master from its store's open to its close
        (0.0: the master writes the store)."""

    @property
    def store_wall(self) -> float:
        """[s] the wall time :attr:`store_cpu` was measured over (0.0: not measured)."""


class InlineSink:
    """The master writes the store itself: a result becomes its record when it is
    submitted, and a batch is stored by one group commit (:meth:`settle`).

    Parameters
    ----------
    store : the open store (this process is its only writer).
    worker_env, git : as :class:`Provenance`.
    """

    waits_for: Literal["handout", "commit"] = "commit"

    def __init__(self, store: Store, worker_env: dict[int, dict[str, Any]],
                 git: dict[str, Any] | None = None) -> None:
        self.store = store
        self.provenance = Provenance(worker_env, git)
        self._staged: list[str] = []  # statuses of the results submitted, not committed

    def __contains__(self, h: str) -> bool:
        return h in self.store

    def status_of(self, h: str) -> str:
        return self.store.status_of(h)

    def handouts(self, h: str) -> list[tuple[int, int, bool]]:
        return self.store.handouts(h)

    def suspects(self) -> set[str]:
        return running(self.store.scan)

    def add(self, record: Record) -> None:
        self.store.add(record)

    def commit(self) -> int:
        return self.store.commit()

    def handout(self, hashes: list[tuple[str, int]], alone: bool = False) -> None:
        self.store.handout(hashes, alone=alone)

    def submit(self, point: Point, payload: Packed | Outcome,
               config: dict[str, Any] | None = None) -> None:
        rec = Record.from_outcome(point, unpacked(payload), config, self.provenance)
        self.store.add(rec)
        self._staged.append(rec.status)

    def settle(self, everything: bool) -> list[str]:
        """One group commit of the batch; then all of it is stored."""
        self.store.commit()
        stored, self._staged = self._staged, []
        return stored

    def take_stored(self) -> list[str]:
        """Nothing: results are stored only by :meth:`settle`."""
        return []

    def wait(self, timeout: float) -> list[str]:
        """Nothing: results are stored only by :meth:`settle` (between batches none
        is waiting here)."""
        return []

    def sync(self) -> list[str]:
        return self.settle(True) if self._staged else []

    def release(self, hashes: list[str]) -> None:
        self.store.release(hashes)

    def close(self, outcome: str = "complete") -> None:
        self.store.close(outcome)

    @property
    def store_cpu(self) -> float:
        return 0.0

    @property
    def store_wall(self) -> float:
        return 0.0
