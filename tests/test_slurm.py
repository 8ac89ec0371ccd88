"""The shipped batch scripts (``slurm/*.sbatch``) under a real single-node Slurm (issue 16).

Each test submits the script itself with ``sbatch`` on a small real campaign (16 points of
~0.1-0.4 s; :data:`CAMPAIGN`), then looks at what Slurm reports (``scontrol show job``:
state, restarts, exit code) and at the store: every point once, the same values as an
uninterrupted run (the first test's job; ``compare`` of the torture test).

The daemons are started by the session fixture :func:`slurm` (tests/slurm_cluster.py) and
need Debian's ``slurm-wlm`` and ``munge`` and root. Without them these tests skip; with
``FLOEWAVE_REQUIRE_SLURM=1`` (set by ``.ci/run``, which installs both) a missing or
unstartable Slurm is a failure. They are the slow tier; to run them here: ``apt-get install
slurm-wlm munge`` as root, then ``FLOEWAVE_REQUIRE_SLURM=1 python -m pytest -m slow
tests/test_slurm.py``. The fast tier runs the scripts without Slurm
(:func:`test_scripts_run_outside_slurm`).

Slurm holds a requeued job for about two minutes (BeginTime); the tests start it at once
(:meth:`SlurmCluster.release`). With ``pytest -s`` (and at the end of any run) each
scenario prints what Slurm reported.
"""
from __future__ import annotations

import os
import pwd
import shutil
import subprocess
import sys
import time
from datetime import datetime
from pathlib import Path

import h5py
import pytest

import sweep
from sweep.store.journal import journal_path
from sweep.store.reader import read_journal
from sweep.testing import SMALL_REAL_BASE
from tests.slurm_cluster import SlurmCluster, SlurmError, missing_programs
from tests.sweep.test_torture import compare

ROOT = Path(__file__).resolve().parents[1]
MPI_SCRIPT = ROOT / "slurm" / "sweep_mpi.sbatch"
ARRAY_SCRIPT = ROOT / "slurm" / "sweep_array.sbatch"
REQUIRE = os.environ.get("FLOEWAVE_REQUIRE_SLURM", "") not in ("", "0")
#: 16 real points of ~0.1-0.4 s (4 or 8 floes of a 24 m sheet, as in the torture test):
#: ~3 s of computing under 3 ranks on 2 cores, after a start-up of 3-6 s.
# dt = 1e-4 (the paper's): points of about the duration these tests were timed with; at
# model version 6's 1e-3 the 16 points could all finish between the first stored point and
# a scancel (seen once in .ci/run: 16 of 16 stored)
CAMPAIGN = SMALL_REAL_BASE + """dt = 0.0001
[sweep]
L_x = [3.0, 1.5]
T = [1.2, 1.6]
eps = [0.2, 0.6]
dispersion = ["ml", "ep"]

[run]
name = "slurm-test"
progress_interval = 1.0
grace_period = 5.0
"""
N_POINTS = 16
RANKS = "3"
HOW_TO = ("apt-get install slurm-wlm munge (as root), then set FLOEWAVE_REQUIRE_SLURM=1"
          " (.ci/run does both)")

_report: list[str] = []


@pytest.fixture(scope="session")
def slurm():
    """A running single-node Slurm for the session (skips outside CI when unavailable)."""
    missing = missing_programs()
    problem = None
    if missing:
        problem = f"Slurm not installed (missing {', '.join(missing)})"
    elif os.geteuid() != 0:
        problem = "the Slurm daemons of these tests need root"
    if problem:
        if REQUIRE:
            pytest.fail(f"FLOEWAVE_REQUIRE_SLURM is set but {problem}")
        pytest.skip(f"{problem}: {HOW_TO}")
    cluster = SlurmCluster()
    try:
        cluster.start()
    except SlurmError as exc:
        cluster.stop()
        pytest.fail(f"Slurm did not start: {exc}")
    yield cluster
    cluster.stop()
    shutil.rmtree(cluster.dir, ignore_errors=True)


@pytest.fixture(autouse=True)
def _summary(request):
    """Each scenario's line goes to the end of the run's output (tests/conftest.py's
    ``pytest_terminal_summary``; also from a ``pytest -n`` worker)."""
    n = len(_report)
    yield
    request.node.user_properties += [("summary", f"slurm: {line}") for line in _report[n:]]


def says(rec: dict[str, str]) -> str:
    """What Slurm reports of a job (or array task)."""
    return f"JobState={rec['JobState']} Restarts={rec['Restarts']} ExitCode={rec['ExitCode']}"


def report(scenario: str, slurm_says: str, store: Path, extra: str = "") -> None:
    """One line per scenario, printed at the end of the session (and with ``-s``)."""
    points = len(sweep.load(store)) if store.exists() else 0
    line = f"{scenario}: {slurm_says}; store points={points}" + (f"; {extra}" if extra else "")
    _report.append(line)
    print(line)


@pytest.fixture(scope="session")
def campaign(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("slurm-campaign") / "c.toml"
    path.write_text(CAMPAIGN)
    return path


def job_env(slurm: SlurmCluster, **changes: str | None) -> dict[str, str]:
    """Job environment: USER set as a login shell sets it; NUMBA_CACHE_DIR left to the
    script (its default, /tmp/numba-cache-$USER, is shared by the jobs)."""
    user = pwd.getpwuid(os.getuid()).pw_name
    return slurm.env(**{"USER": user, "NUMBA_CACHE_DIR": None, **changes})


def submit_mpi(slurm, campaign, store: Path, env=None, ntasks: str = RANKS) -> str:
    return slurm.sbatch(f"--ntasks={ntasks}", f"--output={store.parent}/job-%j.log",
                        str(MPI_SCRIPT), str(campaign), str(store), env=env or job_env(slurm))


#: What the scripts print once their stop signals are trapped.
TRAPPED = "stop signals are trapped"


def log_of(store: Path, job: str) -> str:
    path = store.parent / f"job-{job}.log"
    return path.read_text(errors="replace") if path.exists() else "(no log)"


def journal_lines(store: Path) -> int:
    """Point records in the store's journal (not its campaign line or hand-outs)."""
    path = journal_path(store)
    return sum(1 for _ in read_journal(path)) if path.exists() else 0


def wait_for(pred, timeout: float, what: str, poll: float = 0.02) -> None:
    deadline = time.monotonic() + timeout
    while not pred():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout:g} s")
        time.sleep(poll)


def same_as(reference: Path, store: Path) -> dict:
    res = compare(reference, store)
    assert not res["problems"], "\n".join(res["problems"][:20])
    assert res["points"] == N_POINTS and res["compared"] == N_POINTS
    assert res["dup_table"] == 0 and res["dup_journal"] == 0
    return res


def hold_seconds(rec: dict[str, str]) -> float:
    """How long after its (re)submission a pending job may start (EligibleTime)."""
    t = {k: datetime.fromisoformat(rec[k]) for k in ("SubmitTime", "EligibleTime")}
    return (t["EligibleTime"] - t["SubmitTime"]).total_seconds()


def runs_of(store: Path) -> dict[str, int]:
    """Per hash: the index of the ``sweep run`` that stored it (the table's run column)."""
    df = sweep.load(store)
    return dict(zip(df["hash"], df["run"].astype(int), strict=True))


def completed_array(slurm: SlurmCluster, job: str, tasks: int, logs) -> list[dict[str, str]]:
    """The records of array ``job``'s tasks, asserted to be ``tasks`` that all completed
    with status 0 (else the tasks' ``logs`` are shown)."""
    recs = slurm.jobs(job)
    text = "\n".join(p.read_text() for p in sorted(logs))
    assert len(recs) == tasks, recs
    assert all((r["JobState"], r["ExitCode"]) == ("COMPLETED", "0:0") for r in recs), text
    return recs


def merge_shards(parts: list[Path], tmp_path: Path, reference, recs, scenario: str) -> None:
    """Every shard store holds points, together the campaign's; ``sweep merge`` of them
    equals the uninterrupted reference."""
    sizes = [len(sweep.load(p)) for p in parts]
    assert sum(sizes) == N_POINTS and all(s > 0 for s in sizes), sizes
    merged = tmp_path / "merged.h5"
    proc = subprocess.run([sys.executable, "-m", "sweep", "merge", str(merged),
                           *map(str, parts)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    report(scenario, ", ".join(f"task {r['ArrayTaskId']}: {says(r)}" for r in recs), merged,
           f"shard sizes {sizes}")
    same_as(reference[0], merged)


# --------------------------------------------------------------------------- scenarios
@pytest.fixture(scope="session")
def reference(slurm, campaign, tmp_path_factory) -> tuple[Path, str]:
    """The MPI script, USER set, run to completion: the uninterrupted reference."""
    store = tmp_path_factory.mktemp("slurm-reference") / "ref.h5"
    job = submit_mpi(slurm, campaign, store)
    try:
        slurm.wait(job, timeout=240)  # the first job may compile the numba kernels
    finally:
        slurm.cancel_quietly(job)
    return store, job


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_mpi_script_runs_a_campaign(slurm, reference):
    store, job = reference
    rec = slurm.job(job)
    log = log_of(store, job)
    report("MPI script, USER set", says(rec), store)
    assert (rec["JobState"], rec["ExitCode"], rec["Restarts"]) == ("COMPLETED", "0:0", "0"), log
    assert f"{N_POINTS} grid points: 0 already stored, {N_POINTS} stored now" in log, log
    df = sweep.load(store)
    assert len(df) == N_POINTS and df["hash"].is_unique
    assert set(df["rank"]) == {1, 2}, "the points were not computed by two worker ranks"
    assert sweep.validate(store) == []


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_mpi_script_without_user(slurm, campaign, reference, tmp_path):
    """Submitted from an environment without USER (cron, service accounts)."""
    env = job_env(slurm, USER=None)
    probe = slurm.sbatch("--ntasks=1", f"--output={tmp_path}/probe.log", "--wrap",
                         'echo "USER=${USER-<unset>}"', env=env)
    store = tmp_path / "nouser.h5"
    job = submit_mpi(slurm, campaign, store, env=env)
    try:
        slurm.wait(probe, timeout=60)
        rec = slurm.wait(job, timeout=120)
    finally:
        slurm.cancel_quietly(job)
    assert (tmp_path / "probe.log").read_text().strip() == "USER=<unset>", \
        "the job environment had USER: this test proves nothing"
    log = log_of(store, job)
    report("MPI script, no USER", says(rec), store)
    assert "unbound variable" not in log, log
    assert (rec["JobState"], rec["ExitCode"]) == ("COMPLETED", "0:0"), log
    same_as(reference[0], store)


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_mpi_script_with_the_wheels_mpiexec(slurm, campaign, reference, tmp_path):
    """LAUNCHER=mpiexec: the mpich wheel's Hydra, which starts its proxies with srun (so
    the ranks must be handed the job's SLURM_NTASKS, or sweep refuses the launch)."""
    store = tmp_path / "hydra.h5"
    job = submit_mpi(slurm, campaign, store, env=job_env(slurm, LAUNCHER="mpiexec"))
    try:
        rec = slurm.wait(job, timeout=120)
    finally:
        slurm.cancel_quietly(job)
    log = log_of(store, job)
    report("MPI script, LAUNCHER=mpiexec", says(rec), store)
    assert (rec["JobState"], rec["ExitCode"]) == ("COMPLETED", "0:0"), log
    same_as(reference[0], store)
    assert set(sweep.load(store)["rank"]) == {1, 2}


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_time_limit_signal_stops_requeues_and_resumes(slurm, campaign, reference, tmp_path):
    """What --signal=B:USR1@300 sends: clean stop (6), requeue, resume; nothing recomputed."""
    store = tmp_path / "usr1.h5"
    job = submit_mpi(slurm, campaign, store)
    try:
        wait_for(lambda: journal_lines(store) >= 1, 120, "no point stored")
        slurm.run("scancel", "--signal=USR1", "--batch", job)
        rec1 = slurm.wait(job, "PENDING", timeout=60, restarts=1)
        log = log_of(store, job)
        assert "Exited with exit code 6" in log and "exit status 6; requeueing" in log, log
        first = runs_of(store)
        assert 0 < len(first) < N_POINTS, f"{len(first)} points stored before the stop"
        assert set(first.values()) == {0}
        hold = hold_seconds(rec1)  # Slurm's hold of a requeued job (docs/cluster.md)
        assert hold >= 60, rec1
        slurm.release(job)
        rec = slurm.wait(job, timeout=120)
    finally:
        slurm.cancel_quietly(job)
    log = log_of(store, job)
    report("time-limit signal (USR1) -> requeue -> resume", says(rec), store,
           f"stopped after {len(first)} points; requeue hold {hold:.0f} s;"
           f" runs: {slurm.history(job)}")
    assert (rec["JobState"], rec["ExitCode"], rec["Restarts"]) == ("COMPLETED", "0:0", "1"), log
    assert (f"{N_POINTS} grid points: {len(first)} already stored,"
            f" {N_POINTS - len(first)} stored now") in log, log
    same_as(reference[0], store)
    after = runs_of(store)
    assert {h: after[h] for h in first} == first, "a point stored before the stop was redone"
    assert set(after.values()) == {0, 1}


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_scancel_cancels_and_does_not_requeue(slurm, campaign, tmp_path):
    store = tmp_path / "cancel.h5"
    job = submit_mpi(slurm, campaign, store)
    try:
        wait_for(lambda: journal_lines(store) >= 1, 120, "no point stored")
        slurm.run("scancel", job)
        rec = slurm.wait(job, {"CANCELLED", "COMPLETED", "FAILED", "PENDING", "REQUEUED"},
                         timeout=60)
        time.sleep(1)  # (the batch script has ended: a requeue by it would show)
        rec = slurm.job(job)
    finally:
        slurm.cancel_quietly(job)
    log = log_of(store, job)
    report("scancel", says(rec), store)
    assert (rec["JobState"], rec["Restarts"]) == ("CANCELLED", "0"), log
    assert "requeueing" not in log, log
    n = len(sweep.load(store))
    assert 0 < n < N_POINTS
    assert sweep.validate(store) == []


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_array_script_and_merge(slurm, campaign, reference, tmp_path):
    shards = tmp_path / "shards"
    job = slurm.sbatch("--array=0-3", f"--output={tmp_path}/shard-%A_%a.log",
                       str(ARRAY_SCRIPT), str(campaign), str(shards), env=job_env(slurm))
    try:
        slurm.wait(job, timeout=180)
    finally:
        slurm.cancel_quietly(job)
    recs = completed_array(slurm, job, 4, tmp_path.glob("shard-*.log"))
    parts = sorted(shards.glob("c-*.h5"))
    assert [p.name for p in parts] == [f"c-{k}.h5" for k in range(4)]
    merge_shards(parts, tmp_path, reference, recs, "array script (4 tasks) + sweep merge")


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_mpi_script_sharded_array_and_merge(slurm, campaign, reference, tmp_path):
    """SHARDS=2 with a job array of 2: one MPI job per shard, each its own master and
    store (STORE-sKof2.h5), merged into the reference's points (docs/cluster.md "Past
    one master")."""
    store = tmp_path / "c.h5"
    job = slurm.sbatch("--array=0-1", f"--ntasks={RANKS}", f"--output={tmp_path}/job-%A_%a.log",
                       str(MPI_SCRIPT), str(campaign), str(store),
                       env=job_env(slurm, SHARDS="2"))
    try:
        slurm.wait(job, timeout=240)
    finally:
        slurm.cancel_quietly(job)
    recs = completed_array(slurm, job, 2, tmp_path.glob("job-*.log"))
    parts = [tmp_path / f"c-s{k}of2.h5" for k in range(2)]
    for p in parts:  # each shard computed by its own workers under its own master
        assert set(sweep.load(p)["rank"]) <= {1, 2}
    merge_shards(parts, tmp_path, reference, recs,
                 "MPI script sharded (SHARDS=2, 2 array tasks) + sweep merge")


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_array_task_time_limit_signal_during_startup(slurm, campaign, reference, tmp_path):
    """The time-limit signal to an array task still starting (one shard: the whole grid):
    held back until ``sweep run`` listens, then a clean stop, that task requeued, resumed."""
    shards = tmp_path / "shards"
    job = slurm.sbatch("--array=0", f"--output={tmp_path}/shard-%A_%a.log", str(ARRAY_SCRIPT),
                       str(campaign), str(shards), env=job_env(slurm, SHARDS="1"))
    task = f"{job}_0"
    store = shards / "c-0.h5"
    try:
        # the script traps the signal from its first lines on; before that the batch
        # shell dies of it (exit 0:10, JobLaunchFailure) -- not a time-limit case
        log_path = tmp_path / f"shard-{job}_0.log"
        wait_for(lambda: log_path.exists() and TRAPPED in log_path.read_text(errors="replace"),
                 120, "the task's script did not start")
        slurm.run("scancel", "--signal=USR1", "--batch", task)
        slurm.wait(task, "PENDING", timeout=90, restarts=1)
        first = runs_of(store)
        assert 0 < len(first) < N_POINTS, f"{len(first)} points stored before the stop"
        slurm.release(task)
        rec = slurm.wait(task, timeout=90)
    finally:
        slurm.cancel_quietly(job)
    log = (tmp_path / f"shard-{job}_0.log").read_text()
    report("array task, USR1 during start-up -> requeue -> resume", says(rec), store,
           f"stopped after {len(first)} points")
    assert "exit status 6; requeueing task" in log, log
    assert (rec["JobState"], rec["ExitCode"], rec["Restarts"]) == ("COMPLETED", "0:0", "1"), log
    same_as(reference[0], store)
    after = runs_of(store)
    assert {h: after[h] for h in first} == first, "a point stored before the stop was redone"


@pytest.mark.slow  # a real Slurm (fast: test_scripts_run_outside_slurm)
def test_node_failure_then_time_limit_signal_during_startup(slurm, campaign, reference,
                                                           tmp_path):
    """The job step killed with SIGKILL (as by a node failure), the job requeued, and the
    time-limit signal during the resumed job's start-up, as soon as its script runs (its
    master then starts up and rebuilds the store the killed run left open, from the
    journal). The signal is
    held back until the master listens; the store must end complete and as the reference.
    (The requeued run needs a step id of its own: step 0's MPICH shared memory, left in
    /dev/shm by the SIGKILL, hung MPI_Init.)"""
    store = tmp_path / "node.h5"
    job = submit_mpi(slurm, campaign, store)
    try:
        wait_for(lambda: journal_lines(store) >= 1, 120, "no point stored")
        slurm.run("scancel", "--signal=KILL", f"{job}.0")
        killed = slurm.wait(job, timeout=60)
        assert killed["Restarts"] == "0", "the script requeued a job it should not have"
        with h5py.File(store, "r", locking=False) as f:
            assert bool(f.attrs["writer_open"]), "the kill left a clean store: nothing to test"
        stored_before = len({r["row"]["hash"] for r in read_journal(journal_path(store))})

        slurm.run("scontrol", "requeue", job)
        slurm.release(job)
        # the resumed run's script has started (and trapped the signal): its master is
        # about to start up and rebuild the store the killed run left open
        wait_for(lambda: log_of(store, job).count(TRAPPED) >= 2, 120,
                 "the requeued run did not start", poll=0.005)
        slurm.run("scancel", "--signal=USR1", "--batch", job)
        rec = slurm.wait(job, {"PENDING", *sorted({"COMPLETED", "FAILED", "CANCELLED"})},
                         timeout=90)
        log = log_of(store, job)
        assert rec["JobState"] == "PENDING" and rec["Restarts"] == "2", \
            f"the time-limit signal did not stop and requeue the job: {rec}\n{log}"
        slurm.release(job)
        rec = slurm.wait(job, timeout=90)
    finally:
        slurm.cancel_quietly(job)
    log = log_of(store, job)
    report(f"node failure (step SIGKILL: {killed['JobState']} {killed['ExitCode']}),"
           " requeue, USR1 during the resumed start-up", says(rec), store,
           f"{stored_before} points before the kill; runs: {slurm.history(job)}")
    assert (rec["JobState"], rec["ExitCode"], rec["Restarts"]) == ("COMPLETED", "0:0", "2"), log
    same_as(reference[0], store)
    resumed = log.split(f"Force Terminated StepId={job}.0")[1].split("requeueing job")[0]
    assert resumed.index("time limit near") < resumed.index(" points to compute ("), \
        f"the signal came after the resumed run's start-up: this test proves nothing\n{log}"


def test_scripts_run_outside_slurm(tmp_path, run_main):
    """Fast tier: both scripts, run by ``bash`` without Slurm (the MPI one with a no-op
    launcher, the array one as two array tasks), compute a campaign whose merged shards
    hold every point once; the Slurm behaviour (signals, requeue, time limits) is the slow
    tier's tests above. ``sweep`` is a stand-in that adds ``--compute`` with the hand-set
    ``sweep.testing:power_point``."""
    from sweep.cli import main

    bin_ = tmp_path / "bin"
    bin_.mkdir()
    (bin_ / "sweep").write_text(f'#!/bin/sh\nexec {sys.executable} -m sweep "$@"'
                                " --compute sweep.testing:power_point\n")
    (bin_ / "sweep").chmod(0o755)
    config = tmp_path / "c.toml"
    config.write_text("[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\n"
                      "eps = [0.2, 0.4, 0.6]\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith("SLURM_")}
    env.update(PATH=f"{bin_}{os.pathsep}{env['PATH']}", NUMBA_CACHE_DIR=str(tmp_path / "nc"))

    def bash(script, *args, **extra):
        p = subprocess.run(["bash", str(script), *map(str, args)], env={**env, **extra},
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 0, p.stdout + p.stderr
        return p.stdout

    out = bash(MPI_SCRIPT, config, tmp_path / "mpi.h5", LAUNCH="env")
    assert "stop signals are trapped" in out
    assert len(sweep.load(tmp_path / "mpi.h5")) == 6
    for k in (0, 1):
        bash(ARRAY_SCRIPT, config, tmp_path / "shards", SLURM_ARRAY_TASK_ID=str(k),
             SLURM_ARRAY_TASK_MAX="1")
    shards = sorted((tmp_path / "shards").glob("c-*.h5"))
    assert [s.name for s in shards] == ["c-0.h5", "c-1.h5"]
    assert sum(len(sweep.load(s)) for s in shards) == 6   # (split by hash: sizes vary)
    merged = tmp_path / "merged.h5"
    assert run_main(main, ["merge", merged, *shards]).returncode == 0
    res = compare(tmp_path / "mpi.h5", merged)
    assert res["problems"] == [] and res["compared"] == 6 and res["dup_table"] == 0
