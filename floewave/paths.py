"""Outputs: paths checked before any work starts (a result is never computed and then
lost), and stdout quieted when its reader has gone.

Both command-line programs (``floewave run --json/--plot``, ``sweep figures --out``,
``sweep export -o``) call these first; each returns ``None`` when the path can be written
and otherwise one sentence naming the path and the reason.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["output_file_problem", "output_dir_problem", "quiet_stdout"]


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def output_file_problem(path: str | Path, option: str) -> str | None:
    """Why ``path`` cannot be written as a file (``None`` if it can).

    The directory must exist (it is not created: a typo in it should not make a tree)
    and be writable; ``path`` itself must not be a directory.
    """
    p = Path(path)
    parent = p.absolute().parent
    if p.is_dir():
        return f"{option} {path}: is a directory, expected a file name"
    if not parent.is_dir():
        return f"{option} {path}: directory {parent} does not exist"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"{option} {path}: directory {parent} is not writable"
    if p.exists() and not os.access(p, os.W_OK):
        return f"{option} {path}: file exists and is not writable"
    return None


def output_dir_problem(path: str | Path, option: str) -> str | None:
    """Why ``path`` cannot be used (or created) as an output directory (``None`` if it can)."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        return f"{option} {path}: exists and is not a directory"
    base = _nearest_existing(p)
    if not base.is_dir():
        return f"{option} {path}: {base} is not a directory"
    if not os.access(base, os.W_OK | os.X_OK):
        if base == p.absolute():
            return f"{option} {path}: directory {base} is not writable"
        return f"{option} {path}: cannot be created: {base} is not writable"
    return None


def quiet_stdout() -> None:
    """Point stdout at /dev/null: its reader went away (``... | head``), so what is left to
    print, and the flush at exit, go nowhere instead of raising BrokenPipeError."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
