"""Torture of the store (issue 15): kills at random instants of run, resume-rebuild,
retry, extend and merge; journal corruptions; compute faults; stops during start-up;
reads during writes; hostile inputs. Prints one table.

    python -m tests.sweep.torture_store                  # ~200 kills, a few minutes
    python -m tests.sweep.torture_store --kills 40 --seed 3 --workdir /tmp/t

(from the repository's root). ``test_store_torture`` runs it
small in the slow tier (``tests/sweep/test_torture_store.py``).

Every phase ends by running the same command to completion and comparing the store,
point by point, with an uninterrupted reference (hashes, every result column, every
profile array; duplicates in table and journal; ``sweep validate``), using
:func:`compare` of tests/sweep/test_torture.py. A store is *ruined* when the command
that should finish it does not exit 0. Compute functions are the deterministic fakes of
:mod:`sweep.testing` (the store is what is tortured, not the model).
"""
from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import h5py
import numpy as np

import sweep
from sweep.analysis.load import journal_points
from sweep.store.journal import decode, encode, journal_path
from sweep.testing import catches_signal
from tests.sweep.test_torture import MPIEXEC, compare

PY = sys.executable
EPS = ", ".join(repr(round(0.05 + 0.05 * i, 2)) for i in range(18))
SMALL = f"[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [{EPS}]\n"
BIG = SMALL.replace("[0.5, 1.5]", "[0.5, 1.0, 1.5]")
SLEEPY = "sweep.testing:sleepy_point"  # 0.2 s a point: runs long enough to be hit
FAKE = "sweep.testing:fake_point"


def env() -> dict[str, str]:
    e = dict(os.environ)
    e.pop("SLURM_NTASKS", None)
    return e


class Tally:
    def __init__(self) -> None:
        self.rows: dict[str, Counter] = {}

    def add(self, phase: str, **kw: int) -> None:
        c = self.rows.setdefault(phase, Counter())
        for k, v in kw.items():
            c[k] += int(v)

    def table(self) -> str:
        cols = ["cases", "kills", "ruined", "lost", "duplicated", "wrong", "traceback"]
        lines = ["| phase | " + " | ".join(cols) + " |",
                 "|---|" + "---|" * len(cols)]
        total = Counter()
        for phase, c in self.rows.items():
            total.update(c)
            lines.append(f"| {phase} | " + " | ".join(str(c.get(k, 0)) for k in cols) + " |")
        lines.append("| **total** | " + " | ".join(str(total.get(k, 0)) for k in cols) + " |")
        return "\n".join(lines)


def run_cmd(args: list[str], mpi: int = 0, **kw) -> subprocess.Popen:
    cmd = [PY, "-m", "sweep", *args]
    if mpi:
        cmd = [MPIEXEC, "-n", str(mpi), *cmd]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env(), start_new_session=True, **kw)


def finish(args: list[str], mpi: int = 0, timeout: float = 600) -> tuple[int, str]:
    p = run_cmd(args, mpi)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        return -999, "hung\n" + err
    return p.returncode, out + err


def judge(tally: Tally, phase: str, ref: Path, store: Path, rc: int, log: str,
          problems: list[str], history: bool = False) -> None:
    """Compare a finished store with the reference; ``history``: the journal may hold
    several records of a point (--retry-failed, set-aside lines)."""
    if rc != 0:
        tally.add(phase, ruined=1)
        problems.append(f"{phase}: finishing run exited {rc}: {log[-600:]}")
        return
    tally.add(phase, traceback=("Traceback" in log))
    res = compare(ref, store)
    a = set(sweep.load(ref)["hash"])
    b = set(sweep.load(store)["hash"])
    wrong = {p.split()[0] for p in res["problems"] if not p.startswith(("hashes", "journal",
                                                                         "duplicates",
                                                                         "validate"))}
    if history:
        res["problems"] = [p for p in res["problems"] if not p.startswith(
            ("duplicates: 0 in the table", "journal and table hold"))]
    tally.add(phase, lost=len(a - b), duplicated=res["dup_table"] + (
        0 if history else res["dup_journal"]), wrong=len(wrong) + len(b - a))
    problems += [f"{phase}: {p}" for p in res["problems"][:5]]


def _left(store: Path, total: int) -> float:
    """Share of the ``total`` points not yet in the store's journal."""
    try:
        return 1 - journal_points(store) / total
    except (TypeError, OSError):
        return 1.0


def kill_loop(tally: Tally, phase: str, args: list[str], ref: Path, store: Path, kills: int,
              rng: random.Random, window: tuple[float, float], mpi: int = 0,
              problems: list[str] | None = None, before=None, history: bool = False,
              shrink: int = 0) -> None:
    """Start ``args`` and SIGKILL its process group at a random instant of ``window``,
    ``kills`` times (resuming each time), then finish and compare. With ``shrink`` (the
    number of points), the window's end after the first second shrinks with the share
    of points still missing, so later kills still hit a running campaign."""
    done = 0
    while done < kills:
        if before is not None:
            before()
        lo, hi = window
        if shrink:
            hi = lo + 1.0 + (hi - lo - 1.0) * _left(store, shrink)
        p = run_cmd(args, mpi)
        delay = rng.uniform(lo, hi)
        try:
            rc = p.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            done += 1
            tally.add(phase, kills=1)
            continue
        out = p.stdout.read() + p.stderr.read()
        tally.add(phase, traceback=("Traceback" in out))
        if rc != 0:
            tally.add(phase, ruined=1)
            problems.append(f"{phase}: a resume exited {rc}: {out[-600:]}")
            return
        break  # finished before the kill
    rc, log = finish(args, mpi)
    tally.add(phase, cases=1)
    judge(tally, phase, ref, store, rc, log, problems, history)


def fresh_copy(src: Path, dst: Path) -> None:
    for suffix in ("", ".journal"):
        shutil.copyfile(str(src) + suffix, str(dst) + suffix)
    for extra in (str(dst) + ".lock", str(dst) + ".journal.rejected"):
        if os.path.exists(extra):
            os.unlink(extra)


def unclean(path: Path) -> None:
    with h5py.File(path, "r+", locking=False) as f:
        f.attrs["writer_open"] = True


# ---------------------------------------------------------------- journal corruptions
def corruptions() -> dict[str, object]:
    """The 13 journal corruptions: name -> function(lines, records) editing lines."""
    def w_c(lines, r):
        obj = decode(lines[r[0]])[0]
        v = repr(obj["row"]["W_c"]).encode()
        lines[r[0]] = lines[r[0]].replace(b'"W_c":' + v, b'"W_c":' + v[:-1] + b"7", 1)

    def status(lines, r):
        lines[r[1]] = lines[r[1]].replace(b'"status":"converged"', b'"status":"failed"', 1)

    def hash_char(lines, r):
        obj = decode(lines[r[2]])[0]
        h = obj["row"]["hash"]
        lines[r[2]] = lines[r[2]].replace(h.encode(), (h[:-1] + ("0" if h[-1] != "0" else
                                                                 "1")).encode())

    def resigned_hash(lines, r):
        obj = decode(lines[r[3]])[0]
        h = obj["row"]["hash"]
        obj["row"]["hash"] = h[:-1] + ("0" if h[-1] != "0" else "1")
        lines[r[3]] = encode(obj)

    def no_row(lines, r):
        obj = decode(lines[r[4]])[0]
        del obj["row"]
        lines[r[4]] = encode(obj)

    def no_crc(lines, r):
        obj = decode(lines[r[5]])[0]
        lines[r[5]] = encode(obj)[:-1].rsplit(b',"crc32":', 1)[0] + b"}\n"

    def cut_middle(lines, r):
        lines[r[6]] = lines[r[6]][: len(lines[r[6]]) // 2] + b"\n"

    def garbage(lines, r):
        lines.insert(r[7], b"this is not json at all\n")

    def profile_byte(lines, r):
        line = lines[r[8]]
        i = line.index(b'"a":{"f8":"') + 12  # a character of profile a's base64 bytes
        lines[r[8]] = line[:i] + (b"B" if line[i:i + 1] != b"B" else b"C") + line[i + 1:]

    def nul_line(lines, r):
        lines.insert(r[9], b"\0" * 100 + b"\n")

    def seq_string(lines, r):
        obj = decode(lines[r[10]])[0]
        obj["row"]["seq"] = "seven"
        lines[r[10]] = encode(obj)

    def resigned_config(lines, r):
        obj = decode(lines[r[11]])[0]
        cfg = json.loads(obj["row"]["config_json"])
        cfg["eps"] = 0.123
        obj["row"]["config_json"] = json.dumps(cfg, sort_keys=True, separators=(",", ":"))
        lines[r[11]] = encode(obj)

    def header(lines, r):
        lines[0] = lines[0].replace(b"sweep-journal", b"sweep-journaX")

    return {"W_c digit": w_c, "status flip": status, "hash character": hash_char,
            "hash re-signed": resigned_hash, "row removed": no_row, "checksum removed": no_crc,
            "line cut": cut_middle, "garbage line": garbage, "profile byte": profile_byte,
            "NUL line": nul_line, "seq not a number": seq_string,
            "config re-signed": resigned_config, "campaign line": header}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kills", type=int, default=200, help="total kills over the kill phases")
    ap.add_argument("--seed", type=int, default=15)
    ap.add_argument("--workdir", type=Path)
    ap.add_argument("--no-mpi", action="store_true")
    ap.add_argument("--holes", type=int, default=4, metavar="N",
                    help="tries per case of issue 26's holes (0: skip them)")
    ap.add_argument("--only-holes", action="store_true",
                    help="only issue 26's holes (not the kill phases of issue 15)")
    args = ap.parse_args(argv)
    work = args.workdir or Path(tempfile.mkdtemp(prefix="sweep-torture-store-"))
    work.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.seed)
    tally, problems = Tally(), []
    t0 = time.monotonic()
    small, big = work / "small.toml", work / "big.toml"
    small.write_text(SMALL)
    big.write_text(BIG)
    ref_small, ref_big = work / "ref_small.h5", work / "ref_big.h5"
    for cfg, ref in ((small, ref_small), (big, ref_big)):
        rc, log = finish(["run", str(cfg), "--store", str(ref), "--compute", FAKE, "--no-bar"])
        assert rc == 0, log
    use_mpi = MPIEXEC is not None and not args.no_mpi
    if args.only_holes:
        return _report_holes(args, work, rng, big, ref_big, use_mpi, problems, t0, True)
    # a store whose rebuild takes long enough to be hit: 1,800 points
    rebuild, ref_rebuild = work / "rebuild.toml", work / "ref_rebuild.h5"
    many = ", ".join(repr(round(0.001 + 0.00165 * i, 5)) for i in range(600))
    rebuild.write_text(f"[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.0, 1.5]\n"
                       f"eps = [{many}]\n")
    rc, log = finish(["run", str(rebuild), "--store", str(ref_rebuild), "--compute", FAKE,
                      "--no-bar"])
    assert rc == 0, log
    t = time.monotonic()
    finish(["run", str(rebuild), "--store", str(ref_rebuild), "--compute", FAKE, "--no-bar"])
    t_start = time.monotonic() - t  # a resume with nothing to do
    probe = work / "probe.h5"
    fresh_copy(ref_rebuild, probe)
    unclean(probe)
    t = time.monotonic()
    finish(["run", str(rebuild), "--store", str(probe), "--compute", FAKE, "--no-bar"])
    t_rebuild = max(time.monotonic() - t - t_start, 0.2)
    print(f"resume {t_start:.2f} s; rebuild of {len(sweep.load(ref_rebuild))} points"
          f" {t_rebuild:.2f} s more", flush=True)
    phases = ["run", "resume-rebuild", "retry", "extend", "merge"]
    if use_mpi:
        phases.append("run (mpiexec -n 3)")
    per = max(1, args.kills // len(phases))
    n_big = len(sweep.load(ref_big))

    # run: kills at any instant of a campaign (start-up, loop, commits, close)
    for phase in phases:
        k = 0
        while k < per:
            i = tally.rows.get(phase, Counter())["cases"]
            store = work / f"{phase.split()[0]}-{i}.h5"
            before = tally.rows.get(phase, Counter())["kills"]
            base = ["run", str(big), "--store", str(store), "--no-bar"]
            if phase.startswith("run"):
                mpi = 3 if "mpiexec" in phase else 0
                kill_loop(tally, phase, [*base, "--compute", SLEEPY], ref_big, store,
                          min(5, per - k), rng, (0.3, 2.5 + 0.2 * n_big / (2 if mpi else 1)),
                          mpi=mpi, problems=problems, shrink=n_big)
            elif phase == "resume-rebuild":  # a killed (unclean) store: every start rebuilds
                fresh_copy(ref_rebuild, store)
                kill_loop(tally, phase, ["run", str(rebuild), "--store", str(store),
                                         "--no-bar", "--compute", FAKE], ref_rebuild, store,
                          min(5, per - k), rng, (t_start, t_start + t_rebuild),
                          problems=problems, before=lambda s=store: unclean(s))
            elif phase == "retry":
                finish([*base, "--compute", "sweep.testing:faulty_point"])  # 15 failed
                kill_loop(tally, phase, [*base, "--compute", SLEEPY, "--retry-failed"],
                          ref_big, store, min(5, per - k), rng, (0.3, 4.0), problems=problems,
                          history=True)
            elif phase == "extend":
                finish(["run", str(small), "--store", str(store), "--compute", FAKE,
                        "--no-bar"])
                kill_loop(tally, phase, [*base, "--compute", SLEEPY, "--extend"], ref_big,
                          store, min(5, per - k), rng, (0.3, 3.0), problems=problems)
            elif phase == "merge":
                shards = []
                for s in range(3):
                    sp = work / f"merge-{i}-shard{s}.h5"
                    finish(["run", str(big), "--store", str(sp), "--shard", f"{s}/3",
                            "--compute", FAKE, "--no-bar"])
                    shards.append(str(sp))
                kill_loop(tally, phase, ["merge", str(store), *shards], ref_big, store,
                          min(5, per - k), rng, (0.3, 1.6), problems=problems)
            k += tally.rows[phase]["kills"] - before  # cases that finished before any
            if tally.rows[phase]["cases"] > 6 * per:  # kill count as cases only
                break
        print(f"{phase}: {dict(tally.rows[phase])} ({time.monotonic() - t0:.0f} s)", flush=True)

    # journal corruptions: each on a copy of the reference, with the file to be rebuilt
    phase = "journal corruptions"
    for name, edit in corruptions().items():
        store = work / f"corrupt-{name.replace(' ', '_')}.h5"
        fresh_copy(ref_big, store)
        jp = journal_path(store)
        lines = jp.read_bytes().splitlines(keepends=True)
        records = [i for i, line in enumerate(lines) if line.startswith(b'{"row"')]
        picks = sorted(rng.sample(records, 12))
        edit(lines, picks)
        jp.write_bytes(b"".join(lines))
        unclean(store)
        rc, log = finish(["run", str(big), "--store", str(store), "--compute", FAKE,
                          "--no-bar"])
        tally.add(phase, cases=1)
        judge(tally, phase, ref_big, store, rc, log, problems)
    print(f"{phase}: {dict(tally.rows[phase])}", flush=True)

    # compute faults
    phase = "compute faults"
    faults = work / "faults.toml"
    faults.write_text("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]\n"
                      "[run]\nmax_attempts = 2\n")
    for compute, expect in (("sweep.testing:faulty_point", {"failed": 5, "converged": 1}),
                            ("sweep.testing:stuck_point", {"timeout": 2}),
                            ("sweep.testing:crashing_point", {"crashed": 1})):
        store = work / f"faults-{compute.split(':')[1]}.h5"
        extra = ["--point-timeout", "0.5"] if "stuck" in compute else []
        log, rc = "", None
        for _ in range(6):  # a crasher needs a few runs
            rc, log = finish(["run", str(faults), "--store", str(store), "--compute", compute,
                              "--no-bar", *extra], timeout=120)
            if rc == 0:
                break
        tally.add(phase, cases=1, traceback=("Traceback" in log and rc != 0))
        if rc != 0:
            tally.add(phase, ruined=1)
            problems.append(f"{phase} {compute}: exited {rc}: {log[-400:]}")
            continue
        counts = Counter(sweep.load(store)["status"])
        lost = 6 - sum(counts.values())
        bad = sum(max(0, n - counts.get(s, 0)) for s, n in expect.items())
        tally.add(phase, lost=max(lost, 0), wrong=bad)
        if bad or lost:
            problems.append(f"{phase} {compute}: statuses {dict(counts)}, expected {expect}")
    print(f"{phase}: {dict(tally.rows[phase])}", flush=True)

    # stops during start-up and during the rebuild: SIGTERM/SIGINT/SIGUSR1 at random
    phase = "stops (start-up, rebuild)"
    statuses: Counter = Counter()
    for i in range(15):
        store = work / f"stop-{i}.h5"
        fresh_copy(ref_big, store)
        if i % 2:
            unclean(store)
        sig = (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1)[i % 3]
        p = run_cmd(["run", str(big), "--store", str(store), "--compute", FAKE, "--no-bar"])
        time.sleep(rng.uniform(0.2, 2.0))
        p.send_signal(sig)
        out, err = p.communicate(timeout=120)
        statuses[p.returncode] += 1
        tally.add(phase, cases=1, traceback=("Traceback" in err))
        rc, log = finish(["run", str(big), "--store", str(store), "--compute", FAKE,
                          "--no-bar"])
        judge(tally, phase, ref_big, store, rc, log, problems)
    print(f"{phase}: {dict(tally.rows[phase])}; exit statuses of the stopped runs"
          f" {dict(statuses)}", flush=True)

    # reads during writes: load + status while a run commits
    phase = "reads during writes"
    store = work / "reads.h5"
    eps = ", ".join(repr(round(0.001 + 0.0009 * i, 5)) for i in range(1000))
    reads_cfg = work / "reads.toml"
    reads_cfg.write_text(f"[base]\nL_sheet = 6.0\n[sweep]\neps = [{eps}]\n")
    p = run_cmd(["run", str(reads_cfg), "--store", str(store), "--compute",
                 "sweep.testing:sleepy_trivial_point", "--no-bar"])
    failures = reads = 0
    while p.poll() is None:
        if not store.exists():
            time.sleep(0.02)
            continue
        reads += 1
        try:
            sweep.load(store)
        except Exception as exc:  # noqa: BLE001 - counted
            failures += 1
            problems.append(f"{phase}: load failed: {exc!r}")
        if reads % 10 == 0:
            st = subprocess.run([PY, "-m", "sweep", "status", str(store)],
                                capture_output=True, text=True, env=env())
            reads += 1
            failures += st.returncode != 0
    p.communicate()
    tally.add(phase, cases=reads, wrong=failures)
    print(f"{phase}: {reads} reads, {failures} failed", flush=True)

    # hostile inputs: each must give one clear line and a documented status
    phase = "hostile inputs"
    cases = hostile(work)
    for name, argv, setup in cases:
        if setup:
            setup()
        rc, log = finish(argv, timeout=120)
        tb = "Traceback" in log or rc not in (0, 2, 3, 4, 5, 6)
        tally.add(phase, cases=1, traceback=tb)
        if tb:
            problems.append(f"{phase} {name}: exit {rc}: {log[-300:]}")
    print(f"{phase}: {dict(tally.rows[phase])}", flush=True)

    print()
    print(tally.table())
    return _report_holes(args, work, rng, big, ref_big, use_mpi, problems, t0)


def _report_holes(args, work, rng, big, ref_big, use_mpi, problems, t0,
                  only: bool = False) -> int:
    """The holes' table (``--holes`` tries per case; always with ``--only-holes``), the
    elapsed time and the problems; the exit status (1 if any problem)."""
    if only or args.holes:
        holes_table = holes(work, rng, big, ref_big, args.holes, use_mpi, problems)
        print()
        print(holes_table.table())
    print(f"\nelapsed {time.monotonic() - t0:.0f} s; work directory {work}")
    for p in problems[:40]:
        print("PROBLEM:", p)
    return 1 if problems else 0


# ---------------------------------------------------------------- issue 26: the last holes
class HoleTally(Tally):
    """Per case: tries, survived (the store ended whole and every command said the
    truth), ruined, lost, duplicated, silently wrong (a wrong row, or a command that
    exited 0 with the grid incomplete / a damage unnoticed), tracebacks."""

    COLS = ["tries", "survived", "ruined", "lost", "duplicated", "silently wrong",
            "tracebacks"]

    def table(self) -> str:
        lines = ["| case | " + " | ".join(self.COLS) + " |",
                 "|---|" + "---|" * len(self.COLS)]
        total: Counter = Counter()
        for phase, c in self.rows.items():
            total.update(c)
            lines.append(f"| {phase} | " + " | ".join(str(c.get(k, 0)) for k in self.COLS)
                         + " |")
        lines.append("| **total** | " + " | ".join(str(total.get(k, 0)) for k in self.COLS)
                     + " |")
        return "\n".join(lines)


def _whole(tally: HoleTally, case: str, ref: Path, store: Path, rc: int, log: str,
           problems: list[str], history: bool = False, wrong: int = 0) -> None:
    """Finish-and-compare bookkeeping of one try (``wrong``: silently wrong already
    seen by the case itself)."""
    tally.add(case, tries=1, tracebacks=("Traceback" in log))
    if rc != 0:
        tally.add(case, ruined=1, **{"silently wrong": wrong})
        problems.append(f"{case}: the finishing run exited {rc}: {log[-500:]}")
        return
    res = compare(ref, store)
    a, b = set(sweep.load(ref)["hash"]), set(sweep.load(store)["hash"])
    if history:
        res["problems"] = [p for p in res["problems"] if not p.startswith(
            ("duplicates: 0 in the table", "journal and table hold"))]
    bad = {p.split()[0] for p in res["problems"] if not p.startswith(
        ("hashes", "journal", "duplicates", "validate"))}
    wrong += len(bad) + len(b - a)
    dup = res["dup_table"] + (0 if history else res["dup_journal"])
    tally.add(case, lost=len(a - b), duplicated=dup, **{"silently wrong": wrong})
    if not res["problems"] and not wrong:
        tally.add(case, survived=1)
    problems += [f"{case}: {p}" for p in res["problems"][:5]]


def _flip_byte(path: Path, dataset: str, rng: random.Random) -> None:
    with h5py.File(path, "r", locking=False) as f:
        ds = f[dataset]
        offset = ds.id.get_offset()
        if offset is None:
            offset = ds.id.get_chunk_info(0).byte_offset
        n = ds.shape[0] if ds.shape else 1
    where = offset + 8 * rng.randrange(max(1, min(n, 50))) + rng.randrange(8)
    with open(path, "r+b") as fh:
        fh.seek(where)
        b = fh.read(1)
        fh.seek(where)
        fh.write(bytes([b[0] ^ (1 << rng.randrange(8))]))


_FULL_DISK = """
import errno, os, sys
import sweep.cli, sweep.store.lock
def full(*a):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
sweep.store.lock.os.pwrite = full
sys.exit(sweep.cli.main(sys.argv[1:]))
"""


def holes(work: Path, rng: random.Random, big: Path, ref_big: Path, tries: int,
          use_mpi: bool, problems: list[str]) -> HoleTally:
    """Issue 26's cases, ``tries`` times each: exit 0 in a point (in-process, C exit,
    under mpiexec), foreign and replayed journal lines, truncated stores, writers
    through a symlink and a hard link, output the schema cannot hold, a full disk at the
    resume, HDF5 bit rot, stop signals during imports."""
    tally = HoleTally()
    hw = work / "holes"
    hw.mkdir(exist_ok=True)
    grid = len(sweep.load(ref_big))
    base = ["--compute", FAKE, "--no-bar"]

    def fin(store: Path, *extra: str) -> tuple[int, str]:
        return finish(["run", str(big), "--store", str(store), *base, *extra])

    # 1. a point that ends its process with status 0
    crash_cfg = hw / "exit0.toml"
    crash_cfg.write_text(BIG + "[run]\nmax_attempts = 1\n")
    for case, compute, mpi in (("exit 0 in a point", "exiting_point", 0),
                               ("C exit(0) in a point", "c_exit_point", 0),
                               ("exit 0 in a point (mpiexec -n 3)", "exiting_point", 3)):
        if mpi and not use_mpi:
            continue
        for i in range(tries):
            store = hw / f"exit0-{mpi}-{compute}-{i}.h5"
            wrong, tb, rc, log = 0, False, None, ""
            for _ in range(12):
                rc, log = finish(["run", str(crash_cfg), "--store", str(store), "--compute",
                                  f"sweep.testing:{compute}", "--no-bar"], mpi=mpi)
                tb = tb or "Traceback" in log
                if rc == 0:
                    break
            df = sweep.load(store)
            if rc == 0 and len(df) < grid:
                wrong += 1  # "success" with points missing
            crashed = df[df["eps"] == 0.4]
            others = df[df["eps"] != 0.4]
            ref = sweep.load(ref_big).set_index("hash")
            wrong += int((crashed["status"] != "crashed").sum())
            wrong += sum(ref.loc[h, "W_c"] != w and not (np.isnan(w) and np.isnan(
                ref.loc[h, "W_c"])) for h, w in zip(others["hash"], others["W_c"], strict=True))
            tally.add(case, tries=1, tracebacks=tb, lost=grid - len(df),
                      duplicated=len(df) - df["hash"].nunique(), **{"silently wrong": wrong})
            if rc != 0:
                tally.add(case, ruined=1)
                problems.append(f"{case}: never finished: {log[-300:]}")
            elif not wrong and len(df) == grid and not sweep.validate(store):
                tally.add(case, survived=1)

    # 2. journal lines of another campaign (same [base], eps not in the grid)
    other_cfg, other = hw / "other.toml", hw / "other.h5"
    other_cfg.write_text(BIG.replace(EPS, "0.33, 0.66"))
    finish(["run", str(other_cfg), "--store", str(other), *base])
    foreign = [line for line in journal_path(other).read_bytes().splitlines(keepends=True)
               if line.startswith(b'{"row"')]
    for i in range(tries):
        store = hw / f"foreign-{i}.h5"
        fresh_copy(ref_big, store)
        with open(journal_path(store), "ab") as fh:
            fh.write(b"".join(rng.sample(foreign, rng.randint(1, len(foreign)))))
        if i % 2:
            unclean(store)
        rc, log = fin(store)
        _whole(tally, "foreign journal lines", ref_big, store, rc, log, problems)

    # 5. a replayed block of old failed lines after their retried records
    for i in range(tries):
        store = hw / f"replay-{i}.h5"
        finish(["run", str(big), "--store", str(store), "--compute",
                "sweep.testing:faulty_point", "--no-bar"])
        failed = [line for line in journal_path(store).read_bytes().splitlines(keepends=True)
                  if b'"status":"failed"' in line]
        fin(store, "--retry-failed")
        with open(journal_path(store), "ab") as fh:
            fh.write(b"".join(failed))
        unclean(store)
        rc, log = fin(store)
        _whole(tally, "replayed journal block", ref_big, store, rc, log, problems,
               history=True)

    # 3. a truncated file beside a complete journal
    for i in range(tries):
        store = hw / f"truncated-{i}.h5"
        fresh_copy(ref_big, store)
        data = store.read_bytes()
        cut = (len(data) // 2, 96, rng.randrange(96, len(data)))[i % 3]
        store.write_bytes(data[:cut])
        rc, log = fin(store)
        _whole(tally, "truncated store", ref_big, store, rc, log, problems)

    # 4. two writers, one through a symlink / a hard link
    for kind in ("symlink", "hard link"):
        for i in range(tries):
            store = hw / f"{kind[:4]}-{i}.h5"
            other_name = hw / f"{kind[:4]}-{i}-other.h5"
            args = ["--compute", SLEEPY, "--no-bar"]
            a = run_cmd(["run", str(big), "--store", str(store), *args])
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline and not journal_path(store).exists():
                time.sleep(0.01)
            time.sleep(rng.uniform(0.0, 1.0))
            if kind == "symlink":
                other_name.symlink_to(store.name)
            else:
                os.link(store, other_name)
            b = run_cmd(["run", str(big), "--store", str(other_name), *args])
            out_a, err_a = a.communicate(timeout=600)
            out_b, err_b = b.communicate(timeout=600)
            # the hole: the second writer exits 0 having stored points while the first
            # ran (it starts well within the first's 12 s); refused (3) is right
            now = re.search(r"(\d+) stored now", out_b)
            wrong = int(a.returncode == 0 and b.returncode == 0 and bool(now)
                        and int(now.group(1)) > 0)
            if b.returncode not in (0, 3):
                problems.append(f"two writers ({kind}): the second exited {b.returncode}:"
                                f" {err_b[-300:]}")
            rc, log = fin(store)
            _whole(tally, f"two writers ({kind})", ref_big, store, rc,
                   log + err_a + err_b, problems, wrong=wrong)

    # 6. output the schema cannot hold
    mis_cfg = hw / "misfit.toml"
    mis_cfg.write_text("[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\n"
                       "eps = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]\n")
    for i in range(tries):
        store = hw / f"misfit-{i}.h5"
        rc, log = finish(["run", str(mis_cfg), "--store", str(store), "--compute",
                          "sweep.testing:misfit_point", "--no-bar"])
        tally.add("wrong-shape output", tries=1, tracebacks="Traceback" in log)
        if rc != 0:
            tally.add("wrong-shape output", ruined=1)
            continue
        df = sweep.load(store)
        wrong = int((df[df["eps"] < 0.55]["status"] != "failed").sum())
        wrong += bool(sweep.validate(store))
        tally.add("wrong-shape output", lost=12 - len(df), **{"silently wrong": wrong})
        if not wrong and len(df) == 12:
            tally.add("wrong-shape output", survived=1)

    # 7. a resume on a completely full disk (ENOSPC at the lock's write)
    for i in range(tries):
        store = hw / f"full-{i}.h5"
        fresh_copy(ref_big, store)
        p = subprocess.run([PY, "-c", _FULL_DISK, "run", str(big), "--store", str(store),
                            *base], capture_output=True, text=True, env=env(), timeout=120)
        tb = "Traceback" in p.stderr
        wrong = int(p.returncode == 0)
        if p.returncode != 3 or p.stderr.count("\n") != 1:
            problems.append(f"full disk: exit {p.returncode}: {p.stderr[-300:]}")
        rc, log = fin(store)
        _whole(tally, "full-disk resume", ref_big, store, rc, log + p.stderr, problems,
               wrong=wrong)

    # 8. HDF5 bit rot: validate --deep must see it; run --verify repairs it
    cols = ["W_c", "alpha_all", "a_end", "iterations", "residual"]
    for i in range(tries * 2):
        store = hw / f"rot-{i}.h5"
        fresh_copy(ref_big, store)
        h = rng.choice(list(sweep.load(store)["hash"]))
        where = (f"table/{rng.choice(cols)}" if i % 2 == 0 else
                 f"profiles/{h[:2]}/{h}/{rng.choice(['a', 'x_mean', 'S_sd'])}")
        _flip_byte(store, where, rng)
        v = finish(["validate", "--deep", str(store)])
        seen = v[0] == 3
        if not seen:
            problems.append(f"bit rot at {where}: validate --deep exited {v[0]}")
        rc, log = fin(store, "--verify")
        _whole(tally, "HDF5 bit rot (validate --deep, run --verify)", ref_big, store, rc,
               log + v[1], problems, wrong=int(not seen))

    # 9. stop signals during imports and start-up (in-process)
    for i in range(tries * 3):
        store = hw / f"stop-{i}.h5"
        fresh_copy(ref_big, store)
        sig = (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1)[i % 3]
        p = run_cmd(["run", str(big), "--store", str(store), *base])
        while p.poll() is None and not catches_signal(p.pid, signal.SIGTERM):
            time.sleep(0.001)
        time.sleep(rng.uniform(0.0, 0.7))
        p.send_signal(sig)
        out, err = p.communicate(timeout=120)
        bad = p.returncode not in (0, 6)
        if bad:
            problems.append(f"stop during imports: exit {p.returncode}: {err[-300:]}")
        rc, log = fin(store)
        _whole(tally, "stop signals during imports", ref_big, store, rc, log + err, problems,
               wrong=int(bad))
    return tally


def hostile(work: Path) -> list[tuple[str, list[str], object]]:
    h = work / "hostile"
    h.mkdir(exist_ok=True)
    store = h / "s.h5"
    good = h / "good.toml"
    good.write_text(SMALL)
    out: list[tuple[str, list[str], object]] = []

    def toml(name: str, text: str) -> None:
        path = h / f"{name}.toml"
        path.write_text(text)
        out.append((name, ["run", str(path), "--store", str(h / f"{name}.h5"), "--compute",
                           FAKE, "--no-bar"], None))

    toml("huge_grid", "[sweep]\n" + "\n".join(
        f"{k} = [{', '.join(repr(v * (i + 1)) for i in range(40))}]"
        for k, v in (("L_x", 0.1), ("T", 0.5), ("a0", 0.01), ("C_sd", 0.01), ("eps", 0.02),
                     ("d_f", 0.001))))
    toml("L_sheet_1e308", "[base]\nL_sheet = 1e308\n[sweep]\neps = [0.2]\n")
    toml("dt_1e-305", "[base]\ndt = 1e-305\n[sweep]\neps = [0.2]\n")
    toml("nested", "[base]\nL_sheet = 6.0\n[sweep]\neps = " + "[" * 500 + "0.2" + "]" * 500
         + "\n")
    toml("empty_sweep", "[base]\nL_sheet = 6.0\n[sweep]\n")
    toml("grace_1e300", SMALL + "[run]\ngrace_period = 1e300\n")
    toml("n0_1e30", "[base]\nL_sheet = 6.0\nn0 = 1e30\n[sweep]\neps = [0.2]\n")
    toml("iterations_huge", "[base]\nL_sheet = 6.0\nmax_iterations = 100000000000000000000\n"
         "[sweep]\neps = [0.2]\n")
    toml("not_toml", "[base\nL_sheet = ")
    out.append(("plan_rate_negative", ["plan", str(good), "--rate", "-1"], None))
    out.append(("status_slowest_negative", ["status", str(h / "none.h5"), "--slowest", "-1"],
                None))
    out.append(("status_missing", ["status", str(h / "none.h5")], None))
    ro = h / "ro"
    ro.mkdir(exist_ok=True)
    out.append(("store_is_directory", ["run", str(good), "--store", str(ro)], None))
    (h / "lockdir.h5.lock").mkdir(exist_ok=True)
    out.append(("lock_is_directory", ["run", str(good), "--store", str(h / "lockdir.h5"),
                                      "--compute", FAKE], None))
    (h / "jdir.h5.journal").mkdir(exist_ok=True)
    out.append(("journal_is_directory", ["run", str(good), "--store", str(h / "jdir.h5"),
                                         "--compute", FAKE], None))
    loop = h / "loop.h5"
    if not loop.is_symlink():
        os.symlink(loop, loop)
    out.append(("symlink_loop", ["run", str(good), "--store", str(loop), "--compute", FAKE],
                None))
    notes = h / "notes.txt"
    notes.write_text("mine")
    (h / "notes.txt.journal").write_text("mine too")
    out.append(("store_is_a_text_file", ["run", str(good), "--store", str(notes),
                                         "--compute", FAKE], None))

    def abc() -> None:
        finish(["run", str(good), "--store", str(store), "--compute", FAKE, "--no-bar"])
        with h5py.File(store, "r+", locking=False) as f:
            f.attrs["schema_version"] = "abc"
    out.append(("schema_version_abc", ["run", str(good), "--store", str(store), "--compute",
                                       FAKE], abc))
    out.append(("validate_schema_abc", ["validate", str(store)], None))
    out.append(("export_missing_dir", ["export", str(ref := work / "ref_small.h5"), "-o",
                                       str(h / "nope" / "x.csv")], None))
    out.append(("merge_self", ["merge", str(ref), str(ref)], None))
    out.append(("bad_compute", ["run", str(good), "--store", str(h / "bc.h5"), "--compute",
                                "no_such_module:f"], None))
    out.append(("bad_compute_syntax", ["run", str(good), "--store", str(h / "bc.h5"),
                                       "--compute", "nocolon"], None))
    return out


if __name__ == "__main__":
    sys.exit(main())
