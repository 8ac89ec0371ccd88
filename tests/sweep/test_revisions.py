"""sweep.revisions: a git revision exported; two stores compared bit for bit (h5py only)."""
from __future__ import annotations

import shutil
import subprocess

import h5py
import numpy as np
import pytest

from sweep.revisions import REPOSITORY, RUN_SPECIFIC, compare_stores, export_revision

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\nL_x = [0.5, 1.5]\n"


def test_a_store_equals_itself_and_its_copy(power_store, tmp_path):
    store = power_store(TOML)
    copy = tmp_path / "copy.h5"
    shutil.copy(store, copy)
    problems, summary = compare_stores(store, copy)
    assert problems == [] and summary.endswith("EQUAL")
    assert summary.startswith("4 rows,")


def test_a_changed_bit_a_column_or_a_profile_is_a_difference(power_store, tmp_path):
    store = power_store(TOML)
    changed = tmp_path / "changed.h5"
    shutil.copy(store, changed)
    with h5py.File(changed, "r+") as f:
        w = f["table"]["W_c"]
        w[0] = np.nextafter(w[0], np.inf)              # one ulp: a difference
        f["table"]["wall_time"][0] += 1.0              # run-specific: not one
        group = f["profiles"][next(iter(f["profiles"]))]
        point = group[next(iter(group))]
        name = next(iter(point))
        point[name][...] = -point[name][()]
    problems, summary = compare_stores(store, changed)
    assert "column differs: W_c" in problems
    assert not any("wall_time" in p for p in problems) and "wall_time" in RUN_SPECIFIC
    assert any(p.startswith("profile differs") and p.endswith(name) for p in problems)
    assert summary.endswith(f"{len(problems)} DIFFERENCES")


@pytest.mark.skipif(not (REPOSITORY / ".git").exists(), reason="not a git checkout")
def test_export_revision_writes_the_committed_files(tmp_path):
    head = subprocess.run(["git", "-C", str(REPOSITORY), "show", "HEAD:sweep/__init__.py"],
                          capture_output=True, check=True).stdout
    tree = export_revision("HEAD", tmp_path / "tree", ("sweep/__init__.py",))
    assert (tree / "sweep" / "__init__.py").read_bytes() == head


def test_a_column_of_a_later_schema_is_named_not_a_difference(power_store, tmp_path):
    """A store of an older schema (here: schema 4, without ``seed``) against this one: the
    columns added since are named in the summary; any other difference still counts."""
    from sweep.revisions import columns_added_since

    store = power_store(TOML)
    old = tmp_path / "old.h5"
    shutil.copy(store, old)
    with h5py.File(old, "r+") as f:
        del f["table"]["seed"]
        f.attrs["schema_version"] = 4
    assert "seed" in columns_added_since(old)
    assert compare_stores(old, store)[0] == ["columns differ: ['seed']"]
    problems, summary = compare_stores(old, store, columns_added_since(old))
    assert problems == [] and "later schema: seed" in summary and summary.endswith("EQUAL")
    with h5py.File(old, "r+") as f:
        f["table"]["W_c"][0] = f["table"]["W_c"][0] + 1.0
    assert compare_stores(old, store, columns_added_since(old))[0] == ["column differs: W_c"]
