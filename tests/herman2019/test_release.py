"""The released grid (issue 47): results/herman2019 holds every one of the 24,192 points
once, each with its profiles, run from one commit — the release's — with a clean tree on
every run, at one model version; loadable with sweep.load and sweep.load_profiles."""
from __future__ import annotations

import itertools
import json
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

import sweep

ROOT = Path(__file__).resolve().parents[2]
GRID = ROOT / "results" / "herman2019"


@pytest.fixture(scope="module")
def table():
    return sweep.load(GRID)


def test_every_point_of_the_grid_once(table):
    spec = tomllib.loads((ROOT / "configs" / "herman2019.toml").read_text())["sweep"]
    assert len(table) == 24192 == len(set(table["hash"]))
    have = set(zip(*(table[k].astype(str) if k == "dispersion" else table[k].astype(float)
                     for k in spec), strict=True))
    want = {tuple(str(v) if k == "dispersion" else float(v) for k, v in zip(spec, c,
                                                                             strict=True))
            for c in itertools.product(*spec.values())}
    assert have == want
    assert set(table["status"].astype(str)) <= {"converged", "converged_noisy", "not_converged"}


def test_one_commit_the_release_s_a_clean_tree_and_one_model_version():
    prov = json.loads((GRID / "provenance.json").read_text())
    assert len(prov["shards"]) == 16
    runs = [r for s in prov["shards"].values() for r in s["runs"]]
    commits = {r["git_commit"] for r in runs}
    assert len(commits) == 1 and all(r["git_dirty"] is False for r in runs)
    assert {r["model_version"] for r in runs} == {"9"}
    (commit,) = commits
    # the commit is the release's: its pyproject says version 1.0.0
    shown = subprocess.run(["git", "show", f"{commit}:pyproject.toml"], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout
    assert tomllib.loads(shown)["project"]["version"] == "1.0.0"


def test_every_point_has_its_profiles(table):
    prof = sweep.load_profiles(GRID)
    assert prof.sizes["point"] == len(table)
    assert set(prof["hash"].values.astype(str)) == set(table["hash"])
    n = prof["n_floes"].values
    a = prof["a_rel"].values
    first = a[:, 0]
    assert np.all(np.isfinite(first)) and np.all(n >= 2)
    total = sum((GRID / "profiles" / f).stat().st_size
                for f in (p.name for p in (GRID / "profiles").glob("*.nc")))
    assert total <= 40e6       # "a compact file ... (<= ~40 MB in all)"
