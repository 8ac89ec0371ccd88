"""floewave.outputs: the one declaration of a point's outputs, and what is built from it."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from floewave import outputs
from floewave.outputs import OUTPUTS, W_C_RULES, Output
from floewave.results import (
    PROFILE_FIELDS,
    REPLICA_FIELDS,
    SCALAR_FIELDS,
    PointResult,
    point_result_type,
)


def test_every_output_is_declared_whole():
    names = [o.name for o in OUTPUTS]
    assert len(names) == len(set(names))
    dims = {(), outputs.PER_FLOE, outputs.PER_PAIR, outputs.PER_REPLICA,
            outputs.PER_REPLICA_FLOE, outputs.HISTORY}
    for o in OUTPUTS:
        assert o.kind in ("float", "int", "str") and o.dims in dims, o
        assert o.long_name and (o.unit or o.kind == "str"), o
        assert (o.column is None) == bool(o.dims) or o.name == "status", o
        if o.dims:
            assert o.kind == "float", o


def test_point_result_is_built_from_the_declaration():
    fields = [f.name for f in dataclasses.fields(PointResult)]
    assert [n for n in fields if n != "a0"] == [o.name for o in OUTPUTS]
    assert set(fields) == {*PROFILE_FIELDS, *SCALAR_FIELDS, *REPLICA_FIELDS,
                           "residual_history", "a0"}
    for o in OUTPUTS:
        f = next(f for f in dataclasses.fields(PointResult) if f.name == o.name)
        assert f.type == ("np.ndarray" if o.dims else o.kind)
        assert f"{o.name} [" in PointResult.__doc__


def test_the_w_c_rules_are_asked_of_the_declaration():
    assert W_C_RULES[0].name == "W_c" and len(W_C_RULES) >= 2
    for o in W_C_RULES:
        assert o.unit == "m" and not o.dims and o.rule


def test_adding_an_output_is_one_declaration():
    """One more Output: the result type gets the field, the store the column in its place."""
    from sweep.store.schema import OWN_HEAD, OWN_TAIL, model_columns

    extra = Output("floe_spin", "float", "rad s-1", "mean floe spin rate", default=np.nan)
    declared = (*OUTPUTS[:12], extra, *OUTPUTS[12:])
    cls = point_result_type(declared, "Extended")
    assert "floe_spin" in [f.name for f in dataclasses.fields(cls)]
    cols = model_columns(declared)
    assert [c.name for c in cols] == [str(o.column) for o in outputs.table_outputs(declared)]
    spin = next(c for c in cols if c.name == "floe_spin")
    assert (spin.kind, spin.units, spin.long_name) == ("float", "rad s-1",
                                                     "mean floe spin rate")
    assert not {c.name for c in (*OWN_HEAD, *OWN_TAIL)} & {c.name for c in cols}


def test_an_output_of_an_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="kind"):
        Output("x", "complex", "1", "x")
