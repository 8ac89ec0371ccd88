"""Migrations of the store's layout: each older schema version brought up to the current one.

:data:`MIGRATIONS` maps a version to the next (with a description and the function that
changes an open ``h5py.File``); :func:`migration_steps` is the one walk from a version to
:data:`~sweep.store.schema.SCHEMA_VERSION` (checked before anything changes), and
:func:`migrate` applies it.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import h5py

from sweep.errors import SchemaVersionError
from sweep.store.cells import texts
from sweep.store.schema import (
    ADDED_IN,
    COLUMNS,
    FROM_CONFIG,
    MIGRATION_FILL,
    SCHEMA_VERSION,
    column,
    config_values,
)

__all__ = ["MIGRATIONS", "migration_steps", "migrate", "add_columns", "added_in"]


def added_in(version: int) -> list[str]:
    """The columns that schema ``version`` added, in the table's order."""
    return [c.name for c in COLUMNS if ADDED_IN.get(c.name, 1) == version]


def add_columns(f: Any, version: int) -> None:
    """Add the columns of schema ``version`` to an older store's table, with their fill
    values (:data:`MIGRATION_FILL` where given; a :data:`FROM_CONFIG` column: each row's
    value in its ``config_json``)."""
    table = f["table"]
    size = table["hash"].shape[0]
    for name in added_in(version):
        if name in table:
            continue
        col = column(name)
        fill = MIGRATION_FILL.get(name, col.fill)
        if col.kind == "str":
            ds = table.create_dataset(name, shape=(size,), maxshape=(None,),
                                      chunks=table["hash"].chunks,
                                      dtype=h5py.string_dtype("utf-8"))
            ds[...] = [fill] * size
        else:
            ds = table.create_dataset(name, shape=(size,), maxshape=(None,),
                                      chunks=table["hash"].chunks,
                                      dtype={"float": "float64", "int": "int64"}[col.kind])
            ds[...] = fill
        if name in FROM_CONFIG and size:
            ds[...] = config_values(name, texts(table["config_json"][:size]))


def _v1_to_v2(f: Any) -> None:
    """Add the compact-zone columns (fill values: their points keep the first-pair W_c
    rule of model version 2, which the empty ``compact_zone`` marks)."""
    add_columns(f, 2)


def _v2_to_v3(f: Any) -> None:
    """Add the ensemble columns: replicas = 1 (every older point ran one trajectory),
    standard errors NaN, W_c_n -1 (unknown); no per-replica datasets."""
    add_columns(f, 3)


def _v3_to_v4(f: Any) -> None:
    """Add the columns of schema 4 (:func:`added_in`: the W_c rule on the time-mean gaps
    and the collision statistics) with their standard errors: NaN for old points (not
    recomputed; their per-replica datasets hold the gaps, not the collisions)."""
    add_columns(f, 4)


def _v4_to_v5(f: Any) -> None:
    """Add the ``seed`` column (a swept dimension since schema 5), each row's seed read
    from its ``config_json`` (rows beyond ``n_rows``, and rows without one: -1)."""
    add_columns(f, 5)


#: Migrations: from-version -> (to-version, description, function(h5py.File)). A store
#: older than SCHEMA_VERSION is migrated step by step on open (by a writer; readers read
#: an old store as it is, missing columns as fill values).
MIGRATIONS: dict[int, tuple[int, str, Any]] = {
    1: (2, "add compact_zone, compact_end, ice_extent (model version 3's robust W_c); "
           "old points keep their values, compact_zone empty", _v1_to_v2),
    2: (3, "add the ensemble columns replicas (= 1 for old points), W_c_stderr, W_c_n "
           "(-1), alpha_*_stderr, a_end_stderr (NaN); old points have no per-replica "
           "datasets", _v2_to_v3),
    3: (4, f"add {', '.join(n for n in added_in(4) if not n.endswith('_stderr'))} and"
           " their *_stderr (NaN for old points)", _v3_to_v4),
    4: (5, "add seed (the ensemble seed, a dimension a campaign may sweep), each row's"
           " from its config_json", _v4_to_v5),
}


def migration_steps(version: int) -> list[tuple[int, str, Callable[[Any], None]]]:
    """The migrations from schema ``version`` to the current one, in order (empty if current).

    Raises :class:`SchemaVersionError` if ``version`` is newer than this sweep's, or if
    there is no migration path from it (the message names both versions).
    """
    if version > SCHEMA_VERSION:
        raise SchemaVersionError(f"store schema version {version} is newer than this sweep's"
                                 f" schema version {SCHEMA_VERSION}; upgrade sweep to use it")
    steps = []
    while version < SCHEMA_VERSION:
        if version not in MIGRATIONS:
            raise SchemaVersionError(f"no migration from schema version {version} to"
                                     f" {SCHEMA_VERSION}")
        steps.append(MIGRATIONS[version])
        version = MIGRATIONS[version][0]
    return steps


def migrate(f: Any) -> None:
    """Bring the open, writable store ``f`` (an ``h5py.File``) to the current schema, one
    flushed step at a time (raises :class:`SchemaVersionError` before any change if there
    is no path)."""
    for version, _, step in migration_steps(int(f.attrs.get("schema_version", 0))):
        step(f)
        f.attrs["schema_version"] = version
        f.flush()
