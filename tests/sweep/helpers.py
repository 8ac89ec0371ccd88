"""Shared helpers of the store tests: a store's table without what differs between runs, a
store marked unclean (a writer that did not close it), and another process holding a store
open as its writer."""
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


def partial_shard(campaign, lo: float = 0.25, hi: float = 0.75):
    """Shard 0 of the fewest shards (2, 3, ...) whose shard 0 holds between ``lo`` and
    ``hi`` of the campaign's points: some stored, some missing, whatever the point hashes
    (which points a shard holds follows the hashes, and they change with every model
    version)."""
    total = len(campaign.points())
    for n in range(2, 16):
        part = campaign.shard(0, n)
        if lo * total <= len(part.points()) <= hi * total:
            return part
    raise AssertionError(f"no shard count splits these {total} points")


def split_shards(campaign) -> list:
    """The campaign as the fewest shards (2, 3, ...) of which at least two hold points."""
    for n in range(2, 16):
        parts = [campaign.shard(k, n) for k in range(n)]
        if sum(1 for p in parts if p.points()) >= 2:
            return parts
    raise AssertionError("no shard count splits these points")


_HOLD = """
import sys, sweep
from sweep.store.store import Store
s = Store(sys.argv[1], sweep.parse_campaign(sys.argv[2]))
print("locked", flush=True)
sys.stdin.read()
"""


def store_holder(path, toml: str):
    """Another process (tests/forkserver.py) that has opened the store ``path`` of the
    campaign ``toml`` as its writer and holds it until killed or its stdin closes."""
    import subprocess

    from tests import forkserver

    holder = forkserver.popen([path, toml], code=_HOLD, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "locked"
    return holder


def suspect_with_a_full_disk(path, campaign, monkeypatch):
    """Leave the first point of ``campaign`` at ``path`` as a suspect (a run died while it
    ran alone), and make every journal write of a record fail with ENOSPC from now on
    (hand-outs and releases still fit: the store's writer, or a forked writer process,
    breaks at its first commit). Returns that point."""
    import errno
    import os

    import sweep.store.journal
    from sweep.store.store import Store

    first = next(iter(campaign.points()))
    with Store(path, campaign) as st:
        st.handout([(first.hash, 1)])
    real = sweep.store.journal.Journal.append

    def append(self, lines, sync=True):
        if any(line.startswith(b'{"row"') for line in lines):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(self, lines, sync)

    monkeypatch.setattr(sweep.store.journal.Journal, "append", append)
    return first
