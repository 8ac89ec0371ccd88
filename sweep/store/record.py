"""One finished point: :class:`Record`, built once from (point, outcome).

A worker's :class:`sweep.protocol.Outcome` (status, message, scalars, profiles,
residual history and where and when it ran; :meth:`~sweep.protocol.Outcome.known` for a
point the master decides without a worker: ``invalid``, ``crashed``), a record
read back from a store (:mod:`sweep.store.reader`) or from the journal: each becomes a
:class:`Record` holding the table row and the point's datasets, already converted to the
schema's kinds (:func:`sweep.store.cells.normalise_record`). The store stages Records
(:meth:`sweep.store.store.Store.add`); the journal line (:meth:`Record.journal_line`) and the
HDF5 row and datasets (:meth:`sweep.store.writer.H5Writer.write_many`) are written from it.

A Record also reads like the dict it replaces (``rec["row"]``, ``rec["profiles"]``,
``rec["residual_history"]``), so code holding the old ``{"row": ..., "profiles": ...,
"residual_history": ...}`` dicts keeps working; :meth:`Record.coerce` takes either.
"""
from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sweep.errors import UnstorableError
from sweep.identity import DIMENSIONS, canonical_json
from sweep.protocol import Outcome
from sweep.store.cells import check_profiles, normalise_record
from sweep.store.journal import encode
from sweep.store.schema import RESULT_COLUMNS, column

__all__ = ["Record", "provenance_json"]


@dataclass
class Record:
    """A point as the store holds it: the table ``row`` (column -> value, the schema's
    kinds), its ``profiles`` (name -> float64 array) and ``residual_history``."""

    row: dict[str, Any]
    profiles: dict[str, np.ndarray] = field(default_factory=dict)
    residual_history: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: converted to the schema's kinds already (:meth:`coerce`)
    normal: bool = field(default=False, repr=False, compare=False)

    # ------------------------------------------------------------------ the old dict
    def __getitem__(self, key: str) -> Any:
        if key in ("row", "profiles", "residual_history"):
            return getattr(self, key)
        raise KeyError(key)

    def get(self, key: str, default: Any = None) -> Any:
        return self[key] if key in ("row", "profiles", "residual_history") else default

    def keys(self) -> tuple[str, ...]:
        return ("row", "profiles", "residual_history")

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def __contains__(self, key: object) -> bool:
        return key in self.keys()

    # ------------------------------------------------------------------ building
    @classmethod
    def coerce(cls, record: Record | Mapping[str, Any]) -> Record:
        """A Record as stored: ``record`` (a Record or a dict of the same members)
        converted to the schema's kinds (:class:`sweep.errors.UnstorableError` names a value
        that cannot be; a row without ``hash`` is unstorable)."""
        if isinstance(record, Record) and record.normal:
            return record
        rec = normalise_record(record if isinstance(record, Mapping)
                               else record.as_dict())
        if "hash" not in rec["row"]:
            raise UnstorableError("no 'hash'")
        check_profiles(rec["row"], rec["profiles"])
        return cls(rec["row"], rec["profiles"], rec["residual_history"], normal=True)

    @classmethod
    def from_outcome(cls, point: Any, out: Outcome,
                     config: dict[str, Any] | None = None,
                     provenance: Callable[[int, str], str] | None = None) -> Record:
        """The Record of ``point`` (a :class:`sweep.config.Point`) from a worker's
        outcome ``out`` (or :meth:`sweep.protocol.Outcome.known`): its swept values, its scalar
        results converted to their columns' kinds, the bookkeeping (status, message,
        host, rank, pid, times, canonical ``config_json``) and ``provenance(rank,
        kernel_mode)`` (the JSON of the environment that computed it).

        A result the schema cannot hold makes a ``failed`` record saying why (never an
        exception): a scalar of the wrong kind ("does not fit the schema"), or a value
        or profile :func:`sweep.store.cells.normalise_record` refuses ("cannot be stored").
        """

        try:
            return cls.coerce(_row_of(point, out, config, provenance))
        except UnstorableError as exc:  # the record cannot be stored: a failed point
            out = out.without_results("failed", f"the result cannot be stored: {exc}")
            return cls.coerce(_row_of(point, out, config, provenance))

    def as_dict(self) -> dict[str, Any]:
        """The record as the dict of its three members."""
        return {"row": self.row, "profiles": self.profiles,
                "residual_history": self.residual_history}

    def stamped(self, seq: int, run: int) -> Record:
        """This record with its journal sequence number and run index (the row's other
        members keep their order; ``seq`` and ``run`` come last unless already there)."""
        row = dict(self.row)
        row["seq"] = seq
        row["run"] = run
        return Record(row, self.profiles, self.residual_history, self.normal)

    # ------------------------------------------------------------------ writing
    def journal_line(self) -> bytes:
        """The record's journal line (:func:`sweep.store.journal.encode`)."""
        return encode({"row": self.row,
                       "profiles": {k: np.asarray(v, dtype=np.float64)
                                    for k, v in self.profiles.items()},
                       "residual_history": np.asarray(self.residual_history,
                                                      dtype=np.float64)})

    @property
    def hash(self) -> str:
        return str(self.row["hash"])

    @property
    def status(self) -> str:
        return str(self.row.get("status", ""))


def _row_of(point: Any, out: Outcome, config: dict[str, Any] | None,
            provenance: Callable[[int, str], str] | None) -> dict[str, Any]:
    """The record dict of ``point`` from outcome ``out`` (before normalisation)."""
    row: dict[str, Any] = {name: getattr(point.config, name)
                           for name in DIMENSIONS}
    scalars = out.scalars
    unusable = []
    # the model's declared outputs (floewave.outputs) as the kind declared: those stored
    # under their own name in the result's order, then those stored under another name
    # (model_wall_time: the row's order of schema 1); anything else is not the model's
    declared = [(name, name) for name in scalars if RESULT_COLUMNS.get(name) == name]
    renamed = [(name, stored) for name, stored in RESULT_COLUMNS.items() if stored != name]
    for name, stored in (*declared, *renamed):
        value = scalars.get(name)
        try:
            row[stored] = _result_value(column(stored).kind, value)
        except (TypeError, ValueError, OverflowError):
            unusable.append(f"{name} = {str(value)[:40]!r}")
    if unusable:  # the schema cannot hold the result: a failed point, with the reason
        out = dataclasses.replace(
            out, status="failed", profiles={}, residual_history=np.zeros(0),
            message="the result does not fit the schema: " + ", ".join(unusable))
        row = {name: getattr(point.config, name) for name in DIMENSIONS}
    row.update(hash=point.hash, status=out.status, message=out.message,
               host=out.host, rank=int(out.rank), pid=int(out.pid),
               start_time=out.start_time, end_time=out.end_time,
               wall_time=float(out.wall_time), config_json=canonical_json(
                   point.config.to_dict() if config is None else config))
    if provenance is not None:  # the same for every point of a rank and kernel mode
        row["provenance"] = provenance(int(out.rank), str(scalars.get("kernel_mode", "")))
    return {"row": row, "profiles": out.profiles, "residual_history": out.residual_history}


def _result_value(kind: str, value: Any) -> Any:
    """A model's scalar as its declared kind: None or NaN is missing (-1 for a count, NaN
    for a float); +-inf is no result (ValueError)."""
    if kind == "str":
        return str(value)
    if kind == "int":
        return (-1 if value is None or (isinstance(value, float) and math.isnan(value))
                else int(value))
    number = float(value) if value is not None else math.nan
    if math.isinf(number):
        raise ValueError("not finite")
    return number


def provenance_json(env: Mapping[str, Any], git: Mapping[str, Any], kernel_mode: str) -> str:
    """The ``provenance`` column: a worker's environment, the master's git state and the
    kernel mode, as sorted JSON."""
    prov = dict(env)
    prov.update(git)
    prov["kernel_mode"] = kernel_mode
    return json.dumps(prov, sort_keys=True)
