"""Ensemble kernel speed against the single-chain kernel of model version 4, same run.

    python benchmarks/bench_ensemble.py [--replicas 1 4 8 16] [--seconds 0.2] [--repeat 8]
                                        [--compile] [--markdown]

For 84, 28 and 14 floes (L_x = 0.5, 1.5, 3.0 m at T = 1.2 s, the paper's lab setup) and both
drag modes it times, after compilation and a spin-up of two periods (contacts active):

- ``v4``: the single-chain kernel of model version 4: floewave/_kernels.py of commit
  :data:`V4` (one chain per call, drag of the floes with a root by the cell loop), exported
  from git at run time (``git archive``) with the two modules it imports, as the package
  ``floewave_v4``;
- ``R = ...``: today's kernel advancing R replicas in one call (floewave/_kernels.py).

The unit is floe-steps per second per core, and for an ensemble *replica*-floe-steps (R N_f
per step). Spin-up steps and averaging steps (which add the window statistics) are timed
separately: best of ``--repeat`` windows of about ``--seconds`` each, in CPU time of this
thread (a core-second; the wall clock on a shared machine also counts other processes), and
all kernels of one case (v4 and every R, spin-up and averaging) are timed round-robin, one
window each per round, so that a slow phase of a shared virtual machine (seen: the same
kernel 25 % slower for seconds at a time) slows all of them alike.
``--compile`` also times (CPU seconds), in fresh processes, the import and first point a
worker runs with an empty numba cache (compilation) and with a filled one (loading);
``--compile-base DIR`` the same for another checkout (e.g. model version 4).
"""
from __future__ import annotations

import argparse
import importlib
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from floewave import ModelConfig, solve_dispersion  # noqa: E402
from floewave import _kernels as K  # noqa: E402
from floewave.ensemble import initial_positions  # noqa: E402
from floewave.model import FloeChain  # noqa: E402
from sweep.revisions import export_revision  # noqa: E402

#: the commit whose kernel is model version 4's (the last single-chain kernel)
V4 = "218421e"


def kernel_v4(dest: Path):
    """:data:`V4`'s floewave/_kernels.py and the modules it imports (``_exact``, ``_jit``),
    exported into ``dest`` as the package ``floewave_v4``, imported."""
    export_revision(V4, dest, [f"floewave/{name}.py" for name in ("_kernels", "_exact", "_jit")])
    (dest / "floewave").rename(dest / "floewave_v4")
    (dest / "floewave_v4" / "__init__.py").write_text('"""Model version 4\'s kernel."""\n')
    sys.path.insert(0, str(dest))
    return importlib.import_module("floewave_v4._kernels")


def _window(fn, steps0: int, seconds: float) -> int:
    """Steps of a timing window of about ``seconds`` for ``fn(steps)``."""
    t = time.thread_time()
    fn(steps0)
    per = max(time.thread_time() - t, 1e-9) / steps0
    return max(int(seconds / per), 10)


def _interleaved(fns: list, seconds: float, repeat: int) -> list[float]:
    """Best seconds per step of each ``fn(steps)``, timed round-robin: ``repeat`` rounds,
    each timing one window of every function in turn, so that a slow phase of a shared
    (virtual) machine hits all of them alike instead of one case's every window."""
    steps = [_window(fn, 50, seconds) for fn in fns]
    best = [np.inf] * len(fns)
    for _ in range(repeat):
        for j, fn in enumerate(fns):
            t = time.thread_time()
            fn(steps[j])
            best[j] = min(best[j], (time.thread_time() - t) / steps[j])
    return best


def runners_v4(K4, cfg: ModelConfig) -> tuple:
    """(spin-up, averaging) step runners ``fn(steps)`` of the model-version-4 single-chain
    kernel ``K4`` (:func:`kernel_v4`; compiled, spun up); each advances ``n`` floes per step."""
    k, _ = solve_dispersion(cfg)
    ch = FloeChain(cfg, k)
    o = ch.opts
    P = K4.KernelParams(**ch.P._asdict(), contact=o.contact, damping=o.damping, clip=o.clip,
                        integrator=o.integrator, drag=o.drag)
    n = cfg.n_floes
    x, u, acc = ch.x0.copy(), np.zeros(n), np.zeros(n)
    ic = np.zeros(n, np.int8)
    work, idx = K4.new_work(n), np.zeros(n, np.int64)
    mom = K4.drag_tables(ch.cxi, ch.sxi, P)
    a = np.full(n, cfg.a0)
    st = np.zeros((K4.N_STATS, n))
    state = {"istep": 0}
    K4.initial_acceleration(x, u, a, ch.x0, 0, P, ch.cxi, ch.sxi, acc, ic)

    def run(steps, accumulate):
        state["istep"] = K4.advance(x, u, acc, a, ch.x0, ic, state["istep"], steps,
                                    accumulate, P, ch.cxi, ch.sxi, st, work, mom, idx)

    run(2 * cfg.n_t, False)
    run(10, True)
    return (lambda s: run(s, False)), (lambda s: run(s, True)), n


def runners_ensemble(cfg: ModelConfig, R: int) -> tuple:
    """(spin-up, averaging) step runners of today's kernel with R replicas (compiled, both
    loops loaded, spun up); each advances R N_f replica-floes per step."""
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg.replace(replicas=max(R, 2))))[:R]
    ch = FloeChain(cfg, k, x0)
    a = np.full(x0.shape, cfg.a0)
    st = np.zeros((K.N_STATS,) + x0.shape)
    ch.run(a, 2 * cfg.n_t)
    ch.run(a, 10, st)       # load the averaging loop too: not inside a timed window
    return (lambda s: ch.run(a, s)), (lambda s: ch.run(a, s, st)), x0.size


_FIRST_POINT = """
from floewave import ModelConfig, run_point
run_point(ModelConfig(L_x=1.5, T=1.2, max_iterations=1, n0=1, nT=1, replicas=2,
                      drag_integration={mode!r}))
"""


def first_point_seconds(mode: str, cache: str, pythonpath: str | None = None) -> float:
    """CPU seconds of a fresh process importing floewave and running a first (tiny) point
    with NUMBA_CACHE_DIR ``cache`` (``pythonpath``: another floewave checkout)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", _FIRST_POINT.format(mode=mode)], env=env, cwd=cache,
                   check=True, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--replicas", type=int, nargs="+", default=[1, 4, 8, 16])
    p.add_argument("--seconds", type=float, default=0.2)
    p.add_argument("--repeat", type=int, default=8)
    p.add_argument("--compile", action="store_true")
    p.add_argument("--compile-base", metavar="DIR", default=None,
                   help="with --compile: also time the first point of the floewave checkout"
                        " in DIR (e.g. a worktree of 218421e, model version 4)")
    p.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = p.parse_args()
    Rs = args.replicas
    cols = ["v4"] + [f"R={R}" for R in Rs]
    ref = Rs.index(8) if 8 in Rs else len(Rs) - 1     # the ratio column: R = 8, the default
    if args.markdown:
        print("| drag | N_f | step | " + " | ".join(cols) + f" | R={Rs[ref]} / v4 |")
        print("|---|---|---|" + "---|" * (len(cols) + 1))
    else:
        print(f"{'drag':<11}{'N_f':>4} {'step':<6}" + "".join(f"{c:>9}" for c in cols)
              + f"{f'R={Rs[ref]}/v4':>9}   [M (replica-)floe-steps/s, one core]")
    K4 = kernel_v4(Path(tempfile.mkdtemp(prefix="bench_ensemble-")))
    for mode in ("quadrature", "exact"):
        for L_x in (0.5, 1.5, 3.0):
            cfg = ModelConfig(L_x=L_x, T=1.2, drag_integration=mode)
            kernels = [runners_v4(K4, cfg)] + [runners_ensemble(cfg, R) for R in Rs]
            fns = [ker[j] for ker in kernels for j in (0, 1)]
            best = _interleaved(fns, args.seconds, args.repeat)
            rates = [kernels[i // 2][2] / b for i, b in enumerate(best)]
            for j, step in enumerate(("spin", "avg")):
                vals = rates[j::2]
                ratio = vals[1 + ref] / vals[0]
                if args.markdown:
                    print(f"| {mode} | {cfg.n_floes} | {step} | "
                          + " | ".join(f"{v / 1e6:.1f}" for v in vals)
                          + f" | {ratio:.2f} |")
                else:
                    print(f"{mode:<11}{cfg.n_floes:>4} {step:<6}"
                          + "".join(f"{v / 1e6:>9.1f}" for v in vals)
                          + f"{ratio:>9.2f}", flush=True)
    if args.compile:
        for mode in ("quadrature", "exact"):
            for label, path in (("this checkout", None), (args.compile_base, args.compile_base)):
                if label is None:
                    continue
                with tempfile.TemporaryDirectory() as cache:
                    cold = first_point_seconds(mode, cache, path)
                    warm = first_point_seconds(mode, cache, path)
                print(f"first point of a worker, {label} ({mode}): {cold:.1f} CPU s with an"
                      f" empty numba cache (compiles), {warm:.1f} CPU s with a filled one"
                      f" (loads)", flush=True)


if __name__ == "__main__":
    main()
