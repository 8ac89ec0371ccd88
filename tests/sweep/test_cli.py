"""sweep.cli and sweep.arguments: each error class gives its exit status with one line,
a bug gives 1 with its traceback, and the option types refuse bad values with a reason."""
from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

import floewave
from sweep import arguments
from sweep.cli import main
from sweep.errors import EXIT_CONFIG, EXIT_INTERNAL, EXIT_OK, EXIT_STORE
from sweep.store.schema import SCHEMA_VERSION

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"


def test_version_names_the_model_and_the_store_schema(run_main):
    r = run_main(main, ["--version"])
    assert r.returncode == EXIT_OK
    assert f"model version {floewave.MODEL_VERSION}" in r.stdout
    assert f"store schema {SCHEMA_VERSION}" in r.stdout


def test_python_m_sweep_is_the_command():
    r = subprocess.run([sys.executable, "-m", "sweep", "--version"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and "store schema" in r.stdout


@pytest.mark.parametrize("argv, why", [
    (["run", "c.toml", "--store", "s.h5", "--shard", "3/2"], "need 0 <= K < N"),
    (["run", "c.toml", "--store", "s.h5", "--point-timeout", "-1"], "0 to 3.2e7 seconds"),
    (["status", "s.h5", "--slowest", "x"], "expected an integer"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_arguments_exit_2_with_the_reason(run_main, tmp_path, argv, why):
    r = run_main(main, argv, cwd=tmp_path)
    assert r.returncode == EXIT_CONFIG and why in r.stderr


def test_store_problems_exit_3_in_one_line(run_main, tmp_path):
    (tmp_path / "not.h5").write_text("text, not HDF5")
    r = run_main(main, ["status", tmp_path / "not.h5"])
    assert r.returncode == EXIT_STORE and r.stderr.count("\n") == 1
    assert "not.h5" in r.stderr and "Traceback" not in r.stderr
    r = run_main(main, ["validate", tmp_path / "not.h5"])
    assert r.returncode == EXIT_STORE and "not a readable HDF5 file" in r.stdout + r.stderr


def test_a_bug_exits_1_with_its_traceback(run_main, tmp_path, monkeypatch):
    import sweep.analysis.status

    def broken(*args, **kwargs):
        raise RuntimeError("a bug in status")

    monkeypatch.setattr(sweep.analysis.status, "status_report", broken)
    r = run_main(main, ["status", tmp_path / "s.h5"])
    assert r.returncode == EXIT_INTERNAL
    assert "Traceback" in r.stderr and "RuntimeError: a bug in status" in r.stderr


def test_a_closed_pipe_is_not_an_error(run_main, tmp_path, monkeypatch):
    import sweep.analysis.status

    def closed(*args, **kwargs):
        raise BrokenPipeError

    monkeypatch.setattr(sweep.analysis.status, "status_report", closed)
    assert run_main(main, ["status", tmp_path / "s.h5"]).returncode == EXIT_OK


def test_run_then_status_json(run_main, tmp_path):
    import json

    (tmp_path / "c.toml").write_text(TOML)
    r = run_main(main, ["run", "c.toml", "--store", "s.h5", "--no-bar", "--compute",
                        "sweep.testing:raising_point"], cwd=tmp_path)
    assert r.returncode == EXIT_OK and "1 failed" in r.stdout + r.stderr
    rep = json.loads(run_main(main, ["status", "s.h5", "--json"], cwd=tmp_path).stdout)
    assert rep["stored"] == 2 and rep["counts"] == {"converged": 1, "failed": 1}
    assert rep["failures"][0]["swept"] == {"eps": 0.4}


def test_option_types():
    assert arguments.kind_list("fig2, fig3,") == ["fig2", "fig3"]
    assert arguments.shard("3/40") == (3, 40)
    assert arguments.seconds("0") == 0.0 and arguments.count("0") == 0
    assert arguments.positive_number("2.5") == 2.5
    for fn, text in ((arguments.shard, "40/40"), (arguments.shard, "a/b"),
                     (arguments.seconds, "4e7"), (arguments.positive_number, "0"),
                     (arguments.positive_number, "inf"), (arguments.count, "-1")):
        with pytest.raises(argparse.ArgumentTypeError):
            fn(text)
    assert arguments.plural(1, "point") == "1 point"
    assert arguments.plural(0, "point") == "0 points"
