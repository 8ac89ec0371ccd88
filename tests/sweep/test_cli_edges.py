"""The command line's rough edges (issue 25, item 4): a missing or non-HDF5 store is one
line with exit status 3; abbreviated options are refused; a reader that stops early ends
the output quietly; a campaign that --extend cannot take does not suggest --extend; a
killed run is not shown as running; .gitignore holds what the docs' examples write."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import h5py
import pytest

import floewave.cli
import sweep
import sweep.cli
from sweep import parse_campaign
from sweep.analysis.status import status_report
from sweep.errors import CampaignMismatchError
from sweep.store.campaign_check import check_campaign
from sweep.store.lock import Lock, lock_path
from tests import forkserver

ROOT = Path(__file__).resolve().parents[2]
TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"


@pytest.fixture
def store(tmp_path, campaign):
    path = tmp_path / "s.h5"
    sweep.run_campaign(campaign, str(path), compute="sweep.testing:fake_point")
    return path


@pytest.mark.parametrize("command", ["status", "export", "validate", "report", "figures"])
def test_a_missing_store_or_a_campaign_file_is_one_line_and_status_3(tmp_path, run_main,
                                                                        command):
    (tmp_path / "base.toml").write_text(TOML)
    extra = {"export": ["-o", "t.csv"], "report": ["--out", "r.html"],
             "figures": ["--out", "figs"]}.get(command, [])
    for name, says in (("nosuch.h5", "no such store"), ("base.toml", "not an HDF5 file")):
        p = run_main(sweep.cli.main, [command, name, *extra], cwd=tmp_path)
        assert p.returncode == 3, p.stderr
        assert p.stderr.count("\n") == 1 and says in p.stderr, p.stderr
        assert "Unable to" not in p.stderr and "errno" not in p.stderr, p.stderr


def test_abbreviated_options_are_refused(tmp_path, run_main):
    """``--stor x.h5`` is not ``--store x.h5`` (argparse's abbreviations are off)."""
    for parser, argv in ((sweep.cli.build_parser(), ["run", "c.toml", "--stor", "x.h5"]),
                         (sweep.cli.build_parser(), ["status", "s.h5", "--slow", "2"]),
                         (sweep.cli.build_parser(), ["plan", "c.toml", "--rat", "1e8"]),
                         (floewave.cli.main_parser(), ["run", "--jso", "o.json"])):
        with pytest.raises(SystemExit) as exc:
            parser.parse_args(argv)
        assert exc.value.code == 2, argv
    ok = sweep.cli.build_parser().parse_args(["run", "c.toml", "--store", "x.h5"])
    assert ok.store == Path("x.h5")


def _closed_stdout(module, args, cwd):
    """``python -m MODULE ARGS`` with stdout a pipe whose reader has gone
    (``… | head -0``), forked from an interpreter that imported sweep once
    (tests/forkserver.py)."""
    r, w = os.pipe()
    os.close(r)
    try:
        return forkserver.run(args, module=module, stdout=w, stderr=subprocess.PIPE,
                              text=True, cwd=cwd, timeout=300)
    finally:
        os.close(w)


def test_a_reader_that_stops_early_gets_no_traceback(tmp_path, store):
    """``floewave figures --out figs | head -1`` and ``sweep status S.h5 | head -2``:
    status 0, no BrokenPipeError, and the files are still written."""
    pytest.importorskip("matplotlib")
    p = _closed_stdout("floewave", ["figures", "--out", "figs"], tmp_path)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    assert (tmp_path / "figs" / "fig1_dispersion.png").exists()
    for argv in (["status", str(store)], ["status", str(store), "--json"],
                 ["plan", str(tmp_path / "c.toml"), "--rate", "1e8"]):
        (tmp_path / "c.toml").write_text(TOML)
        p = _closed_stdout("sweep", argv, tmp_path)
        assert p.returncode == 0 and "Traceback" not in p.stderr, (argv, p.stderr)


def test_a_base_change_does_not_suggest_extend():
    """--extend refuses a changed [base]: the error says so instead of suggesting it."""
    old = parse_campaign(TOML).definition()
    rebased = parse_campaign(TOML.replace("6.0", "7.0"))
    with pytest.raises(CampaignMismatchError) as exc:
        check_campaign(Path("s.h5"), old, rebased, False, "store")
    text = str(exc.value)
    assert "differs in [base] L_sheet" in text and "or --extend" not in text
    assert "--extend cannot take it: its [base]" in text and "another --store" in text
    with pytest.raises(CampaignMismatchError, match=r"cannot --extend this store: its \[base\]"):
        check_campaign(Path("s.h5"), old, rebased, True, "store")  # as the message says
    more = parse_campaign(TOML.replace("[0.2, 0.4]", "[0.2, 0.4, 0.6]"))
    with pytest.raises(CampaignMismatchError, match="or --extend to add grid values"):
        check_campaign(Path("s.h5"), old, more, False, "store")   # here --extend works
    check_campaign(Path("s.h5"), old, more, True, "store")


def _as_killed(path, pid):
    """Leave the store as a killed writer does: its last run "running" without an end,
    and its lock file (naming ``pid``) behind."""
    with h5py.File(path, "r+", locking=False) as f:
        g = f["runs"][str(max(int(n) for n in f["runs"]))]
        g.attrs["outcome"] = "running"
        del g.attrs["ended"]
    lock_path(path).write_text(json.dumps({"pid": pid, "host": os.uname().nodename,
                                           "since": "2026-12-02T05:00:00+00:00"}))


def test_status_does_not_show_a_killed_run_as_running(store, run_main):
    dead = forkserver.run([], code="import os; print(os.getpid())", capture_output=True,
                          text=True).stdout.strip()
    _as_killed(store, int(dead))
    p = run_main(sweep.cli.main, ["status", str(store)])
    assert p.returncode == 0
    assert "(running)" not in p.stdout and "(no end recorded)" in p.stdout, p.stdout
    assert "died: its writer was killed" in p.stdout
    rep = status_report(store)
    assert rep["runs"][-1]["outcome"].startswith("died")


def test_status_shows_a_live_run_as_running(store, run_main):
    _as_killed(store, os.getpid())
    lock = Lock(lock_path(store))
    lock.acquire()  # a live writer holds the lock
    try:
        p = run_main(sweep.cli.main, ["status", str(store)])
    finally:
        lock.release()
    assert p.returncode == 0 and "(running)" in p.stdout, p.stdout


@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(),
                    reason="needs a git checkout")
def test_gitignore_holds_what_the_docs_examples_write():
    names = [".venv/", "out.json", "out.png", "demo.h5", "demo.h5.journal", "demo.csv",
             "figs/x.png", "report.html", "paper/fig2.h5"]
    p = subprocess.run(["git", "check-ignore", "--no-index", *names], cwd=ROOT,
                       capture_output=True, text=True)
    assert sorted(p.stdout.split()) == sorted(names), p.stdout
