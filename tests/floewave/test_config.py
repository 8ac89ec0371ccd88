"""ModelConfig: defaults, validation naming the field, exact round trip."""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from floewave import ConfigError, InvalidPointError, ModelConfig


def test_defaults_match_model_md():
    c = ModelConfig()
    assert (c.n_floes, c.n_t, c.n_x) == (84, 1200, 50)      # dt 1e-3 (the paper's: 1e-4)
    assert ModelConfig(dt=1e-4).n_t == 12000
    assert ModelConfig(L_x=1.5).n_floes == 28 and ModelConfig(L_x=3.0).n_floes == 14
    assert (c.h, c.L_y, c.h_i, c.rho_i, c.rho_w, c.E, c.nu, c.k_s) == (
        2.5, 10.0, 0.03, 910.0, 1000.0, 3e7, 0.3, 9e4)
    assert (c.nT, c.delta, c.dt, c.dx) == (5, 1e-3, 1e-3, 0.01)
    assert (c.protocol, c.coupling, c.stationarity) == ("stationary", "independent", "mser")
    assert c.contact == "hertz_disk" and c.damping == "liggghts" and not c.clip_attraction


@pytest.mark.parametrize("field,value", [
    ("L_x", 0.0), ("L_x", -1.0), ("T", 0), ("a0", -0.01), ("eps", 0.0), ("eps", 1.2),
    ("C_sd", -0.1), ("d_f", -0.001), ("dispersion", "xx"), ("contact", "hooke"),
    ("damping", "none"), ("nu", 0.5), ("relax", 0.0), ("relax", 1.5), ("nT", 0),
    ("max_iterations", 0), ("n0", -1), ("dt", 0.0), ("L_x", "0.5"), ("n0", 2.5),
    ("confined", 1), ("L_x", float("nan")), ("drag_integration", "simpson"),
    ("rho_i", 1100.0),
])
def test_bad_values_name_the_field(field, value):
    with pytest.raises(ConfigError, match=field):
        ModelConfig(**{field: value})


@pytest.mark.parametrize("field,value,problem", [
    ("eps", 1.2, "must be in (0, 1]"), ("dispersion", "a b", "must be one of ('ep', 'ml', 'ow')"),
    ("L_x", "0.5", "expected float"), ("L_x", float("inf"), "must be finite"),
    ("n0", 2.5, "expected int"), ("rho_i", 1100.0, "must not exceed rho_w (floes float)"),
])
def test_errors_carry_the_field_and_the_problem(field, value, problem):
    with pytest.raises(ConfigError) as info:
        ModelConfig(**{field: value})
    assert (info.value.field, info.value.problem) == (field, problem)
    assert str(info.value).startswith(f"ModelConfig.{field} = {value!r}")
    assert str(info.value).endswith(problem)


def test_errors_live_in_one_module_and_keep_their_old_homes():
    import pickle

    import floewave
    from floewave import config, dispersion, errors, model

    assert config.ConfigError is floewave.ConfigError is errors.ConfigError
    assert config.FloewaveError is errors.FloewaveError
    assert config.InvalidPointError is errors.InvalidPointError
    assert dispersion.DispersionError is floewave.DispersionError is errors.DispersionError
    assert model.NumericalError is floewave.NumericalError is errors.NumericalError
    assert issubclass(errors.DispersionError, errors.InvalidPointError)
    with pytest.raises(InvalidPointError) as info:
        ModelConfig(T=1.23456).check_physics()
    assert info.value.field == "T" and info.value.problem == str(info.value)
    assert errors.NumericalError("x").field is None
    again = pickle.loads(pickle.dumps(info.value))   # errors cross process boundaries
    assert (type(again), again.args, again.field) == (InvalidPointError, info.value.args, "T")


def test_unknown_field_rejected():
    with pytest.raises(ConfigError, match="'L_z'"):
        ModelConfig.from_dict({"L_z": 1.0})


def test_physically_invalid_points():
    with pytest.raises(InvalidPointError, match="T / dt"):
        ModelConfig(T=1.23456, dt=1e-3).check_physics()
    with pytest.raises(InvalidPointError, match="L_x / dx"):
        ModelConfig(L_x=0.505, dx=0.01).check_physics()
    with pytest.raises(InvalidPointError, match="floe"):
        ModelConfig(L_x=40.0).check_physics()
    ModelConfig().check_physics()


def test_int_and_float_are_the_same_value():
    assert ModelConfig(L_x=3, h=2) == ModelConfig(L_x=3.0, h=2.0)
    assert isinstance(ModelConfig(L_x=3).L_x, float)


@settings(max_examples=50, deadline=None)
@given(L_x=st.sampled_from([0.5, 1.5, 3.0]), T=st.floats(0.5, 3.0), a0=st.floats(1e-3, 0.1),
       eps=st.floats(0.01, 1.0), disp=st.sampled_from(["ep", "ml", "ow"]),
       confined=st.booleans())
def test_round_trip_is_exact(L_x, T, a0, eps, disp, confined):
    c = ModelConfig(L_x=L_x, T=T, a0=a0, eps=eps, dispersion=disp, confined=confined)
    d = c.to_dict()
    assert ModelConfig.from_dict(d) == c
    assert ModelConfig.from_dict(d).to_dict() == d


@pytest.mark.parametrize("name", ["n0", "nT", "n0_warm", "max_iterations", "noise_window",
                                  "n_average", "max_average"])
def test_counts_that_would_run_for_ever_are_refused(name):
    """[base] n0 = 1e30 used to pass validation and fail the point (issue 15)."""
    with pytest.raises(ConfigError, match=f"{name} = 10+ must be <= 1000000"):
        ModelConfig(**{name: 10**30})
    ModelConfig(**{"max_average": 0, name: 1_000_000, "n_average": 2})


def test_replace_validated_is_replace_without_revalidating():
    """The campaign grid sets already-validated swept values without validating every
    field again: the same config (equal, same dict) as replace; cross-field fields are
    refused; and it really skips validation (a value replace would refuse goes through,
    which is why only values validated by replace may be passed)."""
    import floewave
    from floewave import ModelConfig
    base = ModelConfig(C_sd=0.2)
    swept = dict(L_x=1.5, T=1.4, a0=0.02, C_sd=0.1, eps=0.4, d_f=0.01, dispersion="ep")
    assert set(swept) == set(floewave.SWEPT_FIELDS)
    fast, slow = base.replace_validated(**swept), base.replace(**swept)
    assert fast == slow and fast.to_dict() == slow.to_dict()
    with pytest.raises(floewave.ConfigError, match="cross-field"):
        base.replace_validated(rho_i=990.0)
    assert base.replace_validated(eps=5.0).eps == 5.0     # not validated: the caller's job
    with pytest.raises(floewave.ConfigError):
        base.replace(eps=5.0)
