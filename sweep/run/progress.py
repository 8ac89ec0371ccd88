"""Progress of a campaign on the master: done / failed / remaining, rate and ETA.

On a terminal (and with tqdm importable) a tqdm bar is drawn on stderr; otherwise one
log line is written every ``interval`` seconds (and at the end), which is what a batch
log wants.
"""
from __future__ import annotations

import logging
import sys
import time
from typing import Any, TextIO

__all__ = ["Progress", "format_duration", "log_line"]

log = logging.getLogger("sweep")


def format_duration(seconds: float) -> str:
    """``1h02m03s`` style; ``?`` for unknown."""
    if seconds != seconds or seconds == float("inf") or seconds < 0:
        return "?"
    s = int(round(seconds))
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}h{m:02d}m{s:02d}s" if h else (f"{m}m{s:02d}s" if m else f"{s}s")


def log_line(text: str, stream: TextIO | None = None) -> None:
    """``[sweep 2026-11-30 12:00:00] text`` on ``stream`` (default stderr)."""
    stamp = time.strftime("%Y-%m-%d %H:%M:%S")
    print(f"[sweep {stamp}] {text}", file=stream or sys.stderr, flush=True)


class Progress:
    """Counts points as they are stored and reports rate and ETA.

    Parameters
    ----------
    total : points this run has to compute.
    interval : seconds between log lines when not drawing a bar.
    stream : where to write (default stderr).
    bar : force the tqdm bar on (True) or off (False); default: if ``stream`` is a
        terminal and tqdm is importable.
    """

    def __init__(self, total: int, *, interval: float = 30.0, stream: TextIO | None = None,
                 bar: bool | None = None, skipped: int = 0) -> None:
        self.total = total
        self.interval = interval
        self.stream = stream or sys.stderr
        self.done = 0
        self.failed = 0
        self.skipped = skipped
        self.t0 = time.monotonic()
        self._last = self.t0
        self._bar: Any = None
        if bar is None:
            bar = bool(getattr(self.stream, "isatty", lambda: False)())
        if bar:
            try:
                from tqdm import tqdm  # lazy: optional; 20 ms for every sweep command
            except ImportError:
                bar = False
            else:
                self._bar = tqdm(total=total, file=self.stream, unit="pt", dynamic_ncols=True,
                                 smoothing=0.1)
        if not self._bar:
            noun = "point" if total == 1 else "points"
            self._line(f"{total} {noun} to compute ({skipped} already stored)")

    @property
    def rate(self) -> float:
        """Points per second so far."""
        elapsed = time.monotonic() - self.t0
        return self.done / elapsed if elapsed > 0 else 0.0

    @property
    def eta(self) -> float:
        """Seconds to go at the current rate (inf when unknown)."""
        r = self.rate
        return (self.total - self.done) / r if r > 0 else float("inf")

    def summary(self) -> str:
        """``done/total (failed) rate ETA`` in one line."""
        return (f"{self.done}/{self.total} done, {self.failed} failed,"
                f" {self.total - self.done} remaining, {self.rate:.3g} points/s,"
                f" elapsed {format_duration(time.monotonic() - self.t0)},"
                f" ETA {format_duration(self.eta)}")

    def update(self, status: str) -> None:
        """Count one stored point with its status."""
        self.done += 1
        if status == "failed":
            self.failed += 1
        if self._bar is not None:
            self._bar.set_postfix(failed=self.failed, refresh=False)
            self._bar.update(1)
            return
        now = time.monotonic()
        if now - self._last >= self.interval:
            self._last = now
            self._line(self.summary())

    def tick(self) -> None:
        """Called while waiting: writes a log line if one is due."""
        if self._bar is None and time.monotonic() - self._last >= self.interval:
            self._last = time.monotonic()
            self._line(self.summary())

    def close(self) -> None:
        """Final line."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self._line(self.summary())

    def _line(self, text: str) -> None:
        log_line(text, self.stream)
