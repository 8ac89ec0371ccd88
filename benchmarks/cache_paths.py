"""Does a point's result depend on the numba cache? Runs a campaign twice from one empty
cache directory — first compiling the kernels, then loading them — and compares.

    python benchmarks/cache_paths.py [--rev REV] [--config configs/fig2.toml]

``--rev`` exports that git revision's ``floewave`` and ``sweep`` (``git archive``) and runs
them instead of this checkout (e.g. ``--rev 57cc01b``, the last fast-math kernels, shows the
defect of issue *trust*; this checkout shows none). Prints W_c and iterations of every
point from both runs and whether every stored result column and profile is equal bit for bit.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import floewave
import sweep
from sweep.revisions import compare_stores, export_revision

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default=None)
    ap.add_argument("--config", type=Path, default=ROOT / "configs" / "fig2.toml")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="cache_paths-"))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / "numba-cache"))
    env.pop("SLURM_NTASKS", None)
    config = args.config.resolve()
    if args.rev:
        env["PYTHONPATH"] = str(export_revision(args.rev, tmp / "tree"))
        config = tmp / "tree" / "configs" / args.config.name
    stores = []
    for name in ("compiled", "cached"):
        store = tmp / f"{name}.h5"
        subprocess.run([sys.executable, "-m", "sweep", "run", str(config), "--store",
                        str(store), "--no-bar"], env=env, check=True, capture_output=True,
                       cwd=tmp)    # not this checkout's directory: it would shadow --rev
        stores.append(store)
    a, b = (sweep.load(s).set_index("hash").sort_index() for s in stores)
    version = subprocess.run([sys.executable, "-c", "import floewave; print(floewave.__file__,"
                              " floewave.MODEL_VERSION)"], env=env, cwd=tmp,
                             capture_output=True, text=True).stdout.split()
    print(f"{args.rev or 'this checkout'} ({version[0]}, model version {version[1]};"
          f" this process reads with model version {floewave.MODEL_VERSION}): {config.name},"
          " one empty numba cache, the kernels compiled in the first run and loaded in the"
          " second")
    keys = [k for k in ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
            if a[k].nunique() > 1]
    for h in a.index:
        print("  " + " ".join(f"{k}={a.loc[h, k]}" for k in keys)
              + f": W_c {a.loc[h, 'W_c']:.2f} / {b.loc[h, 'W_c']:.2f} m, iterations"
              f" {a.loc[h, 'iterations']} / {b.loc[h, 'iterations']}")
    problems, summary = compare_stores(stores[0], stores[1])
    print(summary + ("" if not problems else f", e.g. {problems[:3]}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
