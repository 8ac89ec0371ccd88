"""tests/forkserver.py: a forked ``python -m sweep`` is the command as a fresh interpreter
runs it (exit statuses, streams, environment, working directory, signals, the store)."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

import sweep
from tests import forkserver
from tests.sweep.helpers import table

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4]\n"
ARGS = ["--compute", "sweep.testing:fake_point", "--no-bar"]


def test_a_forked_run_is_a_fresh_interpreters_run(tmp_path):
    """The same campaign by ``python -m sweep run`` and by the fork server: status 0,
    the same summary and the same stored table; a bad campaign file is status 2 with the
    same one-line message in both."""
    (tmp_path / "c.toml").write_text(TOML)
    fresh = subprocess.run([sys.executable, "-m", "sweep", "run", "c.toml", "--store",
                            "a.h5", *ARGS], capture_output=True, text=True, cwd=tmp_path)
    forked = forkserver.run(["run", "c.toml", "--store", "b.h5", *ARGS],
                            capture_output=True, text=True, cwd=tmp_path)
    assert fresh.returncode == forked.returncode == 0, (fresh.stderr, forked.stderr)
    assert forked.args[0] == "python"  # forked: the fresh one's is sys.executable
    assert fresh.stdout.split(" in ")[0] == forked.stdout.split(" in ")[0]
    assert table(tmp_path / "a.h5").equals(table(tmp_path / "b.h5"))
    assert len(sweep.load(tmp_path / "b.h5")) == 4
    (tmp_path / "bad.toml").write_text("[base]\nnope = 1\n")
    bad = [forkserver.run(["run", "bad.toml", "--store", "c.h5"], capture_output=True,
                          text=True, cwd=tmp_path),
           subprocess.run([sys.executable, "-m", "sweep", "run", "bad.toml", "--store",
                           "c.h5"], capture_output=True, text=True, cwd=tmp_path)]
    assert [p.returncode for p in bad] == [2, 2]
    assert bad[0].stderr == bad[1].stderr and "[base] nope = 1: unknown parameter" in bad[0].stderr
    assert not (tmp_path / "c.h5").exists()


def test_environment_arguments_streams_and_status(tmp_path):
    """``python -c``: its argv, the request's environment (not the server's), ``''`` first
    on sys.path and PYTHONPATH's entries after it, stdin, exit status, an uncaught
    exception's traceback and status 1."""
    (tmp_path / "mod_here.py").write_text("WHERE = 'pythonpath'\n")
    code = ("import os, sys, mod_here; print(sys.argv[1:], os.environ['FORKED_X'],"
            " sys.path[0] == '', mod_here.WHERE, os.getcwd(), sys.stdin.read().strip());"
            " sys.exit(7)")
    env = dict(os.environ, FORKED_X="yes", PYTHONPATH=str(tmp_path))
    p = forkserver.run(["a", "b"], code=code, env=env, cwd=tmp_path, input="in",
                       capture_output=True, text=True)
    assert p.returncode == 7 and p.args[0] == "python", p.stderr
    assert p.stdout.split() == ["['a',", "'b']", "yes", "True", "pythonpath", str(tmp_path),
                                "in"]
    p = forkserver.run([], code="raise ValueError('boom')", capture_output=True, text=True)
    assert p.returncode == 1 and "ValueError: boom" in p.stderr and "Traceback" in p.stderr


def test_signals_reach_the_command_and_end_it_as_they_would(tmp_path):
    """Its pid is the command's: SIGKILL ends it with -9, SIGTERM without a handler -15,
    an uncaught KeyboardInterrupt (SIGINT) -2, as for a fresh interpreter. Where SIGINT
    is ignored from the start (a server started by a job in the background of a
    non-interactive shell: ``nohup ... &``), a fresh interpreter keeps ignoring it, and so
    does the command: it is still running after SIGINT."""
    # ignored or not as in the server's commands (the server's start decides, not this
    # test process: an xdist worker ignores SIGINT, the controller that started the
    # server may not)
    probe = "import signal, sys; sys.exit(signal.getsignal(signal.SIGINT) is signal.SIG_IGN)"
    sigint_ignored = forkserver.run([], code=probe).returncode == 1
    for sig in (signal.SIGKILL, signal.SIGTERM, signal.SIGINT):
        p = forkserver.popen([], code="import time; print('up', flush=True); time.sleep(60)",
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert isinstance(p, forkserver.Forked) and p.stdout.readline() == "up\n"
        p.send_signal(sig)
        if sig == signal.SIGINT and sigint_ignored:
            with pytest.raises(subprocess.TimeoutExpired):
                p.communicate(timeout=1.0)
            p.kill()
            p.communicate(timeout=60)
            assert p.returncode == -signal.SIGKILL
            continue
        _, err = p.communicate(timeout=60)
        assert p.returncode == -sig, (sig, err)
    if not sigint_ignored:
        assert "KeyboardInterrupt" in err
    with pytest.raises(subprocess.TimeoutExpired):
        forkserver.run([], code="import time; time.sleep(60)", timeout=0.2)


NS_LAST_PID = Path("/proc/sys/kernel/ns_last_pid")


@pytest.mark.skipif(os.geteuid() != 0, reason="choosing the next pid (ns_last_pid) needs root"
                    " (CI runs as root)")
def test_a_command_given_an_ended_commands_pid_is_not_taken_for_ended():
    """The kernel gives an ended command's pid to a later process (pid_max is 32768 on
    these machines; a full test run starts more processes than that). A command started
    with the pid of one whose end the server has reported is running, not ended with that
    one's status, and a signal reaches it. (Kept by pid, the old status was read as the new
    command's: send_signal() saw it ended and sent nothing, and communicate() waited out
    its timeout: CI's one failure at 923a0ed.) The pid is arranged by writing the pid
    before it to ns_last_pid; another process may fork in between, so a few tries."""
    try:
        NS_LAST_PID.write_text(NS_LAST_PID.read_text())
    except OSError as exc:  # root without CAP_SYS_ADMIN (a read-only /proc/sys)
        pytest.skip(f"ns_last_pid not writable here ({exc}); CI's machines write it")
    first = forkserver.popen([], code="pass")
    assert isinstance(first, forkserver.Forked) and first.wait(60) == 0
    for _ in range(100):
        NS_LAST_PID.write_text(str(first.pid - 1))
        p = forkserver.popen([], code="import time; print('up', flush=True); time.sleep(60)",
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if p.pid == first.pid:
            break
        p.kill()
        p.communicate(timeout=60)
    assert p.pid == first.pid, "the old pid could not be given to a new command"
    assert p.stdout.readline() == "up\n"
    assert p.poll() is None
    p.send_signal(signal.SIGTERM)
    p.communicate(timeout=60)
    assert p.returncode == -signal.SIGTERM


def test_poll_sees_an_end_and_the_exit_is_the_interpreters(tmp_path):
    """poll() reports a command that has ended (without a wait); the exit is the
    interpreter's own: sys.exit(-2) is 254, a non-daemon thread is joined and a finaliser
    runs before the end, an HDF5 file left open in a global is closed whole."""
    p = forkserver.popen([], code="pass")
    assert isinstance(p, forkserver.Forked)
    deadline = time.monotonic() + 60
    while p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert p.returncode == 0
    assert forkserver.run([], code="import sys; sys.exit(-2)").returncode == 254
    code = ("import threading, time\n"
            "class Last:\n"
            "    def __del__(self): print('finalised', flush=True)\n"
            "last = Last()\n"
            "threading.Thread(target=lambda: (time.sleep(0.2), print('joined', flush=True))"
            ").start()\n"
            "import h5py\n"
            f"f = h5py.File({str(tmp_path / 'x.h5')!r}, 'w')\n"
            "f['d'] = list(range(10))\n")
    p = forkserver.run([], code=code, capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.split() == ["joined", "finalised"], p
    with h5py.File(tmp_path / "x.h5", "r") as f:
        assert list(f["d"][:]) == list(range(10))


def test_an_import_time_variable_of_its_own_runs_fresh():
    """A command whose import-time environment differs from the server's (a variable numba
    or sweep reads when imported) cannot be forked from it: it runs in a fresh
    interpreter, which reads it."""
    env = dict(os.environ, SWEEP_CHILD_MARGIN="0.25")
    code = "import sweep.run.compute as c; print(c._CHILD_MARGIN)"
    p = forkserver.run([], code=code, env=env, capture_output=True, text=True)
    assert p.args[0] == sys.executable and p.stdout.strip() == "0.25", p
    p = forkserver.popen([], code=code, env=env, stdout=subprocess.PIPE, text=True)
    assert not isinstance(p, forkserver.Forked) and p.communicate()[0].strip() == "0.25"
