"""The last holes of the store (issue 26): a point that exits 0, journal lines from
another campaign, a truncated file, writers through a symlink, replayed journal blocks,
output the schema cannot hold, a full disk, bit rot."""
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.store.journal import journal_path, rejected_path
from sweep.store.store import Store
from sweep.testing import catches_signal, find_mpiexec
from tests import forkserver
from tests.sweep.helpers import make_unclean, partial_shard, table

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6]\n"
FAKE = "sweep.testing:fake_point"
MPIEXEC = find_mpiexec()


def _env(**extra):
    env = dict(os.environ)
    env.pop("SLURM_NTASKS", None)
    env.pop("SWEEP_NO_GUARD", None)
    env.update(extra)
    return env


def _sweep(*args, mpi=0, env=None, timeout=120):
    """``python -m sweep ARGS`` (under ``mpiexec -n MPI``); a singleton is forked from an
    interpreter that imported sweep once (tests/forkserver.py)."""
    if not mpi:
        return forkserver.run(args, capture_output=True, text=True, timeout=timeout,
                              env=env or _env())
    cmd = [MPIEXEC, "-n", str(mpi), sys.executable, "-m", "sweep", *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          env=env or _env())


# ---------------------------------------------------------------- 1. a point that exits 0
@pytest.mark.parametrize("compute", ["exiting_point", "c_exit_point"])
def test_a_point_that_exits_0_never_makes_the_campaign_succeed(tmp_path, compute):
    """os._exit(0) / C exit(0) in a compute function: every run exits 6 ("stopped",
    resumable) until the whole grid is stored (the point is ``crashed`` after [run]
    max_attempts); only then 0."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("[0.5, 1.5]", "[0.5]") + "[run]\nmax_attempts = 1\n")
    path = tmp_path / "s.h5"
    codes = []
    for _ in range(6):
        p = _sweep("run", cfg, "--store", path, "--compute", f"sweep.testing:{compute}",
                   "--no-bar")
        codes.append(p.returncode)
        if p.returncode == 0:
            break
        assert p.returncode == 6, p.stderr
        assert "ended with exit status 0 before the campaign finished" in p.stderr
        assert "resumable" in p.stderr
    assert codes[-1] == 0 and codes[:-1] and set(codes[:-1]) == {6}, codes
    df = sweep.load(path).set_index("eps")
    assert len(df) == 3 and df.loc[0.4, "status"] == "crashed"
    assert sweep.validate(path) == []


def test_the_guard_passes_on_status_and_signals(tmp_path):
    """The guard is invisible otherwise: a finished campaign exits 0, a bad campaign
    file 2, and a stop signal to the command still gives 6 (forwarded once: the
    campaign keeps its grace period)."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    path = tmp_path / "s.h5"
    assert _sweep("run", cfg, "--store", path, "--compute", FAKE, "--no-bar").returncode == 0
    bad = tmp_path / "bad.toml"
    bad.write_text("[base]\nnope = 1\n")
    assert _sweep("run", bad, "--store", tmp_path / "b.h5").returncode == 2
    slow = tmp_path / "slow.toml"
    slow.write_text(TOML.replace("0.6]", "0.6, 0.7, 0.8, 0.9]") + "[run]\ngrace_period = 30\n")
    store = tmp_path / "slow.h5"
    p = forkserver.popen(["run", slow, "--store", store, "--compute",
                          "sweep.testing:sleepy_point", "--no-bar"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=_env(), start_new_session=True)
    journal = journal_path(store)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (journal.exists()
                                               and b'"handout"' in journal.read_bytes()):
        time.sleep(0.01)
    os.killpg(p.pid, signal.SIGTERM)  # the group: guard and campaign both get it
    out, err = p.communicate(timeout=60)
    assert p.returncode == 6, err
    # one request, not two: the running point finished within the grace period
    assert "0 running point(s) abandoned" in err, err


def test_run_never_exits_0_with_points_missing(tmp_path, monkeypatch, capsys):
    """Belt and braces in the campaign process: a summary with grid points neither
    skipped nor computed is status 6."""
    import sweep.run.launch
    from sweep.run.master import RunSummary

    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    monkeypatch.setattr(sweep.run.launch, "run_campaign",
                        lambda *a, **k: RunSummary(total=6, skipped=2, computed=3))
    assert main(["run", str(cfg), "--store", str(tmp_path / "s.h5")]) == 6
    assert "1 grid point of 6 not stored" in capsys.readouterr().err


@pytest.mark.skipif(MPIEXEC is None, reason="no mpiexec (pip install mpich)")
@pytest.mark.slow  # fast: test_a_point_that_exits_0_never_makes_the_campaign_succeed
def test_a_worker_that_exits_0_never_makes_the_mpi_job_succeed(tmp_path):
    """Under mpiexec a worker rank ending with 0 inside a point ends the job non-zero
    (its guard exits 6; the launcher then kills the other ranks); the next runs resume
    and only the one that stores the whole grid exits 0."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML + "[run]\nmax_attempts = 1\n")
    path = tmp_path / "s.h5"
    codes = []
    for _ in range(8):
        p = _sweep("run", cfg, "--store", path, "--compute", "sweep.testing:exiting_point",
                   "--no-bar", mpi=3)
        codes.append(p.returncode)
        if p.returncode == 0:
            break
    assert codes[-1] == 0 and 0 not in codes[:-1] and len(codes) > 1, codes
    df = sweep.load(path)
    assert len(df) == 6 and set(df[df["eps"] == 0.4]["status"]) == {"crashed"}
    assert sweep.validate(path) == []


# ---------------------------------------------------------------- store helpers
def records(path):
    return [line for line in journal_path(path).read_bytes().splitlines(keepends=True)
            if line.startswith(b'{"row"')]


# ---------------------------------------------------------------- 2. foreign journal lines
@pytest.mark.parametrize("unclean", [False, True])
def test_a_journal_line_of_another_campaign_is_set_aside(tmp_path, campaign, unclean,
                                                         capsys):
    """A checksummed record with a valid hash for a point not in this grid (same [base],
    eps = 0.3) is set aside with its reason, never a row: from a clean store (replayed
    as 'newer') and from an unclean one (rebuilt)."""
    path, other = tmp_path / "s.h5", tmp_path / "o.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    run_campaign(parse_campaign(TOML.replace("0.2, 0.4, 0.6", "0.3")), str(other),
                 compute=FAKE)
    foreign = records(other)
    assert len(foreign) == 2
    with open(journal_path(path), "ab") as fh:
        fh.write(b"".join(foreign))
    if unclean:
        make_unclean(path)
    capsys.readouterr()
    s = run_campaign(campaign, str(path), compute=FAKE)
    err = capsys.readouterr().err
    assert s.computed == 0
    assert "2 journal line(s) set aside" in err and "not in this campaign's grid" in err
    assert table(path).equals(ref) and len(sweep.load(path)) == 6
    assert sweep.validate(path) == []
    rejected = [json.loads(x) for x in rejected_path(path).read_text().splitlines()]
    assert [r["line"].encode() + b"\n" for r in rejected] == foreign


def test_extend_keeps_the_points_of_the_smaller_grid(tmp_path, campaign):
    """The grid check accepts an --extend-ed campaign's history (old grid values are in
    the new grid): rebuilding after an extension keeps every point."""
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    bigger = parse_campaign(TOML.replace("0.2, 0.4, 0.6", "0.2, 0.3, 0.4, 0.6"))
    assert run_campaign(bigger, str(path), compute=FAKE, extend=True).computed == 2
    make_unclean(path)
    assert run_campaign(bigger, str(path), compute=FAKE).computed == 0
    assert len(sweep.load(path)) == 8


# ---------------------------------------------------------------- 3. a truncated file
@pytest.mark.parametrize("keep", ["half", "superblock"])
def test_a_truncated_store_beside_its_journal_is_rebuilt(tmp_path, campaign, keep, capsys):
    """HDF5's message for a truncated file names its 'sblock' (superblock): that is
    damage, not 'in use'."""
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2] if keep == "half" else data[:96])
    capsys.readouterr()
    s = run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    err = capsys.readouterr().err
    assert s.computed == 0 and "damaged" in err and "in use" not in err
    assert table(path).equals(ref)
    assert len(list(tmp_path.glob("s.h5.damaged-*"))) == 1
    assert sweep.validate(path) == []


# ---------------------------------------------------------------- 5. replayed journal lines
def test_a_replayed_block_of_old_lines_does_not_revert_retried_points(tmp_path, campaign):
    """The rebuild takes each point's record with the highest seq, not the last line."""
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    failed = [line for line in records(path) if b'"status":"failed"' in line]
    assert len(failed) == 2
    run_campaign(campaign, str(path), compute=FAKE, retry_failed=True)
    ref = table(path)
    assert set(ref["status"]) <= {"converged", "converged_noisy"}
    with open(journal_path(path), "ab") as fh:
        fh.write(b"".join(failed))  # the old lines again, after their retried ones
    make_unclean(path)
    assert run_campaign(campaign, str(path), compute=FAKE).computed == 0
    assert table(path).equals(ref)


# ---------------------------------------------------------------- 4. other names, one file
def test_a_symlink_names_the_same_store(tmp_path, campaign, refused_at_once):
    """The lock and journal are named after the file reached: a writer through a
    symlink is refused while another writes the target, and the journal is the
    target's."""
    path, link = tmp_path / "s.h5", tmp_path / "a.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    link.symlink_to(path.name)
    s = Store(path, campaign, report=lambda m: None)
    try:
        with pytest.raises(sweep.StoreLockedError):
            Store(link, campaign, report=lambda m: None)
    finally:
        s.close()
    assert run_campaign(campaign, str(link), compute=FAKE).computed == 0
    assert not (tmp_path / "a.h5.journal").exists() and not (tmp_path / "a.h5.lock").exists()
    assert len(sweep.load(link)) == 6 and sweep.validate(path) == []


def test_a_hard_link_is_refused_while_the_file_is_written(tmp_path, campaign, refused_at_once):
    """A hard link shares no name with the store: the flock on the file itself refuses
    the second writer (nothing of it is written)."""
    path, link = tmp_path / "s.h5", tmp_path / "h.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    os.link(path, link)
    s = Store(path, campaign, report=lambda m: None)
    try:
        with pytest.raises(sweep.StoreLockedError, match="hard link"):
            Store(link, campaign, report=lambda m: None)
    finally:
        s.close()
    assert not (tmp_path / "h.h5.journal").exists()
    assert sweep.validate(path) == [] and len(sweep.load(path)) == 6


GATED = """\
import os, time
from sweep.testing import fake_point


def point(cfg):  # fake_point once the file named by $GATE exists (at most 60 s)
    deadline = time.monotonic() + 60
    while not os.path.exists(os.environ["GATE"]) and time.monotonic() < deadline:
        time.sleep(0.01)
    return fake_point(cfg)
"""


def test_two_writers_through_a_symlink_never_ruin_the_store(tmp_path):
    """The issue's case, two ``sweep run`` at once, ``--store S.h5`` and ``--store A.h5``
    (a symlink to it): one is refused (exit 3) or finds everything stored, and the store
    is whole. (The first one's points wait for a gate the test opens once the second has
    ended: the first is live, holding its points, for the whole of the second.)"""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    (tmp_path / "gated.py").write_text(GATED)
    gate = tmp_path / "gate"
    env = _env(GATE=str(gate),
               PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    path, link = tmp_path / "s.h5", tmp_path / "a.h5"
    link.symlink_to(path.name)
    cmd = ["run", cfg, "--compute", "gated:point", "--no-bar", "--store"]
    a = forkserver.popen([*cmd, path], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    try:
        deadline = time.monotonic() + 60
        journal = journal_path(path)  # the first has opened the store and handed out points
        while time.monotonic() < deadline and not (journal.exists()
                                                   and b'"handout"' in journal.read_bytes()):
            time.sleep(0.01)
        b = forkserver.run([*cmd, link], capture_output=True, text=True, env=env,
                           timeout=120)
        assert a.poll() is None, "the first writer ended before the second one was refused"
    finally:
        gate.touch()
        a.communicate(timeout=120)
    assert a.returncode == 0
    assert b.returncode == 3 and "live campaign" in b.stderr, b.stderr
    assert len(sweep.load(path)) == 6 and sweep.validate(path) == []


# ---------------------------------------------------------------- 6. what the schema cannot hold
def test_output_the_schema_cannot_hold_is_a_failed_point(tmp_path):
    """Profiles of the wrong length (3 or 10**6 for a 12-floe point), complex arrays,
    alpha_all = inf, iterations = -inf: each point is stored ``failed`` with its
    reason, and the store stays valid."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("0.2, 0.4, 0.6", "0.1, 0.2, 0.3, 0.4, 0.5, 0.6"))
    path = tmp_path / "s.h5"
    assert main(["run", str(cfg), "--store", str(path), "--compute",
                 "sweep.testing:misfit_point", "--no-bar"]) == 0
    df = sweep.load(path).set_index(["L_x", "eps"])
    want = {0.1: "profile a: 3 values, expected n_floes = ",
            0.2: "profile gap_mean: 1000000 values, expected n_floes = ",
            0.3: "complex values in F_w_mean", 0.4: "alpha_all = 'inf'",
            0.5: "iterations = '-inf'"}
    for L_x in (0.5, 1.5):
        for eps, needle in want.items():
            assert df.loc[(L_x, eps), "status"] == "failed"
            assert needle in df.loc[(L_x, eps), "message"], df.loc[(L_x, eps), "message"]
        assert df.loc[(L_x, 0.6), "status"] == "converged"
    assert sweep.validate(path) == []


# ---------------------------------------------------------------- 7. a completely full disk
def test_a_resume_on_a_full_disk_is_one_line_and_exit_3(tmp_path, monkeypatch, capsys):
    """ENOSPC where the lock file's owner is written (the first write of a resume):
    exit 3 and one line, no traceback; the store is untouched."""
    import errno

    import sweep.store.lock

    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    path = tmp_path / "s.h5"
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 0
    before = path.read_bytes(), journal_path(path).read_bytes()
    capsys.readouterr()

    def full(fd, data, offset):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(sweep.store.lock.os, "pwrite", full)
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No space left on device" in err and "free space" in err
    assert "Traceback" not in err
    assert (path.read_bytes(), journal_path(path).read_bytes()) == before


def _journal_objects(path):
    from sweep.store.journal import decode

    return [decode(line)[0] for line in journal_path(path).read_bytes().splitlines(True)]


def test_failed_resumes_on_a_full_disk_charge_no_attempt(tmp_path, monkeypatch, capsys):
    """The disk is full when a suspect point's result is committed (ENOSPC in the
    journal write: the store is broken): the run ends with exit 3 and the point, computed
    alone, is released (it did not kill its worker); after more such resumes than
    [run] max_attempts it is still computed, not stored ``crashed``."""
    from tests.sweep.helpers import suspect_with_a_full_disk

    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    campaign = parse_campaign(TOML)
    path = tmp_path / "s.h5"
    with monkeypatch.context() as m:
        first = suspect_with_a_full_disk(path, campaign, m)
        for _ in range(campaign.run.max_attempts + 1):
            assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE,
                         "--no-bar"]) == 3
            assert "no space left on the device" in capsys.readouterr().err
    assert [o["release"] for o in _journal_objects(path) if "release" in o] == \
        [first.hash] * (campaign.run.max_attempts + 1)
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 0
    assert "crashed" not in set(sweep.load(path)["status"])
    assert sweep.validate(path) == []


def test_hand_outs_keep_the_free_space_margin(tmp_path, monkeypatch, capsys):
    """Hand-out lines are refused, like records, when the free space is short (exit 3,
    one line, no hand-out written): they do not eat the margin the releases need."""
    from sweep.store import files

    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    path = tmp_path / "s.h5"
    real = os.statvfs

    class Nearly:  # just the reserve free: opening passes, anything more does not fit
        def __init__(self, st):
            self.f_frsize, self.f_bavail = 1, files.SPACE_RESERVE + 10

    monkeypatch.setattr(files.os, "statvfs", lambda p: Nearly(real(p)))
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 3
    err = capsys.readouterr().err
    assert "no space left on the device for handing out points" in err, err
    assert "Traceback" not in err
    assert not [o for o in _journal_objects(path) if "handout" in o]


# ---------------------------------------------------------------- 8. bit rot
def _flip(path, where, byte=3):
    """Flip one byte of dataset ``where``'s first value in the file (bit rot)."""
    with h5py.File(path, "r", locking=False) as f:
        ds = f[where]
        offset = ds.id.get_offset()
        if offset is None:  # chunked (the table columns)
            offset = ds.id.get_chunk_info(0).byte_offset
    with open(path, "r+b") as fh:
        fh.seek(offset + byte)
        b = fh.read(1)
        fh.seek(offset + byte)
        fh.write(bytes([b[0] ^ 0x5A]))


def test_bit_rot_is_found_by_validate_deep_and_repaired_by_run_verify(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    path = tmp_path / "s.h5"
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 0
    ref = table(path)
    assert main(["validate", "--deep", str(path)]) == 0
    assert "every stored value is its journal's" in capsys.readouterr().out
    h0 = sweep.load(path)["hash"][0]
    _flip(path, "table/W_c")
    _flip(path, f"profiles/{h0[:2]}/{h0}/a", byte=6)
    assert main(["validate", str(path)]) == 0  # the schema check alone cannot see it
    capsys.readouterr()
    assert main(["validate", "--deep", str(path)]) == 3
    err = capsys.readouterr().err
    assert f"/table/W_c[0] (point {h0[:12]})" in err and "in the journal" in err
    assert f"/profiles/{h0[:2]}/{h0}/a: differs from the journal" in err
    assert err.count("sweep: error:") == 3  # two differences and the advice
    # a resume without --verify does not look; with it the file is rebuilt
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar",
                 "--verify"]) == 0
    err = capsys.readouterr().err
    assert "2 value(s) differ from the journal" in err and "rebuilt from the journal" in err
    assert table(path).equals(ref)
    assert len(list(tmp_path.glob("s.h5.damaged-*"))) == 1
    assert main(["validate", "--deep", str(path)]) == 0


# ---------------------------------------------------------------- 9. stops during imports
SLOW_IMPORT = """\
import sys, time
print("importing", flush=True)
time.sleep(float(sys.argv[-1]) if sys.argv[-1].replace(".", "").isdigit() else 3.0)
from sweep.testing import fake_point as point
"""


def test_a_stop_during_the_compute_import_is_status_6(tmp_path):
    """SIGTERM while ``--compute``'s module is being imported: "stopped", exit 6 (not
    exit 2 "--compute ... cannot import it: Interrupted")."""
    (tmp_path / "slowmod.py").write_text(SLOW_IMPORT)
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    env = _env(PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    p = subprocess.Popen([sys.executable, "-m", "sweep", "run", str(cfg), "--store",
                          str(tmp_path / "s.h5"), "--compute", "slowmod:point", "--no-bar"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    assert p.stdout.readline().strip() == "importing"
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 6, err
    assert "stopped by SIGTERM" in err and "cannot import" not in err
    assert "Traceback" not in err


LOST_STOP = """\
import signal, weakref
class Thing:
    pass
thing = Thing()
# the stop signal's handler runs in a weakref callback, where Python cannot raise its
# exception: it reports it ("Exception ignored") and the import goes on
keep = weakref.ref(thing, lambda ref: signal.getsignal(signal.SIGTERM)(signal.SIGTERM, None))
del thing
from sweep.testing import fake_point as point
"""


def test_a_stop_whose_exception_is_lost_still_stops(tmp_path):
    """A start-up stop whose exception Python cannot raise (the handler ran in a weakref
    callback or finaliser during an import; seen as a flake of the start-up tests) is not
    lost: the campaign takes it up and stops at once, status 6, with no "Exception
    ignored" traceback; no point is computed. A merge takes it up the same way."""
    (tmp_path / "lost.py").write_text(LOST_STOP)
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    env = _env(PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    store = tmp_path / "s.h5"
    p = _sweep("run", cfg, "--store", store, "--compute", "lost:point", "--no-bar", env=env)
    assert p.returncode == 6, p.stderr
    assert "stopped by SIGTERM" in p.stderr and "resumable" in p.stderr
    assert "Traceback" not in p.stderr and "Exception ignored" not in p.stderr
    assert len(sweep.load(store)) == 0
    from sweep.errors import Interrupted
    from sweep.store.merge import merge
    from sweep.system import note_start_up_stop, take_start_up_stop

    run_campaign(parse_campaign(TOML), str(store), compute=FAKE)
    note_start_up_stop("SIGTERM")  # as the start-up handler leaves it, its raise lost
    try:
        with pytest.raises(Interrupted, match="merge stopped by SIGTERM after 0 points"):
            merge(tmp_path / "out.h5", [store])
        assert take_start_up_stop() == ""  # taken up once
    finally:
        take_start_up_stop()
    merge(tmp_path / "out.h5", [store])
    assert len(sweep.load(tmp_path / "out.h5")) == 6


def test_a_stop_wrapped_by_an_import_is_status_6(monkeypatch, capsys):
    """A stop raised inside an import whose machinery wraps it (Python 3.11 turns an
    exception in a dataclass field's ``__set_name__`` into a RuntimeError) is still the
    stop: status 6, no traceback (seen in test_a_stop_in_the_first_instants_is_status_6)."""
    import sweep.cli
    import sweep.run.startup

    def parser():  # the start-up handler ran inside an import; its Interrupted wrapped
        sweep.run.startup.FIRST.append(signal.SIGINT)
        raise RuntimeError("Error calling __set_name__ on 'Field' instance 'warnings'")

    monkeypatch.setattr(sweep.cli, "build_parser", parser)
    assert main(["run", "c.toml", "--store", "s.h5"]) == 6
    err = capsys.readouterr().err
    assert "stopped by SIGINT during start-up" in err and "Traceback" not in err


@pytest.mark.parametrize("delay", [0.0, pytest.param(0.02, marks=pytest.mark.slow), 0.05,
                                   pytest.param(0.1, marks=pytest.mark.slow), 0.2,
                                   pytest.param(0.4, marks=pytest.mark.slow)])
def test_a_stop_in_the_first_instants_is_status_6(tmp_path, delay):
    """SIGTERM or SIGINT from the first instants of ``sweep run`` (its handlers are
    installed before any heavy import): 6 (or 0 once finished), never a traceback or a
    death by the signal once the process catches it."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    for sig in (signal.SIGTERM, signal.SIGINT):
        p = subprocess.Popen([sys.executable, "-m", "sweep", "run", str(cfg), "--store",
                              str(tmp_path / "s.h5"), "--compute", FAKE, "--no-bar"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=_env())
        # SIGTERM's handler is sweep's (Python's own SIGINT handler exists from the
        # interpreter's first instants: a SIGINT before sweep runs is Python's affair)
        while p.poll() is None and not catches_signal(p.pid, signal.SIGTERM):
            time.sleep(0.001)
        time.sleep(delay)
        p.send_signal(sig)
        out, err = p.communicate(timeout=60)
        assert p.returncode in (0, 6), (p.returncode, err)
        assert "Traceback" not in err and "cannot import" not in err
        if p.returncode == 0:
            assert "6 grid points" in out


# ---------------------------------------------------------------- 10. hostile inputs
def test_a_campaign_file_that_is_not_a_file_is_refused_at_once(tmp_path):
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * (1 << 20) + "\n" + TOML)
    for cfg, needle in (("/dev/zero", "not a regular file"), (fifo, "not a regular file"),
                        (big, "a campaign file is at most")):
        p = _sweep("run", cfg, "--store", tmp_path / "s.h5", timeout=60)
        assert p.returncode == 2 and needle in p.stderr, p.stderr
        assert "Traceback" not in p.stderr
    assert not (tmp_path / "s.h5").exists()


def test_values_beyond_any_parameter_are_config_errors():
    """a0, d_f, C_sd = 1e308, dt = 1e-300, eps = 5e-324: each named, nothing runs (sweep's
    bound; floewave's own validation is unchanged)."""
    text = ("[base]\nL_sheet = 6.0\na0 = 1e308\nd_f = 1e308\nC_sd = 1e308\ndt = 1e-300\n"
            "[sweep]\neps = [5e-324, 0.5]\n")
    with pytest.raises(sweep.ConfigError) as info:
        parse_campaign(text)
    messages = info.value.messages
    for key in ("[base] a0 = 1e+308", "[base] d_f = 1e+308", "[base] C_sd = 1e+308",
                "[base] dt = 1e-300", "[sweep] eps = 5e-324"):
        assert any(key in m and "out of range [1e-12, 1e+12]" in m for m in messages), messages
    parse_campaign("[base]\nL_sheet = 6.0\nC_sd = 0.0\n[sweep]\neps = [0.5]\n")  # zero is fine


@pytest.mark.slow  # a pipe; fast: test_a_resume_on_a_full_disk_is_one_line_and_exit_3,
# test_a_campaign_file_that_is_not_a_file_is_refused_at_once
def test_hostile_paths_and_outputs_are_one_line(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    deep = tmp_path / ("d" * 250) / ("d" * 250) / "s.h5"
    long_path = str(tmp_path) + "/" + "/".join(["e" * 250] * 17) + "/s.h5"
    for store in (long_path, tmp_path / ("n" * 240 + ".h5"), deep):
        p = _sweep("run", cfg, "--store", store, "--compute", FAKE, "--no-bar")
        assert p.returncode == 3 and "Traceback" not in p.stderr, p.stderr[-500:]
        assert p.stderr.count("\n") == 1
    path = tmp_path / "s.h5"
    assert _sweep("run", cfg, "--store", path, "--compute", FAKE).returncode == 0
    full = tmp_path / "full.csv"
    full.symlink_to("/dev/full")
    p = _sweep("export", path, "-o", full)
    assert p.returncode == 3 and "No space left" in p.stderr and "Traceback" not in p.stderr
    # a reader that stops early: `sweep status S.h5 --slowest 100 | head -1`
    p = subprocess.Popen([sys.executable, "-m", "sweep", "status", str(path), "--slowest",
                          "100"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    assert p.stdout.readline().startswith(str(path).encode())
    p.stdout.close()
    err = p.stderr.read().decode()
    assert p.wait(timeout=60) == 0 and "Traceback" not in err, err


# ---------------------------------------------------------------- 11. smaller
def test_a_point_that_closes_stdout_does_not_break_the_summary(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    p = _sweep("run", cfg, "--store", tmp_path / "s.h5", "--compute",
               "sweep.testing:stdout_closing_point", "--no-bar")
    assert p.returncode == 0, p.stderr
    assert "6 grid points: 0 already stored, 6 stored now" in p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.slow  # fast: test_store_safety.py::test_point_timeout_records_timeout and
# ::test_point_stuck_in_native_code_is_stored_timeout_in_one_run
def test_a_point_that_swallows_its_timeout_is_timeout_in_one_run(tmp_path):
    """``except BaseException`` in a loop: in-process the point runs in a child process
    killed a margin after point_timeout: ``timeout`` in this run (before: 7 runs of
    2t + 30 s until ``crashed``); one that ends its process is ``crashed`` in this run."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML + "[run]\npoint_timeout = 0.5\n")
    path = tmp_path / "s.h5"
    t0 = time.monotonic()
    p = _sweep("run", cfg, "--store", path, "--compute", "sweep.testing:stubborn_point",
               "--no-bar", env=_env(SWEEP_CHILD_MARGIN="0.3"))  # killed 0.3 s after it
    assert p.returncode == 0, p.stderr
    assert time.monotonic() - t0 < 30
    df = sweep.load(path).set_index(["L_x", "eps"])
    assert list(df.xs(0.4, level="eps")["status"]) == ["timeout", "timeout"]
    assert set(df.xs(0.2, level="eps")["status"]) == {"converged"}
    other = tmp_path / "o.h5"
    p = _sweep("run", cfg, "--store", other, "--compute", "sweep.testing:exiting_point",
               "--no-bar")
    assert p.returncode == 0, p.stderr
    df = sweep.load(other).set_index(["L_x", "eps"])
    assert list(df.xs(0.4, level="eps")["status"]) == ["crashed", "crashed"]
    assert "its process ended with status 0" in df.xs(0.4, level="eps")["message"].iloc[0]
    assert sweep.validate(path) == [] and sweep.validate(other) == []


def test_a_rebuild_keeps_the_runs_and_their_numbering(tmp_path, campaign):
    """A rebuilt unclean file keeps /runs (the dead run marked so); a file rebuilt from
    the journal alone (removed) goes on after the journal's last run, not from 0."""
    path = tmp_path / "s.h5"
    run_campaign(partial_shard(campaign), str(path), compute=FAKE)
    run_campaign(campaign, str(path), compute=FAKE)
    make_unclean(path)
    with h5py.File(path, "r+", locking=False) as f:
        f["runs"]["1"].attrs["outcome"] = "running"  # as a killed run leaves it
    run_campaign(campaign, str(path), compute=FAKE)
    runs = sweep.analysis.load.store_runs(path)
    assert [r["index"] for r in runs] == [0, 1, 2]
    assert runs[1]["outcome"].startswith("died") and runs[2]["outcome"] == "complete"
    path.unlink()
    run_campaign(campaign, str(path), compute=FAKE)
    assert [r["index"] for r in sweep.analysis.load.store_runs(path)] == [2]  # the journal's last
    assert set(sweep.load(path)["run"]) == {0, 1}


def test_help_under_the_guard_exits_0():
    """The console path forks the guard for ``run``: argparse's --help (SystemExit 0) is a
    clean exit, not 'ended with status 0 before the campaign finished' (exit 6)."""
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "sweep", "run", "--help"], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "usage" in p.stdout and "before the campaign finished" not in p.stderr


def test_a_point_that_exits_0_behind_uncommitted_results_is_found(tmp_path):
    """The point that ends the process is queued behind points whose results were
    computed but not yet committed (one group commit): every unfinished hand-out is a
    suspect, so it is computed alone, charged, and stored ``crashed``; the campaign ends.
    (With only each worker's earliest unfinished hand-out as the suspect, a point before
    it was retried alone at every run and the campaign never finished: the store torture's
    "exit 0 in a point".)"""
    eps = ", ".join(repr(round(0.05 + 0.05 * i, 2)) for i in range(12))
    cfg = tmp_path / "c.toml"
    cfg.write_text(f"[base]\nL_sheet = 6.0\n[sweep]\neps = [{eps}]\n[run]\nmax_attempts = 1\n")
    path = tmp_path / "s.h5"
    codes = []
    for _ in range(6):
        p = _sweep("run", cfg, "--store", path, "--compute", "sweep.testing:exiting_point",
                   "--no-bar")
        codes.append(p.returncode)
        if p.returncode == 0:
            break
    assert codes[-1] == 0, codes
    df = sweep.load(path).set_index("eps")
    assert len(df) == 12 and df.loc[0.4, "status"] == "crashed"
    assert set(df.drop(index=0.4)["status"]) == {"converged"}
