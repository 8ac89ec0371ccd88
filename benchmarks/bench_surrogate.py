"""The surrogate's speed: loading it, and a prediction per point.

    python benchmarks/bench_surrogate.py [--file results/surrogate/surrogate.npz]

Prints the load time (a fresh interpreter's import of herman2019.surrogate and
``Surrogate.load``, best of 3), and microseconds per point of ``Surrogate.predict`` (every
quantity with its SE and p_zone) for 1, 1,000 and 100,000 points, against a baseline
measured in the same run: scipy's ``RegularGridInterpolator`` (linear) of one quantity on
the same points (the surrogate computes 4 quantities, their two SE parts and p_zone).
Name the machine with the figures (stochastic timings).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def best(f, repeat=3):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--file", default=str(ROOT / "results" / "surrogate" / "surrogate.npz"))
    args = ap.parse_args()
    from scipy.interpolate import RegularGridInterpolator

    from herman2019.numbers import machine
    from herman2019.surrogate import AXES, Surrogate
    from herman2019.surrogate.grid import coordinate
    print(f"[machine] {machine()}")
    code = ("import time; t = time.perf_counter(); from herman2019.surrogate import Surrogate;"
            f" Surrogate.load({args.file!r}); print(time.perf_counter() - t)")
    loads = [float(subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True,
                                  capture_output=True, text=True).stdout) for _ in range(3)]
    print(f"load (import + Surrogate.load, fresh interpreter): {min(loads) * 1e3:.0f} ms"
          f" (best of 3)")
    sur = Surrogate.load(args.file)
    rng = np.random.default_rng(0)
    lv = sur.levels
    y = sur.fields["ml"][:, sur.column("y_alpha_all")].reshape([len(lv[a]) for a in AXES])
    rgi = RegularGridInterpolator([coordinate(a, lv[a]) for a in AXES], y)
    for n in (1, 1000, 100_000):
        q = {a: np.exp(rng.uniform(np.log(lv[a][0]), np.log(lv[a][-1]), n)) for a in AXES}
        t = best(lambda q=q: sur.predict("ml", **q))
        x = np.stack([coordinate(a, q[a]) for a in AXES], axis=1)
        t0 = best(lambda x=x: rgi(x))
        print(f"{n:>7,} points: surrogate {t / n * 1e6:10.2f} us/point;"
              f" baseline (scipy RegularGridInterpolator, linear, one quantity)"
              f" {t0 / n * 1e6:8.2f} us/point; ratio {t / t0:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
