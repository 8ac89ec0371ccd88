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

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["SCHEMA_VERSION", "FORMAT", "Column", "COLUMNS", "DERIVED", "DERIVED_FROM",
           "PROFILE_VARS", "REPLICA_VARS",
           "STATUSES", "ADDED_IN", "MIGRATION_FILL", "HISTORY_VAR", "ROOT_ATTRS", "RUN_ATTRS",
           "column", "profile_path"]

SCHEMA_VERSION = 4
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
#: The per-point table (``/table/<name>``), one row per point.
COLUMNS: tuple[Column, ...] = (
    _C("hash", "str", "", "point identity: SHA-256 of canonical config JSON"),
    _C("L_x", "float", "m", "floe length"),
    _C("T", "float", "s", "wave period"),
    _C("a0", "float", "m", "incident wave amplitude"),
    _C("C_sd", "float", "1", "skin-drag coefficient"),
    _C("eps", "float", "1", "nominal restitution coefficient"),
    _C("d_f", "float", "m", "initial floe-floe distance"),
    _C("dispersion", "str", "", "dispersion relation (ep, ml, ow)"),
    _C("status", "str", "", "converged, converged_noisy, not_converged, failed, invalid,"
       " crashed, timeout"),
    _C("message", "str", "", "reason for failed/invalid (traceback with rank and host)"),
    _C("n_floes", "int", "1", "number of floes N_f"),
    _C("W_c", "float", "m", "collision-zone width: start of the first compact zone (NaN: none)"),
    _C("compact_zone", "str", "", "layout of the compact zone: edge, inverted, patchy, none"),
    _C("compact_end", "float", "m", "end of the first compact zone"),
    _C("ice_extent", "float", "m", "far end of the ice: last floe's mean centre + L_x/2"),
    _C("alpha_all", "float", "m-2", "slope of 1/a over all floes"),
    _C("alpha_all_resid", "float", "1", "RMS misfit of the 1/a fit over all floes / a0"),
    _C("alpha_edge", "float", "m-2", "slope of 1/a in the collisional zone x < W_c (all"
       " floes without a compact zone; NaN if too short)"),
    _C("alpha_edge_resid", "float", "1", "RMS misfit of the edge fit / a0"),
    _C("alpha_inner", "float", "m-2", "slope of 1/a in the first compact zone (NaN: none or"
       " too short)"),
    _C("alpha_inner_resid", "float", "1", "RMS misfit of the inner fit / a0"),
    _C("alpha_exp", "float", "m-1", "exponential attenuation rate (slope of -ln a)"),
    _C("alpha_exp_resid", "float", "1", "RMS misfit of the exponential fit / a0"),
    _C("alpha_c", "float", "m-2", "confined-ice attenuation rate (eq. 24)"),
    _C("k", "float", "rad m-1", "wavenumber (eq. 6)"),
    _C("c_g", "float", "m s-1", "group velocity (eq. 7)"),
    _C("noise", "float", "1", "residual noise floor (converged_noisy)"),
    _C("iterations", "int", "1", "attenuation iterations done"),
    _C("residual", "float", "1", "final residual max |a_new - a| / a"),
    _C("floe_steps", "int", "1", "floe-steps computed (cost unit)"),
    _C("kernel_mode", "str", "", "kernel variant that ran"),
    _C("a_end", "float", "m", "amplitude at the far end of the sheet"),
    _C("model_wall_time", "float", "s", "wall time reported by the model"),
    _C("replicas", "int", "1", "floe chains R of the ensemble (1: a single trajectory)"),
    _C("W_c_stderr", "float", "m", "standard error of W_c (mean over the W_c_n replicas with"
       " a compact zone; NaN with fewer than 2)"),
    _C("W_c_n", "int", "1", "replicas with a compact zone (-1: stored before schema 3)"),
    _C("alpha_all_stderr", "float", "m-2", "jackknife standard error of alpha_all over"
       " replicas (NaN: R = 1)"),
    _C("alpha_edge_stderr", "float", "m-2", "jackknife standard error of alpha_edge"),
    _C("alpha_inner_stderr", "float", "m-2", "jackknife standard error of alpha_inner"),
    _C("alpha_exp_stderr", "float", "m-1", "jackknife standard error of alpha_exp"),
    _C("a_end_stderr", "float", "m", "standard error of a_end"),
    _C("W_c_gap", "float", "m", "W_c of the gaps time-averaged over the whole averaging:"
       " the W_c rule on each replica's gap_mean_replicas, mean over the replicas with a"
       " compact zone (NaN: none)"),
    _C("W_c_gap_stderr", "float", "m", "standard error of W_c_gap (NaN with fewer than 2"
       " replicas with a compact zone)"),
    _C("contact_fraction_mean", "float", "1", "fraction of time steps in contact, mean over"
       " the N_f - 1 pairs and the replicas (NaN: confined)"),
    _C("contact_fraction_mean_stderr", "float", "1", "jackknife standard error of"
       " contact_fraction_mean over replicas (NaN: R = 1)"),
    _C("collision_rate", "float", "1", "contact onsets per pair per wave period: mean over"
       " the pairs and the replicas of onsets in an averaging window / nT (NaN: confined)"),
    _C("collision_rate_stderr", "float", "1", "jackknife standard error of collision_rate"),
    _C("dissipation_per_collision", "float", "J", "skin-drag dissipation per collision:"
       " sum over floes of -S_sd L_x L_y [W] / sum over pairs of onsets per second, replica"
       " means (NaN: no collision, confined)"),
    _C("dissipation_per_collision_stderr", "float", "J", "jackknife standard error of"
       " dissipation_per_collision"),
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
                                    "dissipation_per_collision_stderr")}}
#: Fill value of a column added by a migration, where it differs from the column's fill
#: (every point stored before schema 3 ran one trajectory; schema 4's columns: NaN).
MIGRATION_FILL = {"replicas": 1}

#: Per-point profiles (``/profiles/<hh>/<hash>/<name>``): name -> (units, long_name).
PROFILE_VARS: dict[str, tuple[str, str]] = {
    "x_mean": ("m", "time-mean floe centre from the ice edge"),
    "a": ("m", "wave amplitude at the floe"),
    "a_stderr": ("m", "standard error of the amplitude"),
    "S_sd": ("W m-2", "skin-drag dissipation (eq. 19)"),
    "gap_mean": ("m", "mean gap to the next floe (last value NaN)"),
    "contact_fraction": ("1", "fraction of time in contact with the next floe"),
    "collisions": ("1", "contact onsets with the next floe in the averaging window"),
    "F_w_mean": ("N", "time-mean |wave force|"),
    "F_c_mean": ("N", "time-mean |contact force|"),
    "F_d_mean": ("N", "time-mean |drag force|"),
}
HISTORY_VAR = ("residual_history", "1", "residual max |a_new - a| / a per iteration")
#: Per-replica results of an ensemble (schema 3; absent for points stored before it):
#: name -> (units, long_name, shape) with shape ``("R",)`` or ``("R", "N_f")``.
REPLICA_VARS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "W_c_replicas": ("m", "W_c of each replica (NaN: no compact zone)", ("R",)),
    "compact_end_replicas": ("m", "end of each replica's first compact zone", ("R",)),
    "x_mean_replicas": ("m", "time-mean floe centre per replica", ("R", "N_f")),
    "gap_mean_replicas": ("m", "mean gap to the next floe per replica (last NaN)",
                          ("R", "N_f")),
    "S_sd_replicas": ("W m-2", "skin-drag dissipation per replica", ("R", "N_f")),
}

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


def column(name: str) -> Column:
    """The :class:`Column` called ``name``."""
    return _BY_NAME[name]

