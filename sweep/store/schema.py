"""The store's on-disk layout: schema version, table columns, profile datasets, attributes.

This module is the single source of the layout: the store writes it, the analysis
reads it, :func:`sweep.store.validate.validate` checks a file against it,
:mod:`sweep.store.migrate` brings older layouts up to it, and
``results_schema/schema_v1.json`` is generated from it
(:func:`sweep.store.document.schema_document`; a test keeps the two identical).
Layout of a store (one HDF5 file)::

    /                      attrs: schema_version, format, created, campaign_toml,
                                  campaign_json, campaign_hash, swept_fields (JSON)
    /table/<column>        one 1-D dataset per column of :data:`COLUMNS`;
                           attrs of /table: n_rows (rows beyond it are not committed)
    /profiles/<hh>/<hash>  per point (hh = first two hash characters): one float64
                           dataset per :data:`PROFILE_VARS` entry of length N_f,
                           residual_history (length = iterations), and (schema 3) one
                           per :data:`REPLICA_VARS` entry of shape (R,) or (R, N_f);
                           attrs: hash
    /runs/<n>              attrs: provenance of the n-th ``sweep run`` on this store
    /campaign_history/<n>  earlier campaign texts (``--extend``)

A point is committed when its row index is below ``/table.attrs["n_rows"]``.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from floewave import outputs

__all__ = ["SCHEMA_VERSION", "FORMAT", "Column", "OWN_HEAD", "OWN_TAIL", "COLUMNS",
           "RESULT_COLUMNS", "model_columns", "DERIVED", "DERIVED_FROM",
           "PROFILE_VARS", "REPLICA_VARS",
           "STATUSES", "ADDED_IN", "MIGRATION_FILL", "FROM_CONFIG", "config_values",
           "HISTORY_VAR", "ROOT_ATTRS", "RUN_ATTRS",
           "column", "profile_path"]

SCHEMA_VERSION = 5
FORMAT = "sweep-store"

#: Point statuses: the model's three plus sweep's four (``crashed``: its worker died
#: ``[run] max_attempts`` times computing it; ``timeout``: ran past ``point_timeout``).
STATUSES = ("converged", "converged_noisy", "not_converged", "failed", "invalid", "crashed",
            "timeout")


@dataclass(frozen=True)
class Column:
    """One column of the per-point table: name, kind (float/int/str), units, meaning."""

    name: str
    kind: str
    units: str
    long_name: str

    @property
    def fill(self) -> Any:
        """Value for a point that does not report this column."""
        return {"float": np.nan, "int": -1, "str": ""}[self.kind]


_C = Column
#: The store's own leading columns: the point's identity, its swept parameters, its status.
OWN_HEAD: tuple[Column, ...] = (
    _C("hash", "str", "", "point identity: SHA-256 of canonical config JSON"),
    _C("L_x", "float", "m", "floe length"),
    _C("T", "float", "s", "wave period"),
    _C("a0", "float", "m", "incident wave amplitude"),
    _C("C_sd", "float", "1", "skin-drag coefficient"),
    _C("eps", "float", "1", "nominal restitution coefficient"),
    _C("d_f", "float", "m", "initial floe-floe distance"),
    _C("dispersion", "str", "", "dispersion relation (ep, ml, ow)"),
    _C("seed", "int", "1", "ensemble seed of the point's replicas (a swept dimension when a"
       " campaign sweeps it)"),
    _C("status", "str", "", "converged, converged_noisy, not_converged, failed, invalid,"
       " crashed, timeout"),
    _C("message", "str", "", "reason for failed/invalid (traceback with rank and host)"),
)
#: The store's own trailing columns: where, when and by which run a point was computed.
OWN_TAIL: tuple[Column, ...] = (
    _C("host", "str", "", "host that computed the point"),
    _C("rank", "int", "1", "MPI rank that computed the point (0: in-process)"),
    _C("pid", "int", "1", "process id that computed the point"),
    _C("start_time", "str", "", "start of computation, ISO 8601 UTC"),
    _C("end_time", "str", "", "end of computation, ISO 8601 UTC"),
    _C("wall_time", "float", "s", "wall time of the point measured by the worker"),
    _C("run", "int", "1", "index of the sweep run (/runs/<n>) that stored the point"),
    _C("seq", "int", "1", "journal sequence number of the stored record"),
    _C("config_json", "str", "", "canonical JSON of the resolved ModelConfig"),
    _C("provenance", "str", "", "JSON: versions of package, git, python, numpy, numba, MPI"),
)


def model_columns(declared: tuple[outputs.Output, ...] = outputs.OUTPUTS) -> tuple[Column, ...]:
    """The table columns of the model's declared scalar outputs, in their order."""
    return tuple(Column(str(o.column), o.kind, o.unit, o.long_name)
                 for o in outputs.table_outputs(declared))


#: The per-point table (``/table/<name>``), one row per point: the store's own columns
#: around the model's (:data:`floewave.outputs.OUTPUTS`).
COLUMNS: tuple[Column, ...] = (*OWN_HEAD, *model_columns(), *OWN_TAIL)
#: The table column of each model output stored there (PointResult field -> column).
RESULT_COLUMNS = {o.name: str(o.column) for o in outputs.table_outputs()}
#: Columns that :func:`sweep.load` and :func:`sweep.load_xarray` derive from stored ones
#: when they read a store (not stored: the store's layout and version do not change).
DERIVED: tuple[Column, ...] = (
    _C("a_end_rel", "float", "1", "a_end / a0: relative amplitude at the far end of the"
       " sheet"),
    _C("a_end_rel_stderr", "float", "1", "standard error of a_end_rel: a_end_stderr / a0"),
)
#: What each derived column is computed from (``a / b``, by name).
DERIVED_FROM = {"a_end_rel": ("a_end", "a0"), "a_end_rel_stderr": ("a_end_stderr", "a0")}
_BY_NAME = {c.name: c for c in (*COLUMNS, *DERIVED)}
#: Schema version that added a column (columns not listed: version 1).
ADDED_IN = {"compact_zone": 2, "compact_end": 2, "ice_extent": 2,
            **{name: 3 for name in ("replicas", "W_c_stderr", "W_c_n", "alpha_all_stderr",
                                    "alpha_edge_stderr", "alpha_inner_stderr",
                                    "alpha_exp_stderr", "a_end_stderr")},
            **{name: 4 for name in ("W_c_gap", "W_c_gap_stderr", "contact_fraction_mean",
                                    "contact_fraction_mean_stderr", "collision_rate",
                                    "collision_rate_stderr", "dissipation_per_collision",
                                    "dissipation_per_collision_stderr")},
            "seed": 5}
#: Fill value of a column added by a migration, where it differs from the column's fill
#: (every point stored before schema 3 ran one trajectory; schema 4's columns: NaN).
MIGRATION_FILL = {"replicas": 1}
#: Columns added by a migration whose value is the configuration field of the same name,
#: read from each row's ``config_json`` (schema 5's ``seed``: every point had one): the
#: migration fills them so, and a reader of an older store reads them so.
FROM_CONFIG = ("seed",)

#: Per-point profiles (``/profiles/<hh>/<hash>/<name>``): name -> (units, long_name).
PROFILE_VARS: dict[str, tuple[str, str]] = {o.name: (o.unit, o.long_name)
                                            for o in outputs.profiles()}
HISTORY_VAR = (outputs.history().name, outputs.history().unit, outputs.history().long_name)
#: Per-replica results of an ensemble (schema 3; absent for points stored before it):
#: name -> (units, long_name, shape) with shape ``("R",)`` or ``("R", "N_f")``.
REPLICA_VARS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    o.name: (o.unit, o.long_name, o.dims) for o in outputs.replica_outputs()}


def profile_path(h: str) -> str:
    """The HDF5 group of point ``h``'s profiles: ``profiles/<first two hash chars>/<h>``."""
    return f"profiles/{h[:2]}/{h}"


ROOT_ATTRS = {
    "schema_version": "int: version of this layout",
    "format": f"str: always {FORMAT!r}",
    "created": "str: ISO 8601 UTC time the store was created",
    "campaign_toml": "str: text of the campaign file of the latest run",
    "campaign_json": "str: canonical JSON of the campaign definition (base, sweep, "
                     "model_version)",
    "campaign_hash": "str: SHA-256 of campaign_json",
    "swept_fields": "str: JSON list of the swept dimensions, in grid order",
    "writer_open": "bool: true while a writer has the store open (set before it changes "
                   "anything); true on open means the last writer died, and the store is "
                   "rebuilt from the journal (atomically: temporary file, then rename)",
}
RUN_ATTRS = ("started", "ended", "host", "mpi_size", "sweep_version", "floewave_version",
             "model_version", "git_commit", "git_dirty", "python", "numpy", "numba",
             "h5py", "mpi4py", "mpi_library", "command", "outcome")


def config_values(name: str, config_jsons: Any) -> list[Any]:
    """Field ``name`` of each row's ``config_json`` (the column's fill where a row has no
    readable configuration or the configuration lacks the field)."""
    fill = column(name).fill
    out = []
    for cj in config_jsons:
        try:
            cfg = json.loads(cj.decode() if isinstance(cj, bytes) else cj)
            cfg = cfg.get("config", cfg)
            out.append(cfg.get(name, fill))
        except (ValueError, AttributeError, TypeError):
            out.append(fill)
    return out


def column(name: str) -> Column:
    """The :class:`Column` called ``name``."""
    return _BY_NAME[name]

