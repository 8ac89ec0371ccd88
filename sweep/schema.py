"""The store's schema (version, datasets, attributes), its validator and migrations.

This module is the single source of the layout: the store writes it, the analysis
reads it, :func:`validate` checks a file against it, and
``results_schema/schema_v1.json`` is generated from it (:func:`schema_document`; a test
keeps the two identical). Layout of a store (one HDF5 file)::

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
from pathlib import Path
from typing import Any

import numpy as np

import floewave

from .identity import HASH_LENGTH

__all__ = ["SCHEMA_VERSION", "FORMAT", "Column", "COLUMNS", "DERIVED", "DERIVED_FROM",
           "PROFILE_VARS", "REPLICA_VARS",
           "MIGRATIONS",
           "STATUSES", "schema_document", "validate", "column", "profile_path"]

SCHEMA_VERSION = 3
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
                                    "alpha_exp_stderr", "a_end_stderr")}}
#: Fill value of a column added by a migration, where it differs from the column's fill
#: (every point stored before schema 3 ran one trajectory).
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


def _add_columns(f: Any, version: int) -> None:
    """Add the columns of schema ``version`` to an older store's table, with their fill
    values (:data:`MIGRATION_FILL` where given)."""
    table = f["table"]
    size = table["hash"].shape[0]
    for name in [c.name for c in COLUMNS if ADDED_IN.get(c.name, 1) == version]:
        if name in table:
            continue
        col = _BY_NAME[name]
        fill = MIGRATION_FILL.get(name, col.fill)
        if col.kind == "str":
            import h5py
            ds = table.create_dataset(name, shape=(size,), maxshape=(None,),
                                      chunks=table["hash"].chunks,
                                      dtype=h5py.string_dtype("utf-8"))
            ds[...] = [fill] * size
        else:
            ds = table.create_dataset(name, shape=(size,), maxshape=(None,),
                                      chunks=table["hash"].chunks,
                                      dtype={"float": "float64", "int": "int64"}[col.kind])
            ds[...] = fill


def _v1_to_v2(f: Any) -> None:
    """Add the compact-zone columns (fill values: their points keep the first-pair W_c
    rule of model version 2, which the empty ``compact_zone`` marks)."""
    _add_columns(f, 2)


def _v2_to_v3(f: Any) -> None:
    """Add the ensemble columns: replicas = 1 (every older point ran one trajectory),
    standard errors NaN, W_c_n -1 (unknown); no per-replica datasets."""
    _add_columns(f, 3)


#: Migrations: from-version -> (to-version, description, function(h5py.File)). A store
#: older than SCHEMA_VERSION is migrated step by step on open (by a writer; readers read
#: an old store as it is, missing columns as fill values).
MIGRATIONS: dict[int, tuple[int, str, Any]] = {
    1: (2, "add compact_zone, compact_end, ice_extent (model version 3's robust W_c); "
           "old points keep their values, compact_zone empty", _v1_to_v2),
    2: (3, "add the ensemble columns replicas (= 1 for old points), W_c_stderr, W_c_n "
           "(-1), alpha_*_stderr, a_end_stderr (NaN); old points have no per-replica "
           "datasets", _v2_to_v3),
}

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


def schema_document() -> dict[str, Any]:
    """The human-readable schema as a JSON-able dict (``results_schema/schema_v1.json``)."""
    return {
        "schema_version": SCHEMA_VERSION,
        "format": FORMAT,
        "layout": __doc__.split("Layout of a store (one HDF5 file)::", 1)[1].strip()
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
                   "(journal: sweep-journal, version 2, campaign_hash, campaign_json) first "
                   "and after each --extend, one line per stored point (row, profiles, "
                   "residual_history), fsynced before the HDF5 write, and hand-out/release "
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


def validate(path: str | Path) -> list[str]:
    """Check a store against this schema; returns the problems found (empty: valid).

    Checks the root attributes and version (an older version with a migration path is
    valid: readers read it as it is, a writer migrates it), that every column of its
    version exists, has the kind of
    its schema entry and at least ``n_rows`` values, that hashes are unique 64-hex
    strings and statuses known, and that every committed non-failed point has a profile
    group whose datasets have length ``n_floes``.
    """
    import h5py

    problems: list[str] = []
    try:
        f = h5py.File(path, "r", locking=False)
    except OSError as exc:
        from .reader import not_a_store

        return [f"{path}: not a readable HDF5 file: {not_a_store(path) or exc}"]
    with f:
        for key in ROOT_ATTRS:
            if key not in f.attrs:
                problems.append(f"/: missing attribute {key!r}")
        version = f.attrs.get("schema_version")
        try:
            version = SCHEMA_VERSION if version is None else int(version)
        except (TypeError, ValueError):
            return problems + [f"/: schema_version {version!r} is not a number"]
        if version > SCHEMA_VERSION:
            problems.append(f"/: schema_version {version} is newer than {SCHEMA_VERSION}")
        elif version < SCHEMA_VERSION and version not in MIGRATIONS:
            problems.append(f"/: schema_version {version} has no migration to"
                            f" {SCHEMA_VERSION}")
        if f.attrs.get("format") not in (FORMAT, FORMAT.encode()):
            problems.append(f"/: format {f.attrs.get('format')!r} != {FORMAT!r}")
        if "table" not in f:
            return problems + ["/table: missing"]
        n = int(f["table"].attrs.get("n_rows", -1))
        if n < 0:
            problems.append("/table: missing attribute 'n_rows'")
        for col in COLUMNS:
            if col.name not in f["table"]:
                if ADDED_IN.get(col.name, 1) > version:
                    continue        # an older (readable, migratable) store lacks it
                problems.append(f"/table/{col.name}: missing")
                continue
            ds = f["table"][col.name]
            kind = ds.dtype.kind
            ok = {"float": kind == "f", "int": kind in "iu", "str": kind in "OSU"}[col.kind]
            if not ok:
                problems.append(f"/table/{col.name}: dtype {ds.dtype} is not {col.kind}")
            if ds.shape[0] < n:
                problems.append(f"/table/{col.name}: {ds.shape[0]} values < n_rows {n}")
        if problems:
            return problems
        from . import reader

        table = f["table"]
        swept_names = tuple(floewave.SWEPT_FIELDS)
        cols = reader.table_columns(f, ("hash", "status", "config_json", "provenance",
                                        *swept_names), n)
        hashes, status = list(cols["hash"]), list(cols["status"])
        n_floes = table["n_floes"][:n]
        replicas = table["replicas"][:n] if "replicas" in table else None
        if len(set(hashes)) != len(hashes):
            problems.append("/table/hash: duplicate hashes")
        if "campaign_json" in f.attrs:
            well_formed = [(i, h, cj, prov) for i, (h, cj, prov) in enumerate(zip(
                hashes, cols["config_json"], cols["provenance"], strict=True))
                if len(h) == HASH_LENGTH and set(h) <= set("0123456789abcdef")]
            rows = [w[0] for w in well_formed]
            for k, h in reader.hash_mismatches([w[1] for w in well_formed],
                                               [w[2] for w in well_formed],
                                               reader.model_version(f),
                                               [w[3] for w in well_formed],
                                               {c: [cols[c][r] for r in rows]
                                                for c in swept_names if c in cols}):
                problems.append(f"/table/config_json[{well_formed[k][0]}]: does not hash"
                                f" to its hash {h}, or the row's swept columns differ from"
                                " it (the row was altered after it was written)")
        for i, (h, s) in enumerate(zip(hashes, status, strict=False)):
            if len(h) != HASH_LENGTH or any(c not in "0123456789abcdef" for c in h):
                problems.append(f"/table/hash[{i}]: {h!r} is not a {HASH_LENGTH}-character"
                                " hex hash")
                continue
            if s not in STATUSES:
                problems.append(f"/table/status[{i}]: unknown status {s!r}")
            if s in ("failed", "invalid", "crashed", "timeout"):
                continue
            name = profile_path(h)
            if name not in f:
                problems.append(f"/{name}: missing profile group of a {s} point")
                continue
            for var in PROFILE_VARS:
                if var not in f[name]:
                    problems.append(f"/{name}/{var}: missing")
                elif f[name][var].shape != (int(n_floes[i]),):
                    problems.append(f"/{name}/{var}: shape {f[name][var].shape} != "
                                    f"({int(n_floes[i])},)")
            if HISTORY_VAR[0] not in f[name]:
                problems.append(f"/{name}/{HISTORY_VAR[0]}: missing")
            R = int(replicas[i]) if replicas is not None else -1
            for var, (_, _, shape) in REPLICA_VARS.items():
                if var not in f[name]:
                    continue        # optional: points stored before schema 3
                want = tuple({"R": R, "N_f": int(n_floes[i])}[d] for d in shape)
                if f[name][var].shape != want:
                    problems.append(f"/{name}/{var}: shape {f[name][var].shape} != {want}")
    return problems


def write_schema_file(directory: str | Path) -> Path:
    """Write ``schema_v<N>.json`` into ``directory`` (used to regenerate results_schema/)."""
    path = Path(directory) / f"schema_v{SCHEMA_VERSION}.json"
    path.write_text(json.dumps(schema_document(), indent=2) + "\n", encoding="utf-8")
    return path
