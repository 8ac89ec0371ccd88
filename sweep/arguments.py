"""The command line's small value helpers: option types for argparse, and counted nouns.

Each option type parses one option's text or raises ``argparse.ArgumentTypeError``
saying why not.
"""
from __future__ import annotations

import argparse

__all__ = ["plural", "kind_list", "shard", "seconds", "positive_number", "count"]


def plural(n: int, noun: str) -> str:
    """``1 point``, ``2 points``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def kind_list(text: str) -> list[str]:
    """``--only fig2,fig3``: a comma-separated list (one argument, so that a store name
    after ``--only`` is never taken for a kind)."""
    return [k for k in (s.strip() for s in text.split(",")) if k]


def shard(text: str) -> tuple[int, int]:
    try:
        k, n = (int(x) for x in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--shard {text!r}: expected K/N, e.g. 3/40") from None
    if not (n >= 1 and 0 <= k < n):
        raise argparse.ArgumentTypeError(f"--shard {text!r}: need 0 <= K < N")
    return k, n


def seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected seconds") from None
    if not (0 <= value <= 3.2e7):
        raise argparse.ArgumentTypeError(f"{text!r}: expected 0 to 3.2e7 seconds")
    return value


def positive_number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a number") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a positive number")
    return value


def count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be 0 or more")
    return value
