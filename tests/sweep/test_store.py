"""The store: lock, schema version, repair after a crash, journal rebuild, merge, schema."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import sweep
import sweep.testing
from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.store.document import schema_document
from sweep.store.schema import SCHEMA_VERSION
from sweep.store.store import Store
from tests import forkserver
from tests.sweep.helpers import store_holder

ROOT = Path(__file__).resolve().parents[2]
TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6]\n"


def fill(campaign, path, compute="sweep.testing:fake_point"):
    return run_campaign(campaign, str(path), compute=compute)


def test_schema_file_matches_code():
    doc = json.loads((ROOT / "results_schema" / f"schema_v{SCHEMA_VERSION}.json").read_text())
    assert doc == json.loads(json.dumps(schema_document()))


def test_second_writer_refused_stale_lock_taken_over(tmp_path, campaign, run_main, refused_at_once):
    path = tmp_path / "s.h5"
    with Store(path, campaign):
        with pytest.raises(sweep.StoreLockedError, match="live campaign"):
            Store(path, campaign)
        cfg = tmp_path / "c.toml"
        cfg.write_text(TOML)
        proc = run_main(main, ["run", cfg, "--store", path])  # the command line's refusal
        assert proc.returncode == 3 and "live campaign" in proc.stderr
    # a lock left by a killed writer: the file exists but nobody holds its flock
    holder = store_holder(path, TOML)
    os.kill(holder.pid, signal.SIGKILL)
    holder.wait()
    assert (tmp_path / "s.h5.lock").exists()
    s = fill(campaign, path)
    assert s.computed == 6
    with h5py.File(path, "r") as f:
        assert "took_over_stale_lock" in f["runs"][str(len(f["runs"]) - 1)].attrs


def test_newer_schema_refused(tmp_path, campaign):
    path = tmp_path / "s.h5"
    fill(campaign, path)
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = 99
    with pytest.raises(sweep.SchemaVersionError, match=f"99.*newer.*{SCHEMA_VERSION}"):
        fill(campaign, path)
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    assert main(["run", str(cfg), "--store", str(path)]) == 3


def test_schema_v1_store_read_as_is_and_migrated_by_a_writer(tmp_path, campaign):
    """A version-1 store (no compact-zone columns) loads with fill values and is migrated
    (columns added, values kept) when a writer opens it."""
    path = tmp_path / "s.h5"
    fill(campaign, path)
    before = sweep.load(path)
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = 1
        for name in ("compact_zone", "compact_end", "ice_extent"):
            del f["table"][name]
    old = sweep.load(path)
    assert sweep.validate(path) == []                  # readable as it is
    assert (old["compact_zone"] == "").all() and old["ice_extent"].isna().all()
    pd_cols = ["hash", "W_c", "alpha_inner", "status"]
    assert old[pd_cols].equals(before[pd_cols])
    other = parse_campaign(TOML.replace("0.6]", "0.8]"), "other.toml")
    with pytest.raises(sweep.SweepError):
        fill(other, path)                              # refused: left as it was
    with h5py.File(path, "r") as f:
        assert int(f.attrs["schema_version"]) == 1 and "compact_zone" not in f["table"]
    fill(campaign, path)                               # a writer opens it: migrated
    with h5py.File(path, "r") as f:
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION
    assert sweep.validate(path) == []
    new = sweep.load(path)
    assert new[pd_cols].equals(before[pd_cols]) and (new["compact_zone"] == "").all()


def test_other_campaign_refused(tmp_path, campaign):
    path = tmp_path / "s.h5"
    fill(campaign, path)
    other = parse_campaign(TOML.replace("L_sheet = 6.0", "L_sheet = 9.0"))
    with pytest.raises(sweep.CampaignMismatchError, match="L_sheet"):
        fill(other, path)
    with pytest.raises(sweep.CampaignMismatchError, match="base"):
        run_campaign(other, str(path), compute="sweep.testing:fake_point", extend=True)
    fewer = parse_campaign(TOML.replace("[0.2, 0.4, 0.6]", "[0.2]"))
    with pytest.raises(sweep.CampaignMismatchError, match="drops"):
        run_campaign(fewer, str(path), compute="sweep.testing:fake_point", extend=True)
    # comments and [run] options do not make another campaign
    same = parse_campaign("# note\n" + TOML + "[run]\ngrace_period = 3.0\n")
    assert fill(same, path).skipped == 6


def test_uncommitted_rows_and_orphans_removed(tmp_path, campaign):
    path = tmp_path / "s.h5"
    fill(campaign, path)
    os.unlink(tmp_path / "s.h5.journal")
    with h5py.File(path, "r+") as f:  # simulate a crash after a row write, before commit
        t = f["table"]
        t.attrs["n_rows"] = 4
        f.create_group("profiles/zz/" + "f" * 64)
    s = fill(campaign, path)
    assert s.computed == 2 and s.skipped == 4
    df = sweep.load(path)
    assert len(df) == 6 and df["hash"].is_unique
    assert sweep.validate(path) == []
    with h5py.File(path, "r") as f:
        assert "f" * 64 not in f["profiles/zz"]


def test_journal_replays_points_missing_from_file(tmp_path, campaign):
    path = tmp_path / "s.h5"
    fill(campaign, path)
    ref = sweep.load(path).set_index("hash").sort_index()
    with h5py.File(path, "r+") as f:  # the last two puts never reached the file
        f["table"].attrs["n_rows"] = 4
    s = run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    assert s.computed == 0 and s.skipped == 6
    df = sweep.load(path).set_index("hash").sort_index()
    assert list(df.index) == list(ref.index)
    assert list(df["W_c"]) == list(ref["W_c"])


def test_unreadable_store_rebuilt_from_journal(tmp_path, campaign):
    path = tmp_path / "s.h5"
    fill(campaign, path)
    ref = sweep.load(path).set_index("hash").sort_index()
    with open(path, "r+b") as fh:  # destroy the superblock after the HDF5 signature
        fh.seek(8)
        fh.write(b"\0" * 4088)
    with open(tmp_path / "s.h5.journal", "ab") as fh:  # and a torn last journal line
        fh.write(b'{"row": {"hash": "abc"')
    s = run_campaign(campaign, str(path), compute="sweep.testing:raising_point")
    assert s.computed == 0
    df = sweep.load(path).set_index("hash").sort_index()
    assert list(df.index) == list(ref.index)
    assert list(df["W_c"]) == list(ref["W_c"])
    kept = list(tmp_path.glob("s.h5.damaged-*"))
    assert len(kept) == 1 and kept[0].read_bytes()[8:4096] == b"\0" * 4088
    assert sweep.validate(path) == []


def test_unreadable_store_without_journal(tmp_path, campaign):
    path = tmp_path / "s.h5"
    path.write_bytes(b"not hdf5")
    with pytest.raises(sweep.StoreError, match="not an HDF5 file; it was left untouched"):
        fill(campaign, path)
    assert path.read_bytes() == b"not hdf5"
    assert main(["validate", str(path)]) == 3
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 2000)  # HDF5, damaged, no journal
    with pytest.raises(sweep.StoreError, match="no journal"):
        fill(campaign, path)
    assert path.read_bytes()[8:] == b"\0" * 2000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5"]


def test_store_in_missing_directory(tmp_path, campaign):
    with pytest.raises(sweep.StoreError, match="does not exist"):
        fill(campaign, tmp_path / "nope" / "s.h5")


def test_merge_shards(tmp_path, campaign):
    paths = []
    for k in range(3):
        p = tmp_path / f"shard{k}.h5"
        fill(campaign.shard(k, 3), p, "sweep.testing:raising_point")
        paths.append(p)
    fill(campaign.shard(0, 3), tmp_path / "dup.h5")
    out = tmp_path / "all.h5"
    assert main(["merge", str(out), *map(str, paths), str(tmp_path / "dup.h5")]) == 0
    df = sweep.load(out)
    assert len(df) == 6 and df["hash"].is_unique
    assert set(df["hash"]) == {p.hash for p in campaign.points()}
    assert sweep.validate(out) == []
    other = parse_campaign(TOML.replace("6.0", "9.0"))
    fill(other, tmp_path / "other.h5")
    assert main(["merge", str(tmp_path / "x.h5"), str(paths[0]),
                 str(tmp_path / "other.h5")]) == 3
    assert not (tmp_path / "x.h5").exists()


def test_kill_9_torture(tmp_path, campaign):
    """kill -9 the in-process campaign at random moments; the end equals a clean run.
    (The campaigns are ``python -m sweep run`` forked by an interpreter that imported
    sweep once (tests/forkserver.py), so that every kill falls in the campaign's own life:
    store open, points, commits; without the guard, so that the kill is the campaign's
    own.)"""
    import random

    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML.replace("[0.2, 0.4, 0.6]", "[0.2, 0.4, 0.6, 0.8]").replace(
        "[0.5, 1.5]", "[0.5, 1.0, 1.5, 3.0]"))
    ref, path = tmp_path / "ref.h5", tmp_path / "s.h5"
    args = ["--compute", "sweep.testing:fake_point", "--no-bar"]

    def start(store):
        return forkserver.popen(["run", cfg, "--store", store, *args],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                env=dict(os.environ, SWEEP_NO_GUARD="1"))

    forkserver.prestart(wait=True)
    t0 = time.monotonic()
    assert start(ref).wait(timeout=120) == 0
    whole = time.monotonic() - t0  # an uninterrupted run: the kills fall within its length
    rng = random.Random(7)
    kills = 0
    for _ in range(10):
        run = start(path)
        time.sleep(rng.uniform(0.0, 1.0) * whole)
        run.kill()
        kills += run.wait(timeout=120) == -signal.SIGKILL
    proc = forkserver.run(["run", cfg, "--store", path, *args], capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr
    assert kills >= 5
    a = sweep.load(ref).set_index("hash").sort_index()
    b = sweep.load(path).set_index("hash").sort_index()
    assert b.index.is_unique and list(a.index) == list(b.index)
    for col in ("W_c", "alpha_all", "status", "a_end"):
        assert list(a[col]) == list(b[col])
    assert sweep.validate(path) == []


# ---------------------------------------------------------------- group commit durability
_GROUP_SCRIPT = """
import os, signal, sys
import sweep
from sweep.store.journal import Journal, journal_path
from sweep.store.store import Store
from sweep.testing import fake_point
campaign = sweep.parse_campaign({toml!r})
points = campaign.points()
kill_at = {kill_at!r}

def record(p, seq):
    out = fake_point(p.config)
    prof = {{k: v for k, v in out.items() if k in sweep.store.schema.PROFILE_VARS}}
    return {{"row": {{"hash": p.hash, "status": "converged", "W_c": out["W_c"],
                     "L_x": p.config.L_x, "eps": p.config.eps,
                     "n_floes": p.config.n_floes}},
             "profiles": prof, "residual_history": out["residual_history"]}}

class DyingJournal(Journal):  # dies inside the second commit, before its journal write
    armed = False
    def append(self, lines, sync=True):
        if DyingJournal.armed and any(b'"row"' in line for line in lines):
            os.kill(os.getpid(), signal.SIGKILL)
        super().append(lines, sync)
store = Store({path!r}, campaign, journal=DyingJournal(journal_path({path!r})))
if kill_at == "mid_hdf5":  # die inside the second commit, after its journal fsync
    real = store.w.write_many
    def write_many(records):
        if len(records) > 1:  # the second batch: half of it reaches the file
            real(records[:len(records) // 2])
            os.kill(os.getpid(), signal.SIGKILL)
        real(records)
    store.w.write_many = write_many
for p in points[:{first}]:
    store.add(record(p, 0))
assert len(store) == 0 and store.staged == {first}
store.commit()
print("acknowledged", " ".join(p.hash for p in points[:{first}]), flush=True)
for p in points[{first}:]:
    store.add(record(p, 0))
if kill_at == "before_journal":
    DyingJournal.armed = True
store.commit()
print("acknowledged", " ".join(p.hash for p in points[{first}:]), flush=True)
os.kill(os.getpid(), signal.SIGKILL)  # never closed cleanly
"""

GROUP_TOML = ("[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.0, 1.5]\n"
              "eps = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]\n")


@pytest.mark.parametrize("kill_at", ["mid_hdf5", "before_journal", "after_commit"])
def test_group_commit_survives_kill_9(tmp_path, kill_at):
    """Points acknowledged by one group commit survive kill -9 (inside the next commit,
    or after it) exactly once, with their data; the batch being committed when the
    process died is wholly present (journal written) or wholly absent (not written)."""
    campaign = parse_campaign(GROUP_TOML)
    points = campaign.points()
    first = 1  # a first batch smaller than the journal's write buffer (4 KiB here)
    path = tmp_path / "s.h5"
    script = _GROUP_SCRIPT.format(toml=GROUP_TOML, path=str(path), kill_at=kill_at,
                                  first=first)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    acked = [line.split()[1:] for line in proc.stdout.splitlines()
             if line.startswith("acknowledged")]
    assert len(acked) == (2 if kill_at == "after_commit" else 1)
    acknowledged = [h for batch in acked for h in batch]
    with Store(path, campaign) as store:  # recovery: rebuild from the journal
        assert store.repaired_from_journal
        stored = set(store.rows)
    df = sweep.load(path)
    assert df["hash"].is_unique
    assert set(acknowledged) <= set(df["hash"]), "an acknowledged point was lost"
    second = {p.hash for p in points[first:]}
    if kill_at == "before_journal":
        assert stored == {p.hash for p in points[:first]}
    else:  # the second batch reached the journal: wholly present
        assert stored == {p.hash for p in points}
    assert sweep.validate(path) == []
    by_hash = df.set_index("hash")
    for p in points:
        if p.hash in stored:
            expected = sweep.testing.fake_point(p.config)
            assert by_hash.loc[p.hash, "W_c"] == expected["W_c"]
            np.testing.assert_array_equal(sweep.load_profile(path, p.hash)["a"].values,
                                          expected["a"])
    assert len(second & stored) in (0, len(second))


_MASTER_SCRIPT = """
import os, signal, sys
import sweep
from sweep.run.master import Master, RunSummary
from sweep.run.signals import StopSignals
from sweep.run.sink import InlineSink
from sweep.run.transport import InProcessTransport
from sweep.store.store import Store
campaign = sweep.parse_campaign({toml!r})
todo = campaign.points()
store = Store({path!r}, campaign)
commits = []
real_commit = store.commit
def commit():
    commits.append(store.staged)
    return real_commit()
store.commit = commit

class Progress:  # counts acknowledged points; dies at the {kill_after}th
    done = 0
    def tick(self):
        pass
    def update(self, status):
        Progress.done += 1
        if Progress.done == {kill_after}:
            print("acknowledged", Progress.done, "commits", *commits, flush=True)
            os.kill(os.getpid(), signal.SIGKILL)

transport = InProcessTransport("sweep.testing:trivial_point")
master = Master(InlineSink(store, transport.worker_env), transport)
with StopSignals(5.0, in_process=True) as signals:
    master.run(todo, Progress(), signals, RunSummary())
"""


def test_master_acknowledges_only_committed_batches(tmp_path):
    """kill -9 of the in-process master right after it counted point k as stored (in
    the middle of a batch's acknowledgements): the first k points of the schedule are
    in the store, once each; commits were grouped (fewer commits than points)."""
    n_eps = 150
    eps = ", ".join(repr(round(0.005 + i * 0.006, 6)) for i in range(n_eps))
    toml = f"[base]\nL_sheet = 6.0\n[sweep]\neps = [{eps}]\n"
    campaign = parse_campaign(toml)
    path = tmp_path / "s.h5"
    kill_after = 100
    script = _MASTER_SCRIPT.format(toml=toml, path=str(path), kill_after=kill_after)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    line = proc.stdout.split()
    assert line[:2] == ["acknowledged", str(kill_after)], proc.stdout
    commits = [int(c) for c in line[3:]]
    assert sum(commits) >= kill_after and len(commits) < kill_after / 4, commits
    order = sorted(campaign.points(), key=lambda p: (-p.cost, p.index))
    acknowledged = {p.hash for p in order[:kill_after]}
    with Store(path, campaign):
        pass  # recovery on open
    df = sweep.load(path)
    assert df["hash"].is_unique
    assert acknowledged <= set(df["hash"]), "an acknowledged point was lost"
    assert sweep.validate(path) == []
    # the resumed campaign completes without duplicates
    s = run_campaign(campaign, str(path), compute="sweep.testing:trivial_point")
    assert s.skipped + s.computed == n_eps
    df = sweep.load(path)
    assert len(df) == n_eps and df["hash"].is_unique
