"""A store nothing can ruin (issue 15): atomic rebuilds, stops during them, the campaign
check on the journal, refusing what is not a damaged store, the lock, checksummed journal
lines, records that cannot be written, compute faults."""
import json
import os
import random
import signal
import subprocess
import sys
import time

import h5py
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.store.journal import Journal, decode, encode, journal_path, rejected_path
from sweep.store.store import Store
from sweep.testing import catches_signal
from tests import forkserver
from tests.sweep.helpers import make_unclean, store_holder, table

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6, 0.8]\n"
FAKE = "sweep.testing:fake_point"


# ---------------------------------------------------------------- atomic rebuild, stops
_OPEN_SCRIPT = """
import sys, time, sweep, sweep.cli
from sweep.store.store import Store
from sweep.store.writer import H5Writer
real = H5Writer.write_many
def slow(self, records):  # a rebuild that takes long enough to be hit
    print("writing", flush=True)
    time.sleep(0.02)
    real(self, records)
H5Writer.write_many = slow
if sys.argv[1] == "open":
    Store(sys.argv[2], sweep.load_campaign(sys.argv[3])).close()
else:
    sys.exit(sweep.cli.main(["run", sys.argv[3], "--store", sys.argv[2], "--compute",
                             "sweep.testing:fake_point", "--no-bar"]))
"""


def _big(tmp_path):
    eps = ", ".join(repr(round(0.01 + 0.009 * i, 4)) for i in range(100))
    cfg = tmp_path / "big.toml"
    cfg.write_text(f"[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5, 3.0]\neps = [{eps}]\n")
    path = tmp_path / "s.h5"
    assert main(["run", str(cfg), "--store", str(path), "--compute", FAKE, "--no-bar"]) == 0
    return cfg, path


def test_kill_9_during_rebuild_never_ruins_the_store(tmp_path):
    """SIGKILL at random instants of the rebuild: the store path always holds the old
    (unclean) file or the complete new one, never a half-built one that looks clean.
    (Each rebuild is a process forked by an interpreter that imported sweep once:
    tests/forkserver.py.)"""
    cfg, path = _big(tmp_path)
    ref = table(path)
    with h5py.File(path, "r", locking=False) as f:
        n_ref = int(f["table"].attrs["n_rows"])
    make_unclean(path)
    rng = random.Random(15)
    hit = left = 0
    for _ in range(6):
        opener = forkserver.popen(["open", path, cfg], code=_OPEN_SCRIPT,
                                  stdout=subprocess.PIPE, text=True)
        assert opener.stdout.readline().strip() == "writing"
        time.sleep(rng.uniform(0.0, 0.02))
        opener.kill()
        opener.communicate(timeout=60)
        pid = opener.pid
        hit += opener.returncode == -signal.SIGKILL
        with h5py.File(path, "r", locking=False) as f:  # old file or the whole new one
            if not f.attrs["writer_open"]:
                assert int(f["table"].attrs["n_rows"]) == n_ref
                assert "rebuilt_from_journal" in f.attrs
        # the temporary file of a killed rebuild stays until the next open removes it:
        # at most this process's own is left, never an earlier one's
        temps = {t.name for t in tmp_path.glob(".s.h5.rebuild-*")}
        assert temps <= {f".s.h5.rebuild-{pid}.tmp"}, temps
        left += bool(temps)
    assert hit >= 4
    assert left >= 1  # a killed rebuild did leave its temporary file (removed below)
    s = run_campaign(sweep.load_campaign(cfg), str(path), compute="sweep.testing:raising_point")
    assert s.computed == 0
    assert not list(tmp_path.glob(".s.h5.rebuild-*"))
    assert table(path).equals(ref)
    assert sweep.validate(path) == []


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGUSR1,
                                 pytest.param(signal.SIGINT, marks=pytest.mark.slow)])
# SIGINT: slow tier (fast: SIGTERM and SIGUSR1 here; SIGINT in test_store_holes.py)
def test_stop_signal_during_rebuild_is_deferred_then_exit_6(tmp_path, sig):
    cfg, path = _big(tmp_path)
    ref = table(path)
    make_unclean(path)
    p = forkserver.popen(["run", path, cfg], code=_OPEN_SCRIPT, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "writing"
    p.send_signal(sig)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 6, err
    assert "resumable" in err and "rebuilt from the journal" in err
    assert table(path).equals(ref)
    with h5py.File(path, "r", locking=False) as f:
        assert not f.attrs["writer_open"]
    assert sweep.validate(path) == []


def test_rebuild_failure_leaves_the_old_file(tmp_path, campaign):
    """h5py's RuntimeError/ValueError during the rebuild: the old file is untouched."""
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    make_unclean(path)
    before = path.read_bytes()

    class Broken(Journal):
        def lines(self):
            for i, item in enumerate(super().lines()):
                if i == 3:
                    raise ValueError("bad heap free list")  # as h5py raises it
                yield item

    with pytest.raises(ValueError, match="heap"):
        Store(path, campaign, journal=Broken(journal_path(path)))
    assert path.read_bytes() == before
    assert not list(tmp_path.glob(".s.h5.rebuild-*"))
    assert len(Store(path, campaign, report=lambda m: None).rows) == 8


# ---------------------------------------------------------------- the campaign check
def test_campaign_check_covers_the_journal(tmp_path, campaign):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    other = parse_campaign(TOML.replace("6.0", "9.0"))
    make_unclean(path)  # a killed store of campaign A, run with campaign B
    before = path.read_bytes()
    with pytest.raises(sweep.CampaignMismatchError, match="store belongs"):
        run_campaign(other, str(path), compute=FAKE)
    assert path.read_bytes() == before
    path.unlink()  # the .h5 deleted, the journal of A kept
    with pytest.raises(sweep.CampaignMismatchError, match="journal belongs"):
        run_campaign(other, str(path), compute=FAKE)
    assert not path.exists()
    # a journal of before checksums (no campaign line, arrays as lists) is checked point
    # by point
    legacy = [json.dumps(decode(line)[0], default=lambda a: a.tolist()).encode() + b"\n"
              for line in journal_path(path).read_bytes().splitlines(keepends=True)
              if b'"row"' in line]
    journal_path(path).write_bytes(b"".join(legacy))
    with pytest.raises(sweep.CampaignMismatchError, match="not in this campaign"):
        run_campaign(other, str(path), compute=FAKE)
    s = run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    assert (s.skipped, s.computed) == (8, 0)  # the legacy journal rebuilt campaign A


# ---------------------------------------------------------------- not ours, the lock
def test_what_is_not_a_damaged_store_is_never_touched(tmp_path, campaign):
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    journal_path(notes).write_text("also mine\n")
    with pytest.raises(sweep.StoreError, match="not an HDF5 file"):
        run_campaign(campaign, str(notes), compute=FAKE)
    assert notes.read_text() == "my notes\n"
    assert journal_path(notes).read_text() == "also mine\n"
    folder = tmp_path / "dir.h5"
    folder.mkdir()
    with pytest.raises(sweep.StoreError, match="directory"):
        run_campaign(campaign, str(folder), compute=FAKE)
    assert folder.is_dir() and not list(folder.iterdir())
    # another reader holding the store open (with HDF5 file locking) is no corruption
    path = tmp_path / "s.h5"
    run_campaign(campaign.shard(0, 2), str(path), compute=FAKE)
    reader = forkserver.popen([], code="import sys, h5py;"
                              f"f = h5py.File({str(path)!r}, 'r'); print('open', flush=True);"
                              "sys.stdin.read()", stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert reader.stdout.readline().strip() == "open"
        assert run_campaign(campaign, str(path), compute=FAKE, extend=False).skipped > 0
    finally:
        reader.kill()
        reader.wait()
    with h5py.File(path, "r") as same_process:  # HDF5 refuses a second open here
        before = path.read_bytes()
        with pytest.raises(sweep.StoreError, match="in use"):
            run_campaign(campaign, str(path), compute=FAKE)
        assert path.read_bytes() == before
        assert int(same_process["table"].attrs["n_rows"]) == 8
    assert not [p for p in tmp_path.iterdir() if "damaged" in p.name or "corrupt" in p.name]
    lock_dir = tmp_path / "s.h5.lock"
    lock_dir.mkdir()
    with pytest.raises(sweep.StoreError, match="lock file is a directory"):
        run_campaign(campaign, str(path), compute=FAKE)


def test_empty_store_beside_its_journal_is_rebuilt(tmp_path, campaign):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    path.write_bytes(b"")
    s = run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    assert s.computed == 0 and table(path).equals(ref)
    assert len(list(tmp_path.glob("s.h5.damaged-*"))) == 1


def test_deleting_the_lock_file_does_not_admit_a_second_writer(tmp_path, campaign, refused_at_once):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    holder = store_holder(path, TOML)
    try:
        with pytest.raises(sweep.StoreLockedError, match=f"pid {holder.pid}"):
            Store(path, campaign)
        os.unlink(tmp_path / "s.h5.lock")
        before = path.read_bytes()
        with pytest.raises(sweep.StoreLockedError, match=f"journal is held.*{holder.pid}"):
            Store(path, campaign)
        assert path.read_bytes() == before
    finally:
        holder.kill()
        holder.wait()
    assert len(Store(path, campaign, report=lambda m: None).rows) == 8


# ---------------------------------------------------------------- checksummed journal
def _edit_journal(path, edit):
    jp = journal_path(path)
    lines = jp.read_bytes().splitlines(keepends=True)
    jp.write_bytes(b"".join(edit(lines)))


def test_altered_journal_lines_are_set_aside_and_recomputed(tmp_path, campaign, capsys):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    records = [i for i, line in enumerate(journal_path(path).read_bytes().splitlines())
               if b'"row"' in line]
    hashes = [decode(journal_path(path).read_bytes().splitlines()[i])[0]["row"]["hash"]
              for i in records[:4]]

    def edit(lines):
        a, b, c, d = records[:4]
        w = json.loads(decode(lines[a])[0]["row"]["W_c"].__repr__())
        lines[a] = lines[a].replace(b'"W_c":' + repr(w).encode(),
                                    b'"W_c":' + repr(w + 80).encode())  # a flipped digit
        lines[b] = lines[b].replace(b'"status":"converged"', b'"status":"failed"')
        obj = decode(lines[c])[0]
        obj["row"]["hash"] = obj["row"]["hash"][:-1] + "0" if \
            obj["row"]["hash"][-1] != "0" else obj["row"]["hash"][:-1] + "1"
        lines[c] = encode(obj)  # a valid checksum, but the config does not re-hash
        obj = decode(lines[d])[0]
        del obj["row"]
        lines[d] = encode(obj)  # a valid checksum, but no row
        return lines

    _edit_journal(path, edit)
    make_unclean(path)  # the file is rebuilt from the journal
    capsys.readouterr()
    s = run_campaign(campaign, str(path), compute=FAKE)
    err = capsys.readouterr().err
    assert "4 journal line(s) set aside" in err and str(rejected_path(path)) in err
    assert "checksum mismatch" in err and "does not hash" in err and "no 'row'" in err
    assert s.computed == 4  # the four points were computed again, nothing else
    assert table(path).equals(ref)
    rejected = [json.loads(x) for x in rejected_path(path).read_text().splitlines()]
    assert len(rejected) == 4 and all(r["reason"] for r in rejected)
    assert set(hashes) <= set(sweep.load(path)["hash"])
    capsys.readouterr()
    assert run_campaign(campaign, str(path), compute=FAKE).computed == 0
    assert "set aside" not in capsys.readouterr().err  # once


def test_unwritable_record_is_quarantined_once(tmp_path, campaign, capsys):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)

    def edit(lines):
        for i, line in enumerate(lines):
            if b'"row"' in line:
                obj = decode(line)[0]
                obj["row"]["iterations"] = 1e20  # passes the checksum, cannot be an int64
                lines[i] = encode(obj)
                return lines

    _edit_journal(path, edit)
    path.unlink()
    capsys.readouterr()
    s = run_campaign(campaign, str(path), compute=FAKE)
    assert "cannot be written to HDF5" in capsys.readouterr().err
    assert s.computed == 1 and table(path).equals(ref)
    s = run_campaign(campaign, str(path), compute=FAKE)
    assert s.computed == 0 and "set aside" not in capsys.readouterr().err
    assert "64-bit" in rejected_path(path).read_text()


# ---------------------------------------------------------------- compute faults
def test_compute_faults_are_failed_points(tmp_path):
    c = parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]\n")
    path = tmp_path / "s.h5"
    s = run_campaign(c, str(path), compute="sweep.testing:faulty_point")
    df = sweep.load(path).set_index("eps")
    assert s.computed == 6 and len(df) == 6
    expect = {0.1: "SystemExit", 0.2: "KeyboardInterrupt", 0.3: "W_c = 'wide'",
              0.4: "iterations", 0.5: "\\udcff"}
    for eps, needle in expect.items():
        assert df.loc[eps, "status"] == "failed", eps
        assert needle in df.loc[eps, "message"], (eps, df.loc[eps, "message"])
    assert df.loc[0.6, "status"] == "converged"
    assert sweep.validate(path) == []
    # the run's counts are the stored statuses (one Record: W_c = 'wide' is failed)
    assert s.counts == {"failed": 5, "converged": 1}


def test_bad_compute_is_a_config_error_and_writes_nothing(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    assert main(["run", str(cfg), "--store", str(tmp_path / "s.h5"), "--compute",
                 "no_such_module:f"]) == 2
    assert list(tmp_path.iterdir()) == [cfg]


def test_grace_period_bounded():
    with pytest.raises(sweep.ConfigError, match="grace_period"):
        parse_campaign(TOML + "[run]\ngrace_period = 1e300\n")


def test_stop_during_start_up_never_ruins_the_store(tmp_path):
    """SIGTERM at instants of a resume's start-up after its handlers are installed
    (imports, campaign, lock, open): exit 6 with "resumable" (or 0 if it had finished),
    and the same complete, clean store every time."""
    cfg, path = _big(tmp_path)
    ref = table(path)
    statuses = []
    for delay in (0.0, 0.1, 0.2):
        p = subprocess.Popen([sys.executable, "-m", "sweep", "run", str(cfg), "--store",
                              str(path), "--compute", FAKE, "--no-bar"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        while p.poll() is None and not catches_signal(p.pid, signal.SIGTERM):
            time.sleep(0.005)
        time.sleep(delay)
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=60)
        statuses.append(p.returncode)
        # -15: the run had finished and the interpreter was shutting down (Python
        # restores the default handlers then)
        assert p.returncode in (0, 6) or (p.returncode == -signal.SIGTERM and
                                          "300 grid points" in out), (out, err)
        if p.returncode == 6:
            assert "resumable" in err
        assert table(path).equals(ref)
        with h5py.File(path, "r", locking=False) as f:
            assert not f.attrs["writer_open"]
    assert 6 in statuses, statuses


def test_a_point_that_kills_its_process_is_recorded_crashed(tmp_path):
    """A deterministic crasher (``os._exit`` in the point: a segfault's effect) cannot
    block the campaign: after [run] max_attempts deaths while it ran alone it is stored
    as ``crashed``; every other point is computed normally."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("[0.5, 1.5]", "[0.5]") + "[run]\nmax_attempts = 2\n")
    path = tmp_path / "s.h5"
    statuses = []
    for _ in range(5):
        p = forkserver.run(["run", cfg, "--store", path, "--compute",
                            "sweep.testing:crashing_point", "--no-bar"],
                           capture_output=True, text=True, timeout=120)
        statuses.append(p.returncode)
        if p.returncode == 0:
            break
    assert statuses == [3, 3, 3, 0], statuses  # died unseen, then twice alone, then done
    df = sweep.load(path).set_index("hash")
    assert len(df) == 4
    crashed = df[df["status"] == "crashed"]
    assert set(crashed["eps"]) == {0.4} and len(crashed) == 1
    assert all("max_attempts = 2" in m for m in crashed["message"])
    assert set(df[df["eps"] != 0.4]["status"]) == {"converged", "converged_noisy"}
    assert sweep.validate(path) == []
    s = run_campaign(parse_campaign(cfg.read_text()), str(path), compute=FAKE,
                     retry_failed=True)
    assert s.computed == 1 and set(sweep.load(path)["status"]) <= {"converged",
                                                                    "converged_noisy"}


def _handouts(path, run):
    """The hand-out lines of run ``run`` in the journal of store ``path``, in order."""
    lines = [decode(line)[0] for line in journal_path(path).read_bytes().splitlines(True)]
    return [o for o in lines if "handout" in o and o["run"] == run]


def test_every_unfinished_hand_out_is_a_suspect_after_a_kill(tmp_path):
    """A run killed with tasks at its workers: on resume every unfinished hand-out is
    computed alone (results are committed in groups: a task queued before the one that
    killed the run may have finished uncommitted, so the earliest unfinished hand-out of a
    worker need not be the one it was running); the others go out as any point does."""
    campaign = parse_campaign(TOML)
    path = tmp_path / "s.h5"
    pts = list(campaign.points())
    with Store(path, campaign) as st:  # run 0 dies: 3 tasks at worker 1, 2 at worker 2
        st.handout([(pts[0].hash, 1), (pts[1].hash, 2), (pts[2].hash, 1)])
        st.handout([(pts[3].hash, 2), (pts[4].hash, 1)])
    s = run_campaign(campaign, str(path), compute=FAKE)
    assert s.computed == len(pts)
    again = _handouts(path, 1)
    assert sorted(o["handout"] for o in again if o["alone"]) == sorted(
        p.hash for p in pts[:5])
    assert len(again) == len(pts) and sweep.validate(path) == []


def test_point_timeout_records_timeout(tmp_path):
    """[run] point_timeout: a point that loops (Python) or blocks (sleep) is stored as
    ``timeout`` and the campaign goes on; --point-timeout overrides it."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("[0.5, 1.5]", "[0.5]") + "[run]\npoint_timeout = 100.0\n")
    path = tmp_path / "s.h5"
    t0 = time.monotonic()
    assert main(["run", str(cfg), "--store", str(path), "--compute",
                 "sweep.testing:stuck_point", "--point-timeout", "0.5", "--no-bar"]) == 0
    assert time.monotonic() - t0 < 30
    df = sweep.load(path).set_index("eps")
    assert df.loc[0.4, "status"] == "timeout" and df.loc[0.6, "status"] == "timeout"
    assert "point_timeout = 0.5 s" in df.loc[0.4, "message"]
    assert df.loc[0.2, "status"] == "converged" and df.loc[0.8, "status"] != "timeout"
    assert sweep.validate(path) == []


def test_point_stuck_in_native_code_is_stored_timeout_in_one_run(tmp_path):
    """The hard limit: a point where no Python handler can run (the timeout signal blocked,
    as in native code). In-process a point with a timeout runs in a child process, killed
    a margin after point_timeout (issue 26: before, the whole process ended and the point
    needed max_attempts more runs to be stored crashed); one run stores it ``timeout``
    and the campaign completes."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("[0.5, 1.5]", "[0.5]").replace("0.6, 0.8", "0.6")
                   + "[run]\npoint_timeout = 0.5\nmax_attempts = 2\n")
    path = tmp_path / "s.h5"
    cmd = ["run", cfg, "--store", path, "--compute", "sweep.testing:native_stuck_point",
           "--no-bar"]
    env = dict(os.environ, SWEEP_CHILD_MARGIN="0.3")  # killed 0.3 s after its limit
    env.pop("SLURM_NTASKS", None)
    t0 = time.monotonic()
    proc = forkserver.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert time.monotonic() - t0 < 30
    df = sweep.load(path).set_index("eps")
    assert df.loc[0.4, "status"] == "timeout"
    assert "did not stop: its process was killed after 0.8 s" in df.loc[0.4, "message"]
    assert set(df.loc[[0.2, 0.6], "status"]) <= {"converged", "converged_noisy"}
    assert sweep.validate(path) == []


def test_merge_refuses_itself_and_other_versions_and_stops_with_6(tmp_path):
    cfg, path = _big(tmp_path)
    a = str(path)
    assert main(["merge", a, a]) == 3
    assert main(["merge", str(tmp_path / "out.h5"), a, a]) == 3
    old = tmp_path / "old.h5"
    old.write_bytes(path.read_bytes())
    with h5py.File(old, "r+", locking=False) as f:
        f.attrs["schema_version"] = 99  # newer than this sweep
    assert main(["merge", str(tmp_path / "out.h5"), str(old)]) == 3
    assert not (tmp_path / "out.h5").exists()
    statuses = []
    for k in range(2):
        out = tmp_path / f"merged{k}.h5"
        if k == 0:  # the stop lands in a fresh interpreter's imports
            p = subprocess.Popen([sys.executable, "-m", "sweep", "merge", str(out), a],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        else:  # in the merge itself
            p = forkserver.popen(["merge", out, a], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        while p.poll() is None and not catches_signal(p.pid, signal.SIGTERM):
            time.sleep(0.002)
        time.sleep(0.05 * k)
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=60)
        statuses.append(p.returncode)
        assert p.returncode in (0, 6), err
        if out.exists():
            assert sweep.validate(out) == []
            assert main(["merge", str(out), a]) == 0  # resumes
            assert table(out).equals(table(path))
    assert 6 in statuses, statuses


def test_status_counts_the_journal(tmp_path, campaign, capsys):
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    with h5py.File(path, "r+", locking=False) as f:  # the last points never reached it
        f["table"].attrs["n_rows"] = 5
    capsys.readouterr()
    assert main(["status", str(path), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert (rep["stored"], rep["journaled"]) == (5, 8)
    assert main(["status", str(path)]) == 0
    assert "journal holds 8 points: 3 more" in capsys.readouterr().out


def test_reads_during_writes(tmp_path):
    """sweep.load and status while a live run commits quickly: every read succeeds and
    sees a growing, duplicate-free table."""
    eps = ", ".join(repr(round(0.001 + 0.0009 * i, 5)) for i in range(500))
    cfg = tmp_path / "c.toml"
    cfg.write_text(f"[base]\nL_sheet = 6.0\n[sweep]\neps = [{eps}]\n")
    path = tmp_path / "s.h5"
    p = forkserver.popen(["run", cfg, "--store", path, "--compute",
                          "sweep.testing:sleepy_trivial_point", "--no-bar"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sizes = []
    try:
        deadline = time.monotonic() + 60
        while not path.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        while p.poll() is None and len(sizes) < 60:
            df = sweep.load(path)
            assert df["hash"].is_unique
            sizes.append(len(df))
    finally:
        p.wait(timeout=120)
    assert p.returncode == 0, p.stderr.read()
    assert len(sizes) >= 10 and sizes == sorted(sizes) and sizes[-1] > sizes[0]


def test_a_removed_journal_is_journaled_again_from_the_store(tmp_path, campaign, capsys):
    """The journal of a complete store removed, then a run killed: the rebuild must not
    lose the points only the file held (they are journaled again on open)."""
    path = tmp_path / "s.h5"
    run_campaign(campaign.shard(0, 2), str(path), compute=FAKE)
    journal_path(path).unlink()
    capsys.readouterr()
    with Store(path, campaign.shard(0, 2)) as store:
        n = len(store)
    assert "journaled again from the store" in capsys.readouterr().err
    make_unclean(path)  # as if the next run were killed
    s = run_campaign(campaign.shard(0, 2), str(path), compute="sweep.testing:raising_point")
    assert s.computed == 0 and len(sweep.load(path)) == n
    assert sweep.validate(path) == []


HUGE = "[sweep]\n" + "\n".join(
    f"{k} = [{', '.join(repr(round(v * (i + 1), 6)) for i in range(40))}]"
    for k, v in (("L_x", 0.1), ("T", 0.5), ("eps", 0.02), ("d_f", 0.001), ("C_sd", 0.01)))


@pytest.mark.parametrize("text,needle", [
    ("[base]\nL_sheet = 1e308\n[sweep]\neps = [0.2]\n", "out of range"),
    ("[base]\ndt = 1e-305\n[sweep]\neps = [0.2]\n", "out of range"),
    ("[base]\nL_sheet = 1e9\n[sweep]\neps = [0.2]\n", "floes, more than 1,000,000"),
    ("[base]\nL_sheet = 6.0\n[sweep]\nT = [1.2, 1.2000000001]\n", "the same point twice"),
    ("[base]\nL_sheet = 6.0\n[sweep]\n", "[sweep] is empty"),
    (HUGE, "102,400,000 points, more than [run] max_points"),
    ("[base]\nL_sheet = 6.0\n[sweep]\neps = " + "[" * 2000 + "]" * 2000 + "\n", "TOML"),
    (TOML + "[run]\ngrace_period = 1e300\n", "grace_period"),
    (TOML + "[run]\npoint_timeout = -1.0\n", "point_timeout"),
])
def test_hostile_campaigns_are_one_clear_config_error(text, needle):
    with pytest.raises(sweep.ConfigError) as info:
        parse_campaign(text, "h.toml")
    assert needle in str(info.value)
    assert len(str(info.value).splitlines()) == 1
