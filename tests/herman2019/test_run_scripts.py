"""results/herman2019/run_shard.sh and run_grid.sh refuse bad input with exit status 2 and
one message, before running anything (a shard runs for many minutes: these are checked
without running one)."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHARD = ROOT / "results" / "herman2019" / "run_shard.sh"
GRID = ROOT / "results" / "herman2019" / "run_grid.sh"


def _run(script, *args, **env):
    return subprocess.run(["bash", str(script), *args], capture_output=True, text=True,
                          env={**os.environ, **env}, timeout=60)


def test_run_shard_refuses_a_bad_shard_and_a_missing_config(tmp_path):
    r = _run(SHARD, "3", "2", STORES=str(tmp_path))
    assert r.returncode == 2 and "K = 3 is not below N = 2" in r.stderr
    r = _run(SHARD, "x", "2", STORES=str(tmp_path))
    assert r.returncode == 2 and "give K and N" in r.stderr
    r = _run(SHARD, "0", "2", STORES=str(tmp_path), CONFIG="configs/nope.toml")
    assert r.returncode == 2 and "CONFIG configs/nope.toml: no such file" in r.stderr
    assert not any(tmp_path.iterdir())          # nothing written


def test_run_grid_refuses_a_bad_n_deadline_or_shard(tmp_path):
    r = _run(GRID, "x", "tomorrow", "0", LOGS=str(tmp_path))
    assert r.returncode == 2 and "N must be a positive integer" in r.stderr
    r = _run(GRID, "16", "not a date", "0", LOGS=str(tmp_path))
    assert r.returncode == 2 and "is not a date" in r.stderr
    r = _run(GRID, "16", "tomorrow", "16", LOGS=str(tmp_path))
    assert r.returncode == 2 and "shard 16 is not below N = 16" in r.stderr
    assert not any(tmp_path.iterdir())
