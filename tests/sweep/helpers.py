"""Shared helpers of the store tests: a store's table without what differs between runs, and
a store marked unclean (a writer that did not close it)."""
from __future__ import annotations

import h5py

import sweep


def table(path):
    """The stored rows by hash, without the columns a rerun changes (seq, run, host, pid,
    times, provenance)."""
    df = sweep.load(path).set_index("hash").sort_index()
    return df.drop(columns=["seq", "run", "host", "pid", "start_time", "end_time",
                            "wall_time", "provenance"])


def make_unclean(path):
    """Mark the store as left open by a writer (its next open rebuilds or checks it)."""
    with h5py.File(path, "r+", locking=False) as f:
        f.attrs["writer_open"] = True
