"""Campaign files: grid expansion and counts, shipped configs, validation of bad input."""
import math
from pathlib import Path

import pytest

import floewave
from floewave import ModelConfig, solve_dispersion
from floewave.transient import transient_windows
from sweep import ConfigError, load_campaign, parse_campaign
from sweep.cli import main
from sweep.config import DEFAULT_EXPECTED_ITERATIONS, EXTRA_WINDOWS

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
MINIMAL = "[sweep]\neps = [0.2, 0.6]\n"


@pytest.fixture(scope="module")
def herman2019():
    """The paper's campaign, loaded (and so its 24,192 points expanded) once."""
    return load_campaign(CONFIGS / "herman2019.toml")


def test_herman2019_grid_is_24192_points(herman2019):
    c = herman2019
    assert c.size == 24192
    assert c.swept_fields == floewave.SWEPT_FIELDS
    # the grid's definition: a product of distinct values per dimension, three dispersions
    assert math.prod(len(v) for v in c.sweep.values()) == 24192
    assert all(len(set(v)) == len(v) for v in c.sweep.values())
    assert set(c.sweep["L_x"]) == {0.5, 1.5, 3.0}
    assert len(c.sweep["dispersion"]) == 3 and "ml" in c.sweep["dispersion"]
    # the expansion loading made (cached): as many points and hashes, none invalid
    points = c.points()
    assert len(points) == len({p.hash for p in points}) == 24192
    assert not any(p.invalid for p in points)


def test_herman2019_base_is_modelconfig_defaults(herman2019):
    assert herman2019.base == ModelConfig()


@pytest.mark.parametrize("name, n", [("demo", 16), ("fig2", 8), ("fig5", 6), ("fig6a", 8),
                                     ("fig6b", 8)])
def test_shipped_configs(name, n):
    import tomllib

    path = CONFIGS / f"{name}.toml"
    c = load_campaign(path)
    assert c.size == n == len(c.points())
    data = tomllib.loads(path.read_text())
    written = set(data["base"]) | set(data["sweep"])
    assert written == set(ModelConfig().to_dict()), "every parameter written out"


def test_fig2_values():
    c = load_campaign(CONFIGS / "fig2.toml")
    assert c.sweep["eps"] == (0.2, 0.4, 0.6, 0.8)
    assert set(c.sweep["dispersion"]) == {"ml", "ep"}
    assert (c.sweep["L_x"], c.sweep["T"], c.sweep["a0"], c.sweep["d_f"], c.sweep["C_sd"]) == (
        (0.5,), (1.2,), (0.0125,), (0.005,), (0.05,))


def test_grid_order_and_coercion():
    c = parse_campaign("[base]\nn0 = 2\n[sweep]\nT = [1, 2]\nL_x = [1, 0.5]\n")
    pts = c.points()
    assert [p.swept for p in pts] == [{"L_x": 1.0, "T": 1.0}, {"L_x": 1.0, "T": 2.0},
                                      {"L_x": 0.5, "T": 1.0}, {"L_x": 0.5, "T": 2.0}]
    assert all(isinstance(p.config.T, float) for p in pts)
    assert pts[0].config.n0 == 2
    # the stationary protocol's cost: the point's own minimum (transient + n_average) plus
    # the measured extra windows
    cfg = pts[0].config
    k, _ = solve_dispersion(cfg)
    expected = transient_windows(cfg, k) + cfg.n_average + EXTRA_WINDOWS
    assert c.expected_iterations(cfg) == expected
    assert pts[0].cost == cfg.floe_steps_of(expected)
    assert pts[0].cost < cfg.floe_steps_per_iteration() * expected
    # a low-drag point's transient is longer: it costs more
    slow = cfg.replace(C_sd=0.005)
    assert c.expected_iterations(slow) > expected
    # the noise_floor protocol, or a [run] value, as before
    assert c.expected_iterations(cfg.replace(protocol="noise_floor")) == \
        DEFAULT_EXPECTED_ITERATIONS


def test_invalid_points_inside_a_valid_grid_are_kept():
    c = parse_campaign("[base]\nh_i = 0.1\n[sweep]\nT = [0.6, 1.2]\ndispersion = ['ml', 'ep']\n")
    bad = [p for p in c.points() if p.invalid]
    assert len(bad) == 1 and bad[0].swept == {"T": 0.6, "dispersion": "ml"}
    assert "cutoff" in bad[0].invalid


def test_shard_partition():
    c = load_campaign(CONFIGS / "fig2.toml")
    shards = [c.shard(k, 3).points() for k in range(3)]
    hashes = [p.hash for s in shards for p in s]
    assert sorted(hashes) == sorted(p.hash for p in c.points())
    assert c.shard(0, 3).definition_hash() == c.definition_hash()


def test_shard_filters_the_expanded_grid_instead_of_expanding_it_again():
    import dataclasses

    c = parse_campaign("[base]\nh_i = 0.1\n[sweep]\nT = [0.6, 1.2, 1.8]\n"
                       "dispersion = ['ml', 'ep']\neps = [0.2, 0.4]\n")
    for k in range(3):
        shard = c.shard(k, 3)
        assert "_grid" in shard.__dict__  # the parent's grid, filtered
        fresh = dataclasses.replace(c, shard_of=(k, 3))  # expanded on its own
        assert "_grid" not in fresh.__dict__

        def key(points):
            return [(p.index, p.hash, p.swept, p.cost, p.invalid) for p in points]

        assert key(shard.points()) == key(fresh.points()) and shard.size == fresh.size
    assert sum(c.shard(k, 3).size for k in range(3)) == c.size == 12


BAD = [
    ("unknown_table", "[oops]\nx = 1\n" + MINIMAL, "oops"),
    ("unknown_base_key", "[base]\nL_xx = 1.0\n" + MINIMAL, "L_xx"),
    ("base_wrong_type", "[base]\nL_sheet = 'long'\n" + MINIMAL, "L_sheet"),
    ("base_negative_length", "[base]\nL_sheet = -42.0\n" + MINIMAL, "L_sheet"),
    ("base_zero_period", "[base]\nh = 0\n" + MINIMAL, "h"),
    ("base_bad_contact", "[base]\ncontact = 'glue'\n" + MINIMAL, "contact"),
    ("base_bool_type", "[base]\nconfined = 1\n" + MINIMAL, "confined"),
    ("base_int_type", "[base]\nn0 = 2.5\n" + MINIMAL, "n0"),
    ("base_rho", "[base]\nrho_i = 1100.0\n" + MINIMAL, "rho_i"),
    ("base_nu", "[base]\nnu = 0.7\n" + MINIMAL, "nu"),
    ("base_relax", "[base]\nrelax = 0.0\n" + MINIMAL, "relax"),
    ("base_nan", "[base]\nE = nan\n" + MINIMAL, "E"),
    ("base_not_table", "base = 3\n" + MINIMAL, "base"),
    ("missing_sweep", "[base]\nn0 = 1\n", "[sweep]"),
    ("sweep_unknown_dim", "[sweep]\nn0 = [1, 2]\n", "n0"),
    ("sweep_not_list", "[sweep]\neps = 0.5\n", "eps"),
    ("sweep_empty", "[sweep]\neps = []\n", "eps"),
    ("sweep_eps_zero", "[sweep]\neps = [0.0, 0.5]\n", "eps"),
    ("sweep_eps_above_one", "[sweep]\neps = [0.5, 1.5]\n", "eps"),
    ("sweep_negative_L_x", "[sweep]\nL_x = [-0.5]\n", "L_x"),
    ("sweep_zero_T", "[sweep]\nT = [0.0, 1.2]\n", "T"),
    ("sweep_bad_dispersion", "[sweep]\ndispersion = ['ml', 'xx']\n", "dispersion"),
    ("sweep_string_number", "[sweep]\na0 = ['0.01']\n", "a0"),
    ("sweep_duplicate", "[sweep]\nT = [1.2, 1.2]\n", "T"),
    ("sweep_duplicate_int_float", "[sweep]\nL_x = [3, 3.0]\n", "L_x"),
    ("T_over_dt_not_integral", "[sweep]\nT = [1.2, 1.23456]\n", "T = 1.23456"),
    ("L_x_over_dx_not_integral", "[sweep]\nL_x = [0.5, 0.555]\n", "L_x = 0.555"),
    ("ml_beyond_cutoff", "[base]\nh_i = 0.5\n[sweep]\nT = [0.8, 1.1]\ndispersion = ['ml']\n",
     "cutoff"),
    ("too_few_floes", "[sweep]\nL_x = [50.0, 0.5]\n", "L_x = 50.0"),
    ("run_unknown", MINIMAL + "[run]\nworkers = 4\n", "workers"),
    ("run_negative_grace", MINIMAL + "[run]\ngrace_period = -1\n", "grace_period"),
    ("run_name_type", MINIMAL + "[run]\nname = 3\n", "name"),
    ("run_zero_interval", MINIMAL + "[run]\nprogress_interval = 0\n", "progress_interval"),
    ("run_writer", MINIMAL + "[run]\nwriter = \"threads\"\n", "writer"),
    ("not_toml", "[sweep\neps = [0.2]\n", "TOML"),
    # issue *first hour* 2: a base value a [sweep] list silently replaced
    ("base_and_sweep", "[base]\neps = 0.5\n[sweep]\neps = [0.6]\n",
     "eps is set in both [base] (eps = 0.5) and [sweep] (eps = [0.6])"),
]


@pytest.mark.parametrize("label, text, key", BAD, ids=[b[0] for b in BAD])
def test_bad_config_exits_2_names_key_writes_nothing(tmp_path, capsys, label, text, key):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_campaign(cfg)
    assert key in str(info.value)
    store = tmp_path / "out.h5"
    status = main(["run", str(cfg), "--store", str(store), "--compute",
                   "sweep.testing:fake_point"])
    assert status == 2
    err = capsys.readouterr().err
    assert key in err and "sweep: error:" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_each_bad_value_gives_its_own_message():
    text = "[base]\nL_sheet = -1.0\nh = 'deep'\n[sweep]\neps = [0.5, 2.0]\nT = [-1.0]\n"
    with pytest.raises(ConfigError) as info:
        parse_campaign(text)
    msgs = info.value.messages
    assert len(msgs) == 4
    for key, value in [("L_sheet", "-1.0"), ("h", "'deep'"), ("eps", "2.0"), ("T", "-1.0")]:
        assert any(key in m and value in m for m in msgs), (key, msgs)


def test_field_messages_come_from_the_error_not_its_text():
    """The problem shown is floewave's ``problem`` for the field, whatever the value's repr
    holds (a string with a space or ': ' once cut the parsed message in the wrong place)."""
    text = "[base]\ndispersion = 'elastic plate'\nh = 'a: b'\n[sweep]\neps = [0.5]\n"
    with pytest.raises(ConfigError) as info:
        parse_campaign(text)
    assert info.value.messages == [
        "<string>: [base] dispersion = 'elastic plate': must be one of ('ep', 'ml', 'ow')",
        "<string>: [base] h = 'a: b': expected float"]
    # another field at fault: its whole message
    with pytest.raises(ConfigError) as info:
        parse_campaign("[base]\nrho_w = 800.0\n" + MINIMAL)
    assert info.value.messages == ["<string>: [base] rho_w = 800.0: ModelConfig.rho_i ="
                                   " 910.0 must not exceed rho_w (floes float)"]

def test_missing_file_and_bad_cli(run_main, tmp_path):
    assert main(["plan", str(tmp_path / "nope.toml"), "--rate", "1e7"]) == 2
    proc = run_main(main, ["run", CONFIGS / "demo.toml"])
    assert proc.returncode == 2 and "--store" in proc.stderr
    proc = run_main(main, ["run", CONFIGS / "demo.toml", "--store", tmp_path / "s.h5",
                           "--shard", "5/3"])
    assert proc.returncode == 2 and "shard" in proc.stderr
    assert not (tmp_path / "s.h5").exists()


def test_plan_writes_nothing(tmp_path, capsys, monkeypatch):
    """(The demo's 16 points: the paper grid's 24,192 are counted by
    test_herman2019_grid_is_24192_points, and planned by the docs walks, reduced.)"""
    monkeypatch.chdir(tmp_path)
    assert main(["plan", str(CONFIGS / "demo.toml"), "--rate", "3e7"]) == 0
    out = capsys.readouterr().out
    assert "16 points" in out and "core-hours" in out
    assert list(tmp_path.iterdir()) == []
