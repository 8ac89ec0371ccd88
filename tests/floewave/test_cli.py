"""``floewave run``: summary, JSON and plot output, bad input -> exit 2 with one message.

``floewave.cli.main`` runs in-process (the ``run_main`` fixture); the entry points themselves
(``python -m floewave``/``sweep``) by a subprocess in the help test and
tests/sweep/test_cli.py::test_python_m_sweep_is_the_command."""
import json
import subprocess
import sys

import pytest

from floewave.cli import main

FAST = ["--set", "L_x=3.0", "--set", "n0=1", "--set", "nT=1", "--set", "max_iterations=3"]


@pytest.fixture
def run(run_main):
    """``run(args, cwd)``: ``floewave run ARGS`` in ``cwd``."""
    return lambda args, cwd: run_main(main, ["run", *args], cwd)


def test_run_prints_summary_and_writes_json_and_plot(run, tmp_path):
    pytest.importorskip("matplotlib")
    p = run(FAST + ["--json", "out.json", "--plot", "out.png"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert "iterations" in p.stdout and "W_c" in p.stdout and "floe-steps/s" in p.stdout
    data = json.loads((tmp_path / "out.json").read_text())
    assert data["config"]["L_x"] == 3.0
    assert len(data["result"]["a"]) == 14
    assert (tmp_path / "out.png").stat().st_size > 1000


@pytest.mark.parametrize("args,needle", [
    (["--set", "L_x=-1"], "L_x"),
    (["--set", "eps=1.5"], "eps"),
    (["--set", "bogus=1"], "bogus"),
    (["--set", "n0=two"], "n0"),
    (["--set", "dispersion=ml", "--set", "h_i=0.5"], "cutoff"),
    (["--set", "T=1.23456", "--set", "dt=0.001"], "T / dt"),
    (["--set", "confined=maybe"], "confined"),
    (["--set", "noequals"], "NAME=VALUE"),
    # a trace of a confined point is refused before the point runs, not after it
    (["--set", "confined=true", "--set", "d_f=0", "--trace", "1"], "confined point"),
])
def test_bad_input_exits_2_and_writes_nothing(run, tmp_path, args, needle):
    p = run(args + ["--json", "out.json"], tmp_path)
    assert p.returncode == 2
    assert needle in p.stderr
    assert p.stderr.count("error:") == 1
    assert not (tmp_path / "out.json").exists()


@pytest.mark.parametrize("option", ["--json", "--plot"])
def test_unwritable_output_is_refused_before_the_point_runs(run, tmp_path, option):
    """Issue *first hour* 1: the point is not computed and then lost to a bad path."""
    p = run(FAST + [option, "nodir/out.x"], tmp_path)
    assert p.returncode == 2, p.stderr
    assert f"{option} nodir/out.x: directory" in p.stderr and "does not exist" in p.stderr
    assert p.stderr.count("error:") == 1 and "Traceback" not in p.stderr
    assert "iteration" not in p.stderr and p.stdout == ""  # nothing ran


def test_run_help_lists_every_field_with_default_and_units(run_main):
    """Issue *first hour* 5: the list is read from ModelConfig (a new field appears)."""
    from dataclasses import fields

    from floewave import ModelConfig

    p = run_main(main, ["run", "--help"])
    assert p.returncode == 0
    for f in fields(ModelConfig):
        assert f"\n  {f.name} = " in p.stdout, f.name
    assert "L_x = 0.5 [m] (float)" in p.stdout and "floe length" in p.stdout
    assert "rho_w = 1000.0 [kg m^-3]" in p.stdout
    assert "compact_min_length = 3.0 [m]" in p.stdout and "compact_min_pairs = 3 [-]" in p.stdout
    assert "exit statuses: 0 success" in p.stdout


def test_top_level_help_is_plain_text_and_versions_exist(run_main):
    top = subprocess.run([sys.executable, "-m", "floewave", "--help"], capture_output=True,
                         text=True, timeout=60)
    assert top.returncode == 0 and "``" not in top.stdout
    # the versions in this process (``python -m sweep --version`` in a process of its own:
    # tests/sweep/test_cli.py::test_python_m_sweep_is_the_command)
    import sweep.cli

    for prog, prog_main in (("floewave", main), ("sweep", sweep.cli.main)):
        v = run_main(prog_main, ["--version"])
        assert v.returncode == 0 and "model version" in v.stdout, (prog, v.stderr)


def test_unknown_field_suggests_the_near_one(run, tmp_path):
    p = run(["--set", "epsilon=0.5"], tmp_path)
    assert p.returncode == 2
    assert "unknown field 'epsilon' (did you mean 'eps'?)" in p.stderr
    assert "L_x, T, a0" in p.stderr


def test_run_says_it_compiles_first_and_its_rate_excludes_the_compilation(run, tmp_path,
                                                                          monkeypatch):
    """Issue 25: a word before the (silent) compilation, and a floe-steps/s of the point
    alone. The warm-up is made to take 0.5 s here (the point takes about 0.01 s): none of it
    may reach the point's wall time or rate."""
    import re
    import time

    import floewave.cli as cli

    real = cli.warm_up

    def slow_warm_up(cfg):
        time.sleep(0.5)
        return real(cfg) + 0.5

    monkeypatch.setattr(cli, "warm_up", slow_warm_up)
    p = run(FAST + ["--json", "out.json"], tmp_path)
    assert p.returncode == 0, p.stderr
    lines = p.stderr.splitlines()
    assert lines[0].startswith("floewave: compiling the numba kernels")
    assert re.match(r"floewave: kernels ready in \d+\.\d s", lines[1])
    assert "iteration" in lines[2]                   # the point's progress comes after
    result = json.loads((tmp_path / "out.json").read_text())["result"]
    assert result["wall_time"] < 0.5
    rate = float(re.search(r"([0-9.]+) M floe-steps/s", p.stdout).group(1))
    assert rate == pytest.approx(result["floe_steps"] / result["wall_time"] / 1e6, abs=0.051)
    assert "not included" in p.stdout


@pytest.mark.parametrize("sets", [{}, {"confined": True}, {"drag_integration": "exact"},
                                  {"replicas": 4, "L_sheet": 30.0}])
def test_the_warm_up_point_uses_the_points_kernels(sets):
    from floewave import ModelConfig
    from floewave.cli import warm_up_config
    from floewave.model import kernel_mode

    cfg = ModelConfig(**sets)
    small = warm_up_config(cfg)
    assert kernel_mode(small) == kernel_mode(cfg)
    assert small.n_floes <= 4 and small.max_iterations == 1 and small.replicas == 1
