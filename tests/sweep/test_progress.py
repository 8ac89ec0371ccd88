"""sweep.run.progress: the master's progress lines (counts, rate, ETA) and the tqdm bar."""
from __future__ import annotations

import io
import re
import types

import pytest

from sweep.run import progress as progress_mod
from sweep.run.progress import Progress, format_duration, log_line

LINE = re.compile(r"^\[sweep \d{4}-\d\d-\d\d \d\d:\d\d:\d\d\] (.*)$")


@pytest.mark.parametrize("seconds, text", [
    (0, "0s"), (4.4, "4s"), (59.6, "1m00s"), (61, "1m01s"), (3723, "1h02m03s"),
    (36000, "10h00m00s"), (float("nan"), "?"), (float("inf"), "?"), (-1, "?")])
def test_format_duration(seconds, text):
    assert format_duration(seconds) == text


def test_log_line_is_stamped():
    out = io.StringIO()
    log_line("hello", out)
    lines = out.getvalue().splitlines()
    assert len(lines) == 1 and LINE.match(lines[0]).group(1) == "hello"


@pytest.fixture
def clock(monkeypatch):
    """A hand-moved clock for sweep.run.progress (``clock.now`` seconds)."""
    fake = types.SimpleNamespace(now=100.0)
    monkeypatch.setattr(progress_mod, "time", types.SimpleNamespace(
        monotonic=lambda: fake.now, strftime=lambda fmt: "2026-01-01 00:00:00"))
    return fake


def lines(stream):
    return [LINE.match(x).group(1) for x in stream.getvalue().splitlines()]


def test_counts_rate_eta_and_lines(clock):
    out = io.StringIO()
    p = Progress(4, interval=10.0, stream=out, bar=False, skipped=2)
    assert lines(out) == ["4 points to compute (2 already stored)"]
    assert p.rate == 0.0 and p.eta == float("inf") and "ETA ?" in p.summary()
    clock.now += 2.0
    p.update("converged")
    p.update("failed")
    assert (p.done, p.failed) == (2, 1)
    assert p.rate == pytest.approx(1.0) and p.eta == pytest.approx(2.0)
    assert len(lines(out)) == 1  # the interval has not passed
    clock.now += 10.0
    p.tick()  # due: one line while waiting
    assert lines(out)[-1] == ("2/4 done, 1 failed, 2 remaining, 0.167 points/s,"
                              " elapsed 12s, ETA 12s")
    p.tick()
    assert len(lines(out)) == 2  # not due again
    p.update("crashed")  # only 'failed' counts as failed
    p.update("timeout")
    assert (p.done, p.failed) == (4, 1)
    p.close()
    assert lines(out)[-1].startswith("4/4 done, 1 failed, 0 remaining,")


def test_one_point_is_singular_and_update_logs_when_due(clock):
    out = io.StringIO()
    p = Progress(1, interval=0.0, stream=out, bar=False)
    assert lines(out) == ["1 point to compute (0 already stored)"]
    clock.now += 1.0
    p.update("converged")
    assert lines(out)[-1].startswith("1/1 done, 0 failed, 0 remaining, 1 points/s")


def test_the_bar_is_drawn_on_request_and_closed_with_a_line():
    pytest.importorskip("tqdm")
    out = io.StringIO()
    p = Progress(3, stream=out, bar=True)
    assert "to compute" not in out.getvalue()  # the bar replaces the first line
    p.update("failed")
    p.update("converged")
    p.close()
    text = out.getvalue()
    assert "2/3" in text and "failed=1" in text
    assert lines(io.StringIO(text.splitlines()[-1] + "\n"))[-1].startswith(
        "2/3 done, 1 failed, 1 remaining")
    assert not Progress(1, stream=io.StringIO(), bar=None)._bar  # not a terminal: no bar
