"""The guard of ``sweep run`` (sweep/run/guard.py) ends as its child ended, by the same
signal, for every signal a child can die of: SIGKILL included (which has no handler to
reset, so the guard must not try), without a traceback."""
from __future__ import annotations

import os
import signal
import traceback

import pytest

from sweep.run.guard import _guard  # noqa: PLC2701 - the guard's loop, tested on its own


def _guard_of_a_child_killed_by(sig: int, err_path) -> int:
    """The wait status of a process that runs the guard over a child that dies by ``sig``;
    the guard's stderr goes to ``err_path``."""
    pid = os.fork()
    if pid == 0:  # the guard's process
        code = 99
        try:
            fd = os.open(err_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
            os.dup2(fd, 2)
            r, w = os.pipe()
            child = os.fork()
            if child == 0:
                os.close(r)
                if sig != signal.SIGKILL:  # as a campaign would (nohup may ignore SIGHUP)
                    signal.signal(sig, signal.SIG_DFL)
                os.kill(os.getpid(), sig)
                os._exit(0)  # pragma: no cover - the signal ends it first
            os.close(w)
            code = _guard(child, r, set())
        except BaseException:  # noqa: BLE001 - the test reads what went wrong
            traceback.print_exc()
            code = 98
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    return status


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGHUP])
def test_the_guard_ends_by_its_childs_signal_without_a_traceback(tmp_path, sig):
    err = tmp_path / "err"
    status = _guard_of_a_child_killed_by(sig, err)
    text = err.read_text()
    assert "Traceback" not in text, text
    assert os.WIFSIGNALED(status), (os.waitstatus_to_exitcode(status), text)
    assert os.WTERMSIG(status) == sig
