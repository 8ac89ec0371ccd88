"""The store schema covers everything floewave's PointResult reports (no silent drift)."""
from floewave.results import PROFILE_FIELDS, SCALAR_FIELDS
from floewave.results import STATUSES as MODEL_STATUSES
from sweep.store.schema import COLUMNS, PROFILE_VARS, STATUSES


def test_every_profile_is_stored():
    assert set(PROFILE_VARS) == set(PROFILE_FIELDS)


def test_every_scalar_result_has_a_column():
    names = {c.name for c in COLUMNS}
    assert [f for f in SCALAR_FIELDS if f not in names] == []


def test_model_statuses_are_store_statuses():
    assert set(MODEL_STATUSES) <= set(STATUSES)
    assert {"failed", "invalid"} <= set(STATUSES)
