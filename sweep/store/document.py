"""The store's schema as a JSON document: ``results_schema/schema_v<N>.json`` is generated here.

A test keeps the shipped file identical to :func:`schema_document`.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sweep.store import schema
from sweep.store.migrate import MIGRATIONS
from sweep.store.schema import (
    COLUMNS,
    FORMAT,
    HISTORY_VAR,
    PROFILE_VARS,
    REPLICA_VARS,
    ROOT_ATTRS,
    RUN_ATTRS,
    SCHEMA_VERSION,
    STATUSES,
)

__all__ = ["schema_document", "write_schema_file"]


def schema_document() -> dict[str, Any]:
    """The human-readable schema as a JSON-able dict (``results_schema/schema_v1.json``)."""
    return {
        "schema_version": SCHEMA_VERSION,
        "format": FORMAT,
        "layout": schema.__doc__.split("Layout of a store (one HDF5 file)::", 1)[1].strip()
        .split("\n\nA point")[0].splitlines(),
        "commit_rule": "a point is committed when its row index is below "
                       "/table.attrs['n_rows']; rows and profile groups beyond that are "
                       "removed on the next open",
        "root_attributes": ROOT_ATTRS,
        "run_attributes": list(RUN_ATTRS),
        "table_columns": [{"name": c.name, "kind": c.kind, "units": c.units,
                           "long_name": c.long_name,
                           "dtype": {"float": "float64", "int": "int64",
                                     "str": "variable-length UTF-8"}[c.kind]}
                          for c in COLUMNS],
        "profile_datasets": [{"name": n, "units": u, "long_name": ln, "dtype": "float64",
                              "length": "N_f"} for n, (u, ln) in PROFILE_VARS.items()]
        + [{"name": HISTORY_VAR[0], "units": HISTORY_VAR[1], "long_name": HISTORY_VAR[2],
            "dtype": "float64", "length": "iterations"}]
        + [{"name": n, "units": u, "long_name": ln, "dtype": "float64",
            "shape": list(shape), "optional": "absent for points stored before schema 3"}
           for n, (u, ln, shape) in REPLICA_VARS.items()],
        "statuses": list(STATUSES),
        "hash": {
            "algorithm": "SHA-256, lower-case hex, 64 characters; displayed as the first 12",
            "input": 'canonical JSON of {"config": <every floewave.ModelConfig field>, '
                     '"model_version": floewave.MODEL_VERSION}',
            "canonical_json": "keys sorted, separators ',' and ':', ASCII, numbers of float "
                              "fields written as floats by Python repr (1 and 1.0 alike), "
                              "-0.0 written as 0.0, NaN/inf refused",
            "example": "see tests/sweep/test_identity.py for pinned values",
        },
        "journal": "<store>.journal beside the store: one JSON line per event, each ending "
                   "in a CRC-32 member \"crc32\" of the line without it: a campaign line "
                   "(journal: sweep-journal, version 3, campaign_hash, campaign_json) first "
                   "and after each --extend, one line per stored point (row, profiles, "
                   "residual_history; since version 3 each array is {\"f8\": base64 of its "
                   "little-endian float64 bytes in C order, \"shape\": [...]}, before it a "
                   "JSON list of numbers, still read; a journal of a newer version than the "
                   "reader knows is refused, exit status 3), fsynced before the HDF5 write, "
                   "and hand-out/release "
                   "lines (attempt counting). Replayed on open and used to rebuild an "
                   "unclean or damaged store; lines failing their checksum or hash re-check, "
                   "and records that cannot be written, are moved to "
                   "<store>.journal.rejected with their reason",
        "lock": "<store>.lock: flock-held by the live writer (pid, host, start); a lock "
                "file whose flock is free is stale and is taken over; the writer also "
                "holds an flock on the journal, so removing the lock file does not admit "
                "a second writer",
        "migrations": {str(k): {"to": v[0], "description": v[1]}
                       for k, v in MIGRATIONS.items()},
    }


def write_schema_file(directory: str | Path) -> Path:
    """Write ``schema_v<N>.json`` into ``directory`` (used to regenerate results_schema/)."""
    path = Path(directory) / f"schema_v{SCHEMA_VERSION}.json"
    path.write_text(json.dumps(schema_document(), indent=2) + "\n", encoding="utf-8")
    return path
