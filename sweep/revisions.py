"""Another revision of this checkout beside it: export one from git, compare two stores.

:func:`export_revision` writes some folders of a git revision of the repository this
package lives in to a directory (``git archive``: no worktree, nothing written to the
repository), to put on ``PYTHONPATH`` in a subprocess. :func:`compare_stores` compares two
campaign stores bit for bit: every table column but :data:`RUN_SPECIFIC` row for row (rows
matched by hash) and every profile dataset byte for byte. It reads the HDF5 files with
h5py alone, so it compares stores written by any revision's store code. The benchmarks that
check a change against an older commit use both (``benchmarks/kernel_bits.py --store``,
``benchmarks/cache_paths.py``).
"""
from __future__ import annotations

import io
import subprocess
import tarfile
from collections.abc import Collection
from pathlib import Path

import h5py
import numpy as np

from sweep.store.schema import ADDED_IN

#: the git checkout this package lives in
REPOSITORY = Path(__file__).resolve().parent.parent

#: table columns that say how, where and when a point ran, not what it is or gave
RUN_SPECIFIC = frozenset({"host", "rank", "pid", "start_time", "end_time", "wall_time",
                          "model_wall_time", "run", "seq", "provenance"})


def export_revision(rev: str, dest: Path, paths=("floewave", "sweep", "configs"),
                    repository: Path = REPOSITORY) -> Path:
    """Export ``paths`` of git revision ``rev`` of ``repository`` into ``dest``; returns
    ``dest``, to put on ``PYTHONPATH``."""
    data = subprocess.run(["git", "-C", str(repository), "archive", "--format=tar", rev,
                           *paths], check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(dest, filter="data")
    return Path(dest)


def _text(values) -> list[str]:
    return [v.decode() if isinstance(v, bytes) else str(v) for v in values]


def _table(f: h5py.File) -> dict[str, np.ndarray]:
    t = f["table"]
    n = int(t.attrs["n_rows"])
    return {k: t[k][:n] for k in t}


def columns_added_since(path: Path) -> frozenset[str]:
    """The table columns this sweep's schema added after the schema version of the store
    at ``path`` (:data:`sweep.store.schema.ADDED_IN`)."""
    with h5py.File(path, "r", locking=False) as f:
        version = int(f.attrs.get("schema_version", 1))
    return frozenset(name for name, v in ADDED_IN.items() if v > version)


def compare_stores(a: Path, b: Path, added: Collection[str] = ()) -> tuple[list[str], str]:
    """(differences, summary line) of stores ``a`` and ``b``: equal when the list is empty.

    Equal means: the same columns and the same set of hashes; per column but
    :data:`RUN_SPECIFIC`, the rows (matched by hash) equal (floats byte for byte, so
    -0.0 is not +0.0 and NaN must be the same NaN); per point the same profile datasets,
    each byte for byte. ``added``: columns that ``b`` may hold and ``a`` not (a later
    schema's, :func:`columns_added_since`); named in the summary, not compared."""
    problems: list[str] = []
    with h5py.File(a, "r", locking=False) as fa, h5py.File(b, "r", locking=False) as fb:
        ta, tb = _table(fa), _table(fb)
        extra = sorted(set(tb) - set(ta) & set(added))
        for k in extra:
            del tb[k]
        if set(ta) != set(tb):
            problems.append(f"columns differ: {sorted(set(ta) ^ set(tb))}")
        ha, hb = _text(ta["hash"]), _text(tb["hash"])
        if sorted(ha) != sorted(hb):
            problems.append(f"hash sets differ: {len(set(ha) - set(hb))} only in {a},"
                            f" {len(set(hb) - set(ha))} only in {b}")
            return problems, f"{len(ha)} / {len(hb)} rows: DIFFERENT POINTS"
        ia, ib = np.argsort(ha), np.argsort(hb)
        for k in sorted(set(ta) & set(tb) - RUN_SPECIFIC):
            x, y = ta[k][ia], tb[k][ib]
            same = (x.dtype == y.dtype and x.tobytes() == y.tobytes()) \
                if x.dtype.kind == "f" else np.array_equal(x, y)
            if not same:
                problems.append(f"column differs: {k}")
        n = 0
        for h in ha:
            name = f"profiles/{h[:2]}/{h}"
            if (name in fa) != (name in fb):
                problems.append(f"profile group in one store only: {h}")
                continue
            if name not in fa:
                continue
            ga, gb = fa[name], fb[name]
            if set(ga) != set(gb):
                problems.append(f"profile sets differ: {h}")
                continue
            for var in ga:
                n += 1
                if ga[var][()].tobytes() != gb[var][()].tobytes():
                    problems.append(f"profile differs: {h} {var}")
    summary = (f"{len(ha)} rows, {len(ta)} columns ({len(RUN_SPECIFIC & set(ta))}"
               f" run-specific skipped"
               + (f"; only in the second, of a later schema: {', '.join(extra)}" if extra
                  else "") + f"), {n} profile datasets: "
               + ("EQUAL" if not problems else f"{len(problems)} DIFFERENCES"))
    return problems, summary
