"""Dump the stores and journals of a few small campaigns with times, pids, hosts and paths masked.

Used to show that a refactor of ``sweep`` leaves the stored bytes and the journals
unchanged: run it before and after, and ``diff`` the two dumps::

    python -m tests.sweep.store_bytes > before.txt   # on the old code
    python -m tests.sweep.store_bytes > after.txt    # on the new code
    diff before.txt after.txt && echo identical

(from the repository's root; in older checkouts
``python benchmarks/store_bytes.py``).

The campaigns (stand-in compute functions of :mod:`sweep.testing`, no DEM kernel):

1. ``configs/demo.toml`` with ``power_point``, in-process (16 points);
2. a 2 x 2 x 2 grid with ``raising_point`` (failures) and ``nan_point`` (NaN
   amplitudes), then resumed with ``--retry-failed`` (two runs in one store);
3. ``configs/demo.toml`` with ``power_point`` under ``mpiexec -n 3`` (master and two
   workers), if ``mpiexec`` is found; rows and journal lines are sorted by content and
   ``seq`` is masked, since the order of completion is not deterministic;
4. ``sweep merge`` of two shard stores of campaign 2.

Every HDF5 attribute and dataset is printed (dtype, shape and values); JSON strings are
parsed and masked recursively. Masked: keys naming a time, a pid, a host, a rank, a
command line, a git commit, a wall time or a journal checksum (which covers the masked
fields), the temporary directory's path, and in messages the traceback's frames and pids.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
MASKED = re.compile(r"^(time|created|started|ended|start_time|end_time|wall_time|"
                    r"model_wall_time|pid|host|rank|worker|command|git_commit|git_dirty|"
                    r"crc32|elapsed|rebuilt_from_journal)$")
#: Inside messages: the traceback's frames (files, lines) and the worker's pid.
FRAMES = re.compile(r'  File "[^"]*", line \d+, in .*\n(    .*\n)*')
PID = re.compile(r"pid \d+")
SMALL = """\
[base]
L_sheet = 12.0
[sweep]
L_x = [0.5, 1.5]
eps = [0.2, 0.4]
d_f = [0.005, 0.01]
[run]
name = "bytes"
"""


#: Also masked in the MPI campaign: the order in which the two workers' results arrive.
ORDER = re.compile(r"^seq$")


def mask(value, tmp: str, unordered: bool = False):
    """``value`` with masked keys replaced by ``"*"`` and ``tmp`` by ``TMP``."""
    if isinstance(value, dict):
        return {k: "*" if MASKED.match(str(k)) or (unordered and ORDER.match(str(k)))
                else mask(v, tmp, unordered) for k, v in value.items()}
    if isinstance(value, list):
        return [mask(v, tmp, unordered) for v in value]
    if isinstance(value, str):
        text = value.strip()
        if text[:1] in "{[":
            try:
                return mask(json.loads(text), tmp, unordered)
            except ValueError:
                pass
        value = FRAMES.sub("  <frames>\n", value.replace(tmp, "TMP"))
        return PID.sub("pid *", value)
    return value


def plain(value, tmp: str):
    """An HDF5 value as JSON-able Python, masked."""
    if isinstance(value, bytes):
        return mask(value.decode(), tmp)
    if isinstance(value, np.ndarray):
        return [plain(v, tmp) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    return mask(value, tmp)


def dump_store(path: Path, tmp: str, unordered: bool) -> list[str]:
    """Lines describing every attribute and dataset of the store at ``path``."""
    out: list[str] = []
    with h5py.File(path, "r") as f:
        columns = {}
        if "table" in f and unordered:
            order = np.argsort(f["table/hash"][...].astype(str))
        else:
            order = None

        def attrs(name, obj):
            for key in sorted(obj.attrs):
                shown = "*" if MASKED.match(key) else plain(obj.attrs[key], tmp)
                out.append(f"@{name}:{key} = {json.dumps(shown, sort_keys=True)}")

        attrs("/", f)

        def visit(name, obj):
            attrs(name, obj)
            if isinstance(obj, h5py.Dataset):
                leaf = name.rsplit("/", 1)[-1]
                data = obj[...]
                if order is not None and name.startswith("table/"):
                    data = data[order]
                hidden = MASKED.match(leaf) or (unordered and ORDER.match(leaf))
                shown = "*" if hidden else plain(np.asarray(data), tmp)
                columns[name] = f"{obj.dtype} {obj.shape} {obj.chunks} {obj.compression} "
                out.append(f"{name} {columns[name]}= {json.dumps(shown, sort_keys=True)}")

        f.visititems(visit)
    return out


def dump_journal(path: Path, tmp: str, unordered: bool) -> list[str]:
    """The journal's lines, parsed and masked (sorted if ``unordered``)."""
    lines = []
    for raw in path.read_bytes().splitlines():
        lines.append(json.dumps(mask(json.loads(raw), tmp, unordered), sort_keys=True))
    return sorted(lines) if unordered else lines


def sweep(*args: str, mpi: int = 0, cwd: str) -> None:
    """Run the ``sweep`` command (under ``mpiexec -n mpi`` if ``mpi``)."""
    cmd = [sys.executable, "-m", "sweep", *args]
    if mpi:
        from sweep.testing import find_mpiexec
        cmd = [find_mpiexec(), "-n", str(mpi), *cmd]
    env = dict(os.environ, PYTHONHASHSEED="0")
    subprocess.run(cmd, cwd=cwd, check=True, env=env, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)


def main() -> int:
    demo = str(ROOT / "configs" / "demo.toml")
    with tempfile.TemporaryDirectory() as tmp:
        small = Path(tmp, "small.toml")
        small.write_text(SMALL)
        stores: list[tuple[str, bool]] = []
        sweep("run", demo, "--store", "demo.h5", "--no-bar",
              "--compute", "sweep.testing:power_point", cwd=tmp)
        stores.append(("demo.h5", False))
        sweep("run", str(small), "--store", "small.h5", "--no-bar",
              "--compute", "sweep.testing:raising_point", cwd=tmp)
        sweep("run", str(small), "--store", "small.h5", "--no-bar", "--retry-failed",
              "--compute", "sweep.testing:nan_point", cwd=tmp)
        stores.append(("small.h5", False))
        for k in (0, 1):
            sweep("run", str(small), "--store", f"shard{k}.h5", "--no-bar",
                  "--shard", f"{k}/2", "--compute", "sweep.testing:fake_point", cwd=tmp)
        sweep("merge", "merged.h5", "shard0.h5", "shard1.h5", cwd=tmp)
        stores.append(("merged.h5", False))
        try:
            sweep("run", demo, "--store", "mpi.h5", "--no-bar",
                  "--compute", "sweep.testing:power_point", mpi=3, cwd=tmp)
            stores.append(("mpi.h5", True))
        except (OSError, subprocess.CalledProcessError) as exc:
            print(f"# MPI campaign skipped: {exc}")
        for name, unordered in stores:
            print(f"# store {name}")
            print("\n".join(dump_store(Path(tmp, name), tmp, unordered)))
            journal = Path(tmp, name + ".journal")
            if journal.exists():
                print(f"# journal {name}.journal")
                print("\n".join(dump_journal(journal, tmp, unordered)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
