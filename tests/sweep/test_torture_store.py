"""The store's torture (issue 15, :mod:`tests.sweep.torture_store`), small, in the slow tier:
kills at random instants of run, resume-rebuild, retry, extend and merge, the journal
corruptions, compute faults, stops during start-up, reads during writes, hostile inputs and
issue 26's holes; every phase finished and compared with an uninterrupted run."""
from __future__ import annotations

import pytest

from tests.sweep.torture_store import main


@pytest.mark.slow  # minutes: fake points, many fresh interpreters
def test_store_torture(tmp_path, capsys):
    rc = main(["--kills", "12", "--holes", "1", "--seed", "15", "--workdir", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0, out[-4000:]
