"""The public ``sweep`` namespace: every name of ``sweep.__all__`` and every part listed by
``dir(sweep)`` resolves from its new home, lazily (``import sweep`` stays light)."""
from __future__ import annotations

import subprocess
import sys

import sweep


def test_every_public_name_resolves():
    for name in sweep.__all__:
        assert getattr(sweep, name) is not None, name
    assert sweep.run_campaign.__module__ == "sweep.run.launch"
    assert sweep.load.__module__ == "sweep.analysis.load"
    assert sweep.validate.__module__ == "sweep.store.validate"
    assert sweep.collision_stats.__module__ == "sweep.analysis.stats"


def test_every_listed_part_imports():
    for name in dir(sweep):
        if not name.startswith("_"):
            assert getattr(sweep, name) is not None, name


def test_import_sweep_loads_neither_the_store_nor_h5py():
    code = ("import sys, sweep; bad = [m for m in ('h5py', 'sweep.store.store',"
            " 'sweep.run.launch', 'numba') if m in sys.modules]; print(bad)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout.strip()
    assert out == "[]"


def test_the_worker_side_does_not_load_the_store():
    """issue 24: the MPI worker imported the store (and h5py) for a time stamp."""
    code = ("import sys, sweep.run.worker; print([m for m in ('h5py', 'sweep.store.store')"
            " if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout.strip()
    assert out == "[]"
