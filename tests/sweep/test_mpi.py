"""Real mpiexec runs (the mpich wheel's launcher): tiny campaigns with run_point and fakes."""
import contextlib
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

import sweep
import sweep.cli
from sweep.testing import TINY_TOML, find_mpiexec
from tests.sweep.helpers import table

MPIEXEC = find_mpiexec()
pytestmark = pytest.mark.skipif(MPIEXEC is None, reason="no mpiexec (pip install mpich)")

FAKE_TOML = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.5]
eps = [0.2, 0.4, 0.6, 0.8]
dispersion = ["ml", "ep"]
d_f = [0.005, 0.01]
[run]
progress_interval = 1.0
grace_period = 5.0
"""


def _env(**extra):
    env = dict(os.environ)
    env.pop("SLURM_NTASKS", None)
    env.update(extra)
    return env


def mpirun(n, *args, env=None, timeout=120):
    cmd = [MPIEXEC, "-n", str(n), sys.executable, "-m", "sweep", *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          env=env or _env())


@pytest.fixture
def inproc(run_main, monkeypatch):
    """``inproc(*args, **env)``: ``sweep *args`` without a launcher, run in this process
    (a singleton: what runs it in a process of its own is the launcher's business)."""
    def call(*args, **env):
        monkeypatch.delenv("SLURM_NTASKS", raising=False)
        for name, value in env.items():
            monkeypatch.setenv(name, value)
        return run_main(sweep.cli.main, args)

    return call


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY_TOML)
    return path


def test_mpiexec_3_real_points_equal_one_rank(tmp_path, tiny, inproc):
    mpi_store, one_store = tmp_path / "mpi.h5", tmp_path / "one.h5"
    proc = mpirun(3, "run", tiny, "--store", mpi_store)
    assert proc.returncode == 0, proc.stderr
    proc1 = inproc("run", tiny, "--store", one_store)
    assert proc1.returncode == 0, proc1.stderr

    df = sweep.load(mpi_store)
    assert len(df) == 8 and df["hash"].is_unique
    assert set(df["rank"]) == {1, 2}, "ranks 1 and 2 computed, rank 0 only stored"
    assert set(df["status"]) <= {"converged", "converged_noisy", "not_converged"}
    ds = sweep.load_xarray(mpi_store)
    assert dict(ds.sizes) == {"L_x": 2, "eps": 2, "dispersion": 2}
    assert np.isfinite(ds["alpha_all"]).all()
    # a 3 m sheet is too short for a sustained compact zone: no W_c, said so
    assert set(df["compact_zone"]) == {"none"} and df["W_c"].isna().all()
    assert sweep.validate(mpi_store) == []
    prov = __import__("json").loads(df["provenance"][0])
    assert prov["mpi_library"].startswith("MPICH")

    one = sweep.load(one_store).set_index("hash").sort_index()
    mpi = df.set_index("hash").sort_index()
    assert list(one.index) == list(mpi.index)
    for col in ("W_c", "alpha_all", "alpha_c", "a_end", "residual", "iterations", "noise",
                "floe_steps", "status"):
        assert list(one[col].astype(str)) == list(mpi[col].astype(str)), col
    for h in one.index:
        a1 = sweep.load_profile(one_store, h)
        a3 = sweep.load_profile(mpi_store, h)
        for var in ("a", "x_mean", "S_sd", "gap_mean", "residual_history"):
            np.testing.assert_array_equal(a1[var].values, a3[var].values)

    again = mpirun(2, "run", tiny, "--store", mpi_store)  # nothing to hand out: ends at once
    assert again.returncode == 0, again.stderr
    assert "8 already stored, 0 stored now" in again.stdout
    after = sweep.load(mpi_store)
    assert list(after["seq"]) == list(df["seq"])


@pytest.mark.slow  # fast: test_store_process.py::test_writer_stores_what_the_inline_master_stores
# (the same table from both writers) and test_mpiexec_3_real_points_equal_one_rank (the
# writer process under mpiexec)
def test_writer_process_and_inline_master_store_the_same(tmp_path):
    """``[run] writer = "process"`` (the default under MPI) and ``"inline"``: the same
    stored table; the summary names the writer's CPU only when there is one; a store
    begun by one is resumed by the other."""
    stores = {}
    for writer in ("process", "inline"):
        cfg = tmp_path / f"{writer}.toml"
        cfg.write_text(FAKE_TOML + f'writer = "{writer}"\n')
        stores[writer] = tmp_path / f"{writer}.h5"
        proc = mpirun(3, "run", cfg, "--store", stores[writer], "--compute",
                      "sweep.testing:fake_point", "--no-bar")
        assert proc.returncode == 0, proc.stderr
        assert "32 stored now" in proc.stdout
        assert ("its store writer" in proc.stdout) == (writer == "process"), proc.stdout
        assert sweep.validate(stores[writer]) == []
    pd.testing.assert_frame_equal(table(stores["process"]).drop(columns="rank"),
                                  table(stores["inline"]).drop(columns="rank"))
    assert set(sweep.load(stores["process"])["rank"]) <= {1, 2}

    cfg = tmp_path / "more.toml"  # a larger grid resumed by the other writer
    cfg.write_text(FAKE_TOML.replace("[0.5, 1.5]", "[0.5, 1.0, 1.5]") + 'writer = "inline"\n')
    proc = mpirun(3, "run", cfg, "--store", stores["process"], "--extend", "--compute",
                  "sweep.testing:fake_point", "--no-bar")
    assert proc.returncode == 0, proc.stderr
    assert "32 already stored, 16 stored now" in proc.stdout
    df = sweep.load(stores["process"])
    assert len(df) == 48 and df["hash"].is_unique


@pytest.mark.slow  # fast: test_store_safety.py::test_compute_faults_are_failed_points
def test_mpiexec_raising_points_recorded(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML)
    store = tmp_path / "s.h5"
    proc = mpirun(3, "run", cfg, "--store", store, "--compute", "sweep.testing:raising_point")
    assert proc.returncode == 0, proc.stderr
    df = sweep.load(store)
    assert len(df) == 32
    failed = df[df["status"] == "failed"]
    assert len(failed) == 8 and set(failed["eps"]) == {0.4}
    assert all(f"rank {r}" in m for r, m in zip(failed["rank"], failed["message"], strict=False))
    assert set(failed["rank"]) <= {1, 2}


def test_slurm_ntasks_mismatch_refused(tmp_path, tiny, inproc):
    store = tmp_path / "s.h5"
    proc = mpirun(2, "run", tiny, "--store", store, env=_env(SLURM_NTASKS="4"))
    assert proc.returncode == 4
    assert "SLURM_NTASKS=4" in proc.stderr
    assert not store.exists()
    proc = inproc("run", tiny, "--store", store, SLURM_NTASKS="3")
    assert proc.returncode == 4 and "singletons" in proc.stderr
    assert not store.exists()


@pytest.mark.slow  # fast: test_worker.py::test_rank_0_that_cannot_read_the_campaign_stops_its_workers
def test_a_campaign_rank_0_cannot_read_ends_the_job(tmp_path):
    """Only rank 0 reads the campaign; when it cannot, it stops the workers (which wait
    for its first word): the job ends at once with status 2 and one message."""
    t0 = time.monotonic()
    proc = mpirun(3, "run", tmp_path / "absent.toml", "--store", tmp_path / "s.h5",
                  timeout=60)
    assert proc.returncode == 2 and time.monotonic() - t0 < 30
    assert proc.stderr.count("cannot read campaign file") == 1, proc.stderr
    assert not (tmp_path / "s.h5").exists()


@pytest.mark.slow  # fast: test_grace_expiry_aborts_but_store_consistent (SIGTERM to an
# mpiexec run) and test_store_safety.py's stops and resumes in-process (SIGUSR1 among them)
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGUSR1])
def test_signal_stops_cleanly_and_resumes(tmp_path, sig):
    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML)
    store = tmp_path / "s.h5"
    cmd = [MPIEXEC, "-n", "3", sys.executable, "-m", "sweep", "run", str(cfg), "--store",
           str(store), "--compute", "sweep.testing:sleepy_point"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=_env())
    deadline = time.monotonic() + 60
    journal = tmp_path / "s.h5.journal"
    while time.monotonic() < deadline:  # wait for the first stored points
        time.sleep(0.2)
        # a point record, not only the campaign line the journal starts with at open
        # (a signal before the first hand-out stops the run with nothing stored)
        if store.exists() and journal.exists() and b'{"row":' in journal.read_bytes():
            break
    p.send_signal(sig)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 6, err
    assert "resumable" in err
    assert not (tmp_path / "s.h5.lock").exists()
    first = sweep.load(store)
    assert 0 < len(first) < 32
    assert sweep.validate(store) == []
    proc = mpirun(2, "run", cfg, "--store", store, "--compute", "sweep.testing:fake_point")
    assert proc.returncode == 0, proc.stderr
    df = sweep.load(store)
    assert len(df) == 32 and df["hash"].is_unique
    kept = df.set_index("hash").loc[first["hash"], "seq"]
    assert list(kept) == list(first["seq"]), "points stored before the stop were kept"


@pytest.mark.slow  # fast: test_store_process.py::test_a_stopped_writer_cannot_make_the_master_deaf
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGUSR1])
def test_a_stopped_writer_does_not_make_the_run_deaf(tmp_path, sig, inproc):
    """The store's writer process stopped (SIGSTOP: a hung NFS/Lustre write), then a stop
    signal to mpiexec: the run ends within the grace period (the stuck writer killed and
    said so), exit status 6, resumable; the resume completes the campaign."""
    import json

    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML.replace("grace_period = 5.0", "grace_period = 2.0"))
    store = tmp_path / "s.h5"
    cmd = [MPIEXEC, "-n", "3", sys.executable, "-m", "sweep", "run", str(cfg), "--store",
           str(store), "--compute", "sweep.testing:sleepy_point", "--no-bar"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=_env())
    journal = tmp_path / "s.h5.journal"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # the first points stored
        time.sleep(0.2)
        if journal.exists() and b'{"row":' in journal.read_bytes():
            break
    writer = json.loads((tmp_path / "s.h5.lock").read_text())["pid"]  # the lock's holder
    os.kill(writer, signal.SIGSTOP)
    try:
        time.sleep(0.5)
        t0 = time.monotonic()
        p.send_signal(sig)
        out, err = p.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        p.kill()
        with contextlib.suppress(ProcessLookupError):
            os.kill(writer, signal.SIGKILL)
            os.kill(writer, signal.SIGCONT)
    assert p.returncode == 6, err
    assert took < 2.0 + 5, (took, err)
    assert "did not answer within the grace period" in err and "resumable" in err, err
    proc = inproc("run", cfg, "--store", store, "--compute", "sweep.testing:fake_point")
    assert proc.returncode == 0, proc.stderr
    assert len(sweep.load(store)) == 32 and sweep.validate(store) == []


def test_grace_expiry_aborts_but_store_consistent(tmp_path, inproc):
    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML.replace("grace_period = 5.0", "grace_period = 0.0"))
    store = tmp_path / "s.h5"
    cmd = [MPIEXEC, "-n", "3", sys.executable, "-m", "sweep", "run", str(cfg), "--store",
           str(store), "--compute", "sweep.testing:sleepy_point"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=_env())
    journal = tmp_path / "s.h5.journal"
    deadline = time.monotonic() + 60  # the master has its store (not a stop at start-up)
    while time.monotonic() < deadline and not (journal.exists() and journal.stat().st_size):
        time.sleep(0.2)
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=60)
    assert p.returncode != 0
    assert "resumable" in err
    assert sweep.validate(store) == []
    n = len(sweep.load(store))
    proc = inproc("run", cfg, "--store", store, "--compute", "sweep.testing:fake_point")
    assert proc.returncode == 0, proc.stderr
    assert f"{n} already stored" in proc.stdout
    assert len(sweep.load(store)) == 32


_RANK0_FAILS = """
import errno, sys
import sweep.cli, sweep.run.launch
from mpi4py import MPI
if MPI.COMM_WORLD.Get_rank() == 0 and sys.argv[1] == "open":
    class Broken:
        def __init__(self, *a, **k):
            raise RuntimeError("Unable to get group info (addr overflow)")  # as h5py
    sweep.run.launch.Store = Broken
if MPI.COMM_WORLD.Get_rank() == 0 and sys.argv[1] == "full":
    import sweep.store.journal
    real = sweep.store.journal.Journal.append
    calls = []
    def append(self, lines, sync=True):  # the disk fills up at the third point commit
        calls.append(sync and any(b'"row"' in line for line in lines))
        if sum(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, lines, sync)
    sweep.store.journal.Journal.append = append
sys.exit(sweep.cli.main(sys.argv[2:]))
"""


@pytest.mark.parametrize("how", ["open", pytest.param("full", marks=pytest.mark.slow)])
# "full": slow tier (fast: "open"; a full disk in test_store_holes.py and test_store.py)
def test_any_master_failure_ends_the_job(tmp_path, how):
    """Rank 0 failing with something else than a SweepError (opening the store), or a
    full disk while workers are busy: the job ends within seconds, nothing hangs."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML)
    store = tmp_path / "s.h5"
    cmd = [MPIEXEC, "-n", "3", sys.executable, "-c", _RANK0_FAILS, how, "run", str(cfg),
           "--store", str(store), "--compute", "sweep.testing:sleepy_point", "--no-bar"]
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=90, env=_env())
    assert time.monotonic() - t0 < 60
    assert proc.returncode != 0
    if how == "open":
        assert "addr overflow" in proc.stderr
    else:
        assert "no space left on the device" in proc.stderr
        assert "Traceback" not in proc.stderr
        assert sweep.validate(store) == []
        done = len(sweep.load(store))
        again = mpirun(3, "run", cfg, "--store", store, "--compute", "sweep.testing:fake_point")
        assert again.returncode == 0, again.stderr
        assert f"{done} already stored" in again.stdout and len(sweep.load(store)) == 32


@pytest.mark.slow  # fast: test_store_safety.py::test_point_timeout_records_timeout
def test_mpi_point_timeout(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(FAKE_TOML.replace("[0.2, 0.4, 0.6, 0.8]", "[0.2, 0.4]").replace(
        "d_f = [0.005, 0.01]", "d_f = [0.005]"))
    store = tmp_path / "s.h5"
    proc = mpirun(3, "run", cfg, "--store", store, "--compute", "sweep.testing:stuck_point",
                  "--point-timeout", "1", timeout=90)
    assert proc.returncode == 0, proc.stderr
    df = sweep.load(store)
    assert len(df) == 8
    assert set(df[df["eps"] == 0.4]["status"]) == {"timeout"}
    assert set(df[df["eps"] == 0.2]["status"]) == {"converged"}
