"""sweep.provenance: what the provenance column and the /runs attributes record."""
from __future__ import annotations

import json
import os
import re
import socket
import subprocess

import pytest

import floewave
from sweep import provenance
from sweep.provenance import environment, git_state, host


def test_host_is_the_host_name():
    assert host() == socket.gethostname()


def test_environment_without_git_and_mpi():
    env = environment(with_git=False, with_mpi=False)
    assert "git_commit" not in env and "git_dirty" not in env
    assert env["pid"] == os.getpid() and env["host"] == host()
    assert env["model_version"] == floewave.MODEL_VERSION
    assert env["floewave_version"] == env["sweep_version"] == floewave.__version__
    assert env["mpi_library"] == "not used"
    import numpy
    assert env["numpy"] == numpy.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", env["python"])
    assert json.loads(json.dumps(env, sort_keys=True)) == env  # the provenance column


def test_versions_of_missing_modules():
    assert provenance._version("no_such_module_for_sweep") == "not installed"
    assert provenance._version("string") == "unknown"  # no __version__


def test_git_state_of_this_checkout():
    root = os.path.dirname(os.path.dirname(floewave.__file__))
    try:
        head = subprocess.run(["git", "-C", root, "rev-parse", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("floewave is not in a git checkout here")
    commit, dirty = git_state()
    assert commit == head and isinstance(dirty, bool)
    env = environment()
    assert env["git_commit"] == head and env["git_dirty"] == dirty


def test_git_state_outside_a_checkout(tmp_path, monkeypatch):
    fake = tmp_path / "site" / "floewave" / "__init__.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("")
    monkeypatch.setattr(floewave, "__file__", str(fake))
    git_state.cache_clear()
    try:
        assert git_state() == ("unknown", None)
        assert environment()["git_dirty"] == "unknown"
    finally:
        git_state.cache_clear()
