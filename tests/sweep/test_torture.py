"""Torture test (issue 4): ``kill -9`` of a whole real ``mpiexec`` campaign at random moments.

A small real campaign (``floewave.run_point``) runs under ``mpiexec -n 3`` in its own
process group, which is killed with SIGKILL (master, workers, launcher) at random moments
and resumed each time with the same command, with no cleanup in between; afterwards it
runs to completion. The end must equal an uninterrupted run of the same campaign point by
point: the same hashes, each once in the table and once in the journal, every result
column and every profile array exactly equal, ``sweep validate`` clean.

Run with ``pytest -s`` to see the summary line. Larger runs by hand, from the repository's
root (``configs/demo.toml``, ``mpiexec -n 2``, 25 kills by default; exit status 0 when the
end equals the uninterrupted run)::

    python -m tests.sweep.test_torture
    python -m tests.sweep.test_torture --kills 40 --ranks 3 --config configs/demo.toml --seed 3
"""
from __future__ import annotations

import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

import sweep
from sweep.errors import BadJournalLineError
from sweep.store.journal import decode, journal_path
from sweep.store.lock import lock_path
from sweep.store.reader import read_journal
from sweep.store.schema import COLUMNS, HISTORY_VAR, PROFILE_VARS, REPLICA_VARS
from sweep.testing import SMALL_REAL_BASE, find_mpiexec

MPIEXEC = find_mpiexec()

#: 24 real points of ~0.1-0.4 s each (4 or 8 floes of a 24 m sheet, 1 + 1 periods per
#: iteration, at most 10 iterations): ~6 s under ``mpiexec -n 3`` on 2 cores, start-up
#: (imports, numba cache) ~2 s of it.
TORTURE_TOML = SMALL_REAL_BASE + """
[sweep]
L_x = [3.0, 1.5]
T = [1.2, 1.6]
eps = [0.2, 0.4, 0.6]
dispersion = ["ml", "ep"]

[run]
name = "torture"
progress_interval = 1.0
grace_period = 5.0
# kill -9 from outside while a point runs alone cannot be told apart from the point
# killing its worker: with many kills an innocent point could reach max_attempts and be
# stored as crashed (tests/sweep/torture_store.py counts how often with the default)
max_attempts = 0
"""

#: Table columns that describe how/where/when a point ran, not what it is or gave.
BOOKKEEPING = {"host", "rank", "pid", "start_time", "end_time", "wall_time",
               "model_wall_time", "run", "seq", "provenance"}


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("SLURM_NTASKS", None)
    return env


def _command(config: Path, store: Path, n_ranks: int) -> list[str]:
    cmd = [sys.executable, "-m", "sweep", "run", str(config), "--store", str(store),
           "--no-bar"]
    return [MPIEXEC, "-n", str(n_ranks), *cmd] if n_ranks > 1 else cmd


def _group_gone(pgid: int, timeout: float = 10.0) -> bool:
    """Wait until no live (non-zombie) process of group ``pgid`` is left."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        alive = []
        for d in os.listdir("/proc"):
            if not d.isdigit():
                continue
            try:
                stat = Path(f"/proc/{d}/stat").read_text()
            except OSError:
                continue
            fields = stat.rsplit(")", 1)[1].split()
            if int(fields[2]) == pgid and fields[0] != "Z":
                alive.append(int(d))
        if not alive:
            return True
        time.sleep(0.05)
    return False


def _probe(store: Path) -> str:
    """The state a killed run left the store in: absent, clean, unclean or unreadable."""
    if not store.exists():
        return "absent"
    try:
        with h5py.File(store, "r", locking=False) as f:
            int(f["table"].attrs["n_rows"])
            return "unclean" if bool(f.attrs.get("writer_open", False)) else "clean"
    except Exception:  # noqa: BLE001 - any failure to open or read counts
        return "unreadable"


def _journal(store: Path) -> tuple[list[str], int, bool]:
    """(hashes of the complete point records, lines failing their checksum or not
    parsing, torn tail)."""
    path = journal_path(store)
    if not path.exists():
        return [], 0, False
    data = path.read_bytes()
    hashes, bad = [], 0
    lines = data.split(b"\n")
    for line in lines[:-1]:
        try:
            obj, _ = decode(line, require_checksum=False)
        except BadJournalLineError:
            bad += 1
            continue
        if "row" in obj:  # a point record (not a campaign, hand-out or release line)
            hashes.append(obj["row"]["hash"])
    return hashes, bad, lines[-1] != b""


def _table(store: Path) -> tuple[dict[str, dict[str, Any]], Counter]:
    """Per hash: the row's columns; and the number of rows per hash."""
    with h5py.File(store, "r", locking=False) as f:
        t = f["table"]
        n = int(t.attrs["n_rows"])
        cols = {c.name: t[c.name][:n] for c in COLUMNS if c.name in t}
    decode = lambda v: v.decode() if isinstance(v, bytes) else v  # noqa: E731
    hashes = [decode(h) for h in cols["hash"]]
    rows = {h: {k: decode(v[i]) for k, v in cols.items()} for i, h in enumerate(hashes)}
    return rows, Counter(hashes)


def compare(ref: Path, store: Path) -> dict[str, Any]:
    """Compare a store with the reference per hash; returns the figures and problems."""
    problems: list[str] = []
    a, _ = _table(ref)
    b, counts = _table(store)
    dup_table = sum(c - 1 for c in counts.values())
    jcounts = Counter(rec["row"]["hash"] for rec in read_journal(journal_path(store)))
    dup_journal = sum(c - 1 for c in jcounts.values())
    _, bad_lines, torn = _journal(store)
    if set(a) != set(b):
        problems.append(f"hashes differ: missing {sorted(set(a) - set(b))[:3]},"
                        f" extra {sorted(set(b) - set(a))[:3]}")
    if set(jcounts) != set(b):
        problems.append("journal and table hold different points")
    if dup_table or dup_journal:
        problems.append(f"duplicates: {dup_table} in the table, {dup_journal} in the journal")
    if bad_lines or torn:
        problems.append(f"journal damage: {bad_lines} unparseable lines, torn tail {torn}")
    compared = 0
    with h5py.File(ref, "r", locking=False) as fa, h5py.File(store, "r", locking=False) as fb:
        for h in sorted(set(a) & set(b)):
            for col in COLUMNS:
                if col.name in BOOKKEEPING:
                    continue
                x, y = a[h].get(col.name), b[h].get(col.name)
                same = (x == y) or (isinstance(x, float) and np.isnan(x) and np.isnan(y))
                if not same:
                    problems.append(f"{h[:12]} {col.name}: {x!r} != {y!r}")
            name = f"profiles/{h[:2]}/{h}"
            if (name in fa) != (name in fb):
                problems.append(f"{h[:12]}: profile group present in only one store")
                continue
            if name in fa:
                for var in (*PROFILE_VARS, *REPLICA_VARS, HISTORY_VAR[0]):
                    if var not in fa[name] and var not in fb[name]:
                        continue  # optional (the per-replica profiles of schema 3)
                    if (var in fa[name]) != (var in fb[name]):
                        problems.append(f"{h[:12]} profile {var} in only one store")
                        continue
                    x, y = fa[name][var][()], fb[name][var][()]
                    if x.shape != y.shape or not np.array_equal(x, y, equal_nan=True):
                        problems.append(f"{h[:12]} profile {var} differs")
            compared += 1
    problems += [f"validate: {p}" for p in sweep.validate(store)]
    return {"points": len(b), "compared": compared, "dup_table": dup_table,
            "dup_journal": dup_journal, "problems": problems}


def torture(config: Path, workdir: Path, *, kills: int = 10, n_ranks: int = 3, seed: int = 1,
            min_delay: float = 0.3, log: Any = print, run_timeout: float = 300.0
            ) -> dict[str, Any]:
    """Kill -9 the campaign ``config`` at ``kills`` random moments while it runs, resume
    each time, finish; compare with an uninterrupted run. Returns the figures.

    A kill counts (``kills``) only if it hit a running ``sweep run`` while the campaign
    was incomplete. Each kill is at a uniform random delay after launch between
    ``min_delay`` and the time the uninterrupted run needs for the points still missing
    (start-up included), so kills hit start-up, computation, commits and the close. If
    the campaign completes before enough kills, it is verified and started again from an
    empty store (a new round).
    """
    workdir.mkdir(parents=True, exist_ok=True)
    ref = workdir / "reference.h5"
    rng = random.Random(seed)
    n_total = len(sweep.load_campaign(config).points())

    def launch(store: Path, i: int) -> subprocess.Popen:
        with open(workdir / f"run-{i:03d}.log", "w") as out:
            return subprocess.Popen(_command(config, store, n_ranks), stdout=out,
                                    stderr=subprocess.STDOUT, env=_env(),
                                    start_new_session=True)

    def finish(store: Path, i: int) -> float:
        t0 = time.monotonic()
        p = launch(store, i)
        try:
            rc = p.wait(timeout=run_timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            raise AssertionError(f"run {i} hung (> {run_timeout} s); see run-{i:03d}.log") from None
        assert rc == 0, (rc, (workdir / f"run-{i:03d}.log").read_text()[-3000:])
        return time.monotonic() - t0

    t_ref = finish(ref, 0)
    t_start = finish(ref, 1)  # a resume with nothing to do: start-up and close only
    log(f"reference: {n_total} points in {t_ref:.2f} s (start-up and close {t_start:.2f} s)")
    assert len(sweep.load(ref)) == n_total

    fig: dict[str, Any] = {"kills": 0, "late_kills": 0, "runs": 0, "rounds": 0,
                           "states": Counter(), "stale_locks": 0, "takeovers_checked": 0,
                           "compared": 0, "dup_table": 0, "dup_journal": 0,
                           "problems": [], "orphans": 0, "corrupt_aside": 0}
    i = 2
    while fig["kills"] < kills or fig["rounds"] == 0:
        fig["rounds"] += 1
        store = workdir / f"round{fig['rounds']}.h5"
        seen: set[str] = set()  # hashes the journal held after the previous kill
        lock_left = False
        while True:
            hashes, bad, _ = _journal(store)
            missing = n_total - len(set(hashes))
            if bad:
                fig["problems"].append(f"round {fig['rounds']} run {i}: {bad} unparseable"
                                       " journal lines")
            if not seen <= set(hashes):
                fig["problems"].append(f"run {i}: journal lost records")
            seen = set(hashes)
            if fig["kills"] >= kills or missing == 0:
                break
            bound = t_start + (t_ref - t_start) * missing / n_total
            delay = rng.uniform(min_delay, max(bound, min_delay + 0.1))
            p = launch(store, i)
            fig["runs"] += 1
            try:
                rc = p.wait(timeout=delay)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                if not _group_gone(p.pid):
                    fig["orphans"] += 1
                    fig["problems"].append(f"run {i}: processes survived killpg")
                state = _probe(store)
                lock_left = lock_path(store).exists()
                done = n_total - len(set(_journal(store)[0])) == 0
                if state == "clean" and done and not lock_left:
                    fig["late_kills"] += 1  # the master had finished and closed the store
                    log(f"late kill at {delay:5.2f} s (run {i}): campaign already complete")
                else:
                    fig["kills"] += 1
                    fig["states"][state] += 1
                    fig["stale_locks"] += lock_left
                    log(f"kill {fig['kills']:3d} at {delay:5.2f} s (run {i}, {missing} points"
                        f" missing before it): store {state}, stale lock {lock_left}")
            else:
                log_text = (workdir / f"run-{i:03d}.log").read_text()
                if rc != 0:  # refused (lock not taken over, unreadable store ...) or crashed
                    fig["problems"].append(f"run {i} exited {rc}: {log_text[-2000:]}")
                    break
                fig["late_kills"] += 1
                lock_left = False
            i += 1
        # run to completion; the stale lock of the last kill must be taken over
        finish(store, i)
        fig["runs"] += 1
        if lock_left:
            with h5py.File(store, "r", locking=False) as f:
                last = f["runs"][str(len(f["runs"]) - 1)]
                fig["takeovers_checked"] += 1
                if "took_over_stale_lock" not in last.attrs:
                    fig["problems"].append(f"run {i}: stale lock not recorded as taken over")
        i += 1
        fig["corrupt_aside"] += len(list(workdir.glob(f"{store.name}.corrupt-*")))
        res = compare(ref, store)
        fig["compared"] += res["compared"]
        fig["dup_table"] += res["dup_table"]
        fig["dup_journal"] += res["dup_journal"]
        fig["problems"] += [f"round {fig['rounds']}: {p}" for p in res["problems"]]
        if fig["problems"]:
            break
    fig["repaired"] = fig["states"]["unclean"] + fig["states"]["unreadable"]
    fig["summary"] = (
        f"torture: {fig['kills']} kill -9 survived ({fig['late_kills']} more arrived after"
        f" completion), {fig['runs']} runs in {fig['rounds']} round(s), {fig['compared']}"
        f" points compared exactly with the uninterrupted run, duplicates"
        f" {fig['dup_table']} (table) / {fig['dup_journal']} (journal); store after a kill:"
        f" {dict(fig['states'])}; unreadable (rebuilt from the journal)"
        f" {fig['states']['unreadable']}, unclean (rebuilt from the journal)"
        f" {fig['states']['unclean']}; stale locks taken over {fig['stale_locks']};"
        f" surviving processes {fig['orphans']}; problems {len(fig['problems'])}")
    return fig


@pytest.mark.slow  # fast: tests/sweep/test_store.py::test_kill_9_torture, test_mpi.py
@pytest.mark.skipif(MPIEXEC is None, reason="no mpiexec (pip install mpich)")
def test_kill_9_whole_mpi_campaign_torture(tmp_path, compiled_kernels):
    config = tmp_path / "torture.toml"
    config.write_text(TORTURE_TOML)
    fig = torture(config, tmp_path, kills=10, n_ranks=3, seed=20261122)
    print("\n" + fig["summary"])
    assert not fig["problems"], "\n".join(fig["problems"][:20])
    assert fig["kills"] >= 10
    assert fig["compared"] >= 24 and fig["dup_table"] == 0 and fig["dup_journal"] == 0
    assert fig["orphans"] == 0


_TORN_SCRIPT = """
import os, signal, sys
import sweep
from sweep.store.journal import journal_path
from sweep.store.store import Store
from sweep.testing import fake_point
campaign = sweep.parse_campaign({toml!r})
p = campaign.points()[int(sys.argv[1])]
out = fake_point(p.config)
store = Store({path!r}, campaign)
store.put({{"row": {{"hash": p.hash, "status": "converged", "W_c": out["W_c"],
                    "eps": p.config.eps, "n_floes": p.config.n_floes}},
           "profiles": {{k: v for k, v in out.items() if k in sweep.store.schema.PROFILE_VARS}},
           "residual_history": out["residual_history"]}})
print("acknowledged", p.hash, flush=True)
if sys.argv[2] == "tear":  # as if killed inside the next commit's journal write
    with open(journal_path({path!r}), "ab") as fh:
        fh.write(b'{{"row":{{"hash":"0123')
os.kill(os.getpid(), signal.SIGKILL)
"""


def test_torn_journal_tail_does_not_swallow_the_next_point(tmp_path):
    """Regression: a master killed inside its journal write leaves a torn last line; the
    next run's first record used to be appended to it, unreadable, and so lost when a
    later kill made the store be rebuilt from the journal."""
    toml = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4, 0.6]\n"
    path = tmp_path / "s.h5"
    script = _TORN_SCRIPT.format(toml=toml, path=str(path))
    acked = []
    for index, how in ((0, "tear"), (1, "die")):
        proc = subprocess.run([sys.executable, "-c", script, str(index), how],
                              capture_output=True, text=True)
        assert proc.returncode == -signal.SIGKILL, proc.stderr
        acked.append(proc.stdout.split()[1])
    hashes, bad, torn = _journal(path)
    assert hashes == acked and bad == 0 and not torn
    campaign = sweep.parse_campaign(toml)
    from sweep.store.store import Store
    with Store(path, campaign) as store:
        assert store.repaired_from_journal
        assert set(store.rows) == set(acked), "an acknowledged point was lost"
    assert sweep.validate(path) == []


def main(argv: list[str] | None = None) -> int:
    """:func:`torture` of a campaign by hand (the module docstring)."""
    root = Path(__file__).resolve().parents[2]
    ap = argparse.ArgumentParser(description="kill -9 torture of a real MPI campaign")
    ap.add_argument("--config", type=Path, default=root / "configs" / "demo.toml")
    ap.add_argument("--kills", type=int, default=25)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--seed", type=int, default=25)
    ap.add_argument("--workdir", type=Path, help="keep stores and logs here (default: a"
                    " temporary directory, removed unless the torture fails)")
    args = ap.parse_args(argv)
    if args.ranks > 1 and MPIEXEC is None:
        print("no mpiexec (pip install mpich)", file=sys.stderr)
        return 2
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="sweep-torture-"))
    t0 = time.monotonic()
    fig = torture(args.config.resolve(), workdir, kills=args.kills, n_ranks=args.ranks,
                  seed=args.seed, log=lambda s: print(s, flush=True))
    print(fig["summary"])
    print(f"elapsed {time.monotonic() - t0:.0f} s; work directory {workdir}")
    for p in fig["problems"]:
        print("PROBLEM:", p)
    if fig["problems"]:
        return 1
    if args.workdir is None:
        shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
