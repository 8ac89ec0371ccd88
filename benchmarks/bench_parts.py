"""Where a time step's cost goes: the drag's parts against the whole step, per floe.

    python benchmarks/bench_parts.py [--replicas 8] [--repeat 7]

For 84, 28 and 14 floes (L_x = 0.5, 1.5, 3.0 m at T = 1.2 s) and both drag modes, an
ensemble of R replicas from random arrangements is spun up for two periods (contacts
active), and then, at that state (positions and velocities held, the wave phase advancing
step by step as in a run), timed in CPU time of this thread, best of ``--repeat``:

- ``step``: the whole spin-up step of the time loop (``FloeChain.run``), per replica-floe;
- ``drag``: the drag evaluation of every floe (``drag_pass`` / ``exact_pass``), per floe;
- ``closed``: the same with every floe's velocity set far above the orbital velocity, so
  that no floe has a root and only the closed form (and the flagging) runs, per floe;
- ``root``: ``(drag - closed) / share``, the extra cost of a floe with a root of w on it
  (the root enumeration and prefix sums), per such floe; ``share`` is the fraction of
  floes with a root at that state;
- ``rest``: ``step - drag``: drift, wave and drag forces, contacts, edge springs and kick.

All in ns. A lower bound follows for any kernel that keeps this arithmetic: ``closed +
rest`` per floe-step is paid whatever the root path costs.
"""
from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from floewave import ModelConfig, solve_dispersion  # noqa: E402
from floewave import _kernels as K  # noqa: E402
from floewave.ensemble import initial_positions  # noqa: E402
from floewave.model import FloeChain  # noqa: E402


@njit(error_model="numpy", nogil=True)
def _drag_steps(nsteps, exact, ck, sk, a, vs, P, cxi, sxi, mom, sc, idx):
    """``nsteps`` drag evaluations at the phases of consecutive time steps; the number of
    floes with a root, summed."""
    roots = 0
    for istep in range(nsteps):
        wt = 2.0 * math.pi / P.n_t * (istep % P.n_t)
        cwt = math.cos(wt)
        swt = math.sin(wt)
        if exact:
            roots += K.exact_pass(ck, sk, cwt, swt, a, vs, P, mom, False, sc, idx)
        else:
            roots += K.drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, False, sc, idx)
    return roots


def _best(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t)
    return best


def parts(cfg: ModelConfig, R: int, repeat: int, steps: int = 600) -> dict:
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg.replace(replicas=max(R, 2))))[:R]
    ch = FloeChain(cfg, k, x0)
    a = np.full(x0.shape, cfg.a0)
    ch.run(a, 2 * cfg.n_t)
    n = x0.size
    step = _best(lambda: ch.run(a, steps), repeat) / steps / n
    x = ch.x.ravel().copy()
    ck, sk = np.cos(k * x), np.sin(k * x)
    vs = ch.u.ravel().copy()
    af = a.ravel().copy()
    sc, idx = K.new_scratch(n), np.zeros(n, np.int64)
    exact = ch.P.drag == K.DRAG_EXACT
    args = (exact, ck, sk, af, vs, ch.P, ch.cxi, ch.sxi, ch.mom, sc, idx)
    fast = (exact, ck, sk, af, np.full(n, 1e3), ch.P, ch.cxi, ch.sxi, ch.mom, sc, idx)
    share = _drag_steps(steps, *args) / steps / n
    _drag_steps(2, *fast)
    drag = _best(lambda: _drag_steps(steps, *args), repeat) / steps / n
    closed = _best(lambda: _drag_steps(steps, *fast), repeat) / steps / n
    root = (drag - closed) / share if share > 0 else float("nan")
    return dict(step=step, drag=drag, closed=closed, root=root, share=share,
                rest=step - drag)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--replicas", type=int, default=8)
    p.add_argument("--repeat", type=int, default=7)
    args = p.parse_args()
    print(f"R = {args.replicas}; ns per (replica-)floe and step, CPU time, best of"
          f" {args.repeat}; 'root' per floe with a root")
    print(f"{'drag':<11}{'N_f':>4}{'step':>8}{'drag':>8}{'closed':>8}{'root':>8}"
          f"{'share':>7}{'rest':>8}{'closed+rest':>13}")
    for mode in ("quadrature", "exact"):
        for L_x in (0.5, 1.5, 3.0):
            cfg = ModelConfig(L_x=L_x, T=1.2, drag_integration=mode)
            r = {key: (v * 1e9 if key != "share" else v)
                 for key, v in parts(cfg, args.replicas, args.repeat).items()}
            print(f"{mode:<11}{cfg.n_floes:>4}{r['step']:>8.1f}{r['drag']:>8.1f}"
                  f"{r['closed']:>8.1f}{r['root']:>8.1f}{r['share']:>7.2f}{r['rest']:>8.1f}"
                  f"{r['closed'] + r['rest']:>13.1f}", flush=True)


if __name__ == "__main__":
    main()
