"""The store schema covers everything floewave's PointResult reports (no silent drift)."""
from floewave.results import PROFILE_FIELDS, SCALAR_FIELDS
from floewave.results import STATUSES as MODEL_STATUSES
from sweep.store.schema import COLUMNS, PROFILE_VARS, STATUSES, column


def test_every_profile_is_stored():
    assert set(PROFILE_VARS) == set(PROFILE_FIELDS)


def test_every_scalar_result_has_a_column():
    names = {c.name for c in COLUMNS}
    assert [f for f in SCALAR_FIELDS if f not in names] == []


def test_model_statuses_are_store_statuses():
    assert set(MODEL_STATUSES) <= set(STATUSES)
    assert {"failed", "invalid"} <= set(STATUSES)


def test_the_table_is_sweeps_own_columns_around_the_declared_outputs():
    """The store's columns are sweep's own (identity, swept parameters, status, where and
    when) around floewave's declared outputs, in the declaration's order: sweep names none
    of the model's columns."""
    from floewave.outputs import table_outputs
    from sweep.store.schema import OWN_HEAD, OWN_TAIL, RESULT_COLUMNS

    declared = table_outputs()
    assert COLUMNS == (*OWN_HEAD, *[column(str(o.column)) for o in declared], *OWN_TAIL)
    for o in declared:
        c = column(str(o.column))
        assert (c.kind, c.units, c.long_name) == (o.kind, o.unit, o.long_name)
        assert RESULT_COLUMNS[o.name] == c.name


def test_profile_datasets_are_the_declared_arrays():
    from floewave.outputs import history, profiles, replica_outputs
    from sweep.store.schema import HISTORY_VAR, REPLICA_VARS

    assert PROFILE_VARS == {o.name: (o.unit, o.long_name) for o in profiles()}
    assert REPLICA_VARS == {o.name: (o.unit, o.long_name, o.dims) for o in replica_outputs()}
    assert HISTORY_VAR == (history().name, history().unit, history().long_name)


#: The table of schema version 1 (frozen: a column not in it needs the schema version that
#: added it, ADDED_IN, and a migration).
SCHEMA_1 = ("hash", "L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion", "status",
            "message", "n_floes", "W_c", "alpha_all", "alpha_all_resid", "alpha_edge",
            "alpha_edge_resid", "alpha_inner", "alpha_inner_resid", "alpha_exp",
            "alpha_exp_resid", "alpha_c", "k", "c_g", "noise", "iterations", "residual",
            "floe_steps", "kernel_mode", "a_end", "model_wall_time", "host", "rank", "pid",
            "start_time", "end_time", "wall_time", "run", "seq", "config_json", "provenance")


def test_every_column_after_schema_1_names_the_version_that_added_it():
    from sweep.store.migrate import MIGRATIONS
    from sweep.store.schema import ADDED_IN, SCHEMA_VERSION

    new = [c.name for c in COLUMNS if c.name not in SCHEMA_1]
    assert [n for n in new if n not in ADDED_IN] == [], (
        "a new column needs the schema version that added it in sweep.store.schema.ADDED_IN"
        " (and SCHEMA_VERSION, MIGRATIONS)")
    assert not set(SCHEMA_1) & set(ADDED_IN)
    assert set(ADDED_IN.values()) <= set(range(2, SCHEMA_VERSION + 1)) <= {
        v for _, (v, _, _) in MIGRATIONS.items()}
