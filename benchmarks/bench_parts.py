"""Where a time step's cost goes: the drag's parts against the whole step, per floe.

    python benchmarks/bench_parts.py [--replicas 8] [--repeat 5] [--states 12]

For 84, 28 and 14 floes (L_x = 0.5, 1.5, 3.0 m at T = 1.2 s, amplitude a0 on every floe:
a run's first iteration) and both drag modes, an ensemble of R replicas from random
arrangements is spun up for two periods (contacts active); over the next period, timed in
CPU time of this thread, best of ``--repeat``:

- ``step``: the whole spin-up step of the time loop (``FloeChain.run``), per replica-floe;
- ``drag``: the drag evaluation of every floe (``drag_pass`` / ``exact_pass``), per floe,
  at ``--states`` states of that same period (positions, the velocity the forces use, the
  wave phase: recorded as the run passed them), each timed on its own (it stays in cache),
  averaged over the states;
- ``closed``: the same with every floe's velocity set far above the orbital velocity, so
  that no floe has a root and only the closed form (and the flagging) runs, per floe;
- ``root``: ``(drag - closed) / share``, the extra cost of a floe with a root of w on it
  (the root enumeration and prefix sums), per such floe; ``share`` is the fraction of
  floes with a root at the recorded states;
- ``rest``: ``step - drag``: drift, wave and drag forces, contacts, edge springs and kick.

All in ns, each a difference of timings on a shared machine (an estimate, not a bound):
``closed + rest`` is roughly what a step costs however cheap the root path were.
"""
from __future__ import annotations

import argparse
import functools
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
def _drag_calls(ncalls, exact, ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, sc, idx):
    """``ncalls`` drag evaluations of one state; the number of floes with a root."""
    m = 0
    for _ in range(ncalls):
        if exact:
            m = K.exact_pass(ck, sk, cwt, swt, a, vs, P, mom, False, sc, idx)
        else:
            m = K.drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, False, sc, idx)
    return m


def _best(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t)
    return best


def parts(cfg: ModelConfig, R: int, repeat: int, nstates: int, ncalls: int = 200) -> dict:
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg.replace(replicas=max(R, 2))))[:R]
    ch = FloeChain(cfg, k, x0)
    a = np.full(x0.shape, cfg.a0)
    ch.run(a, 2 * cfg.n_t)
    n = x0.size
    snap = (ch.x.copy(), ch.u.copy(), ch.acc.copy(), ch.in_contact.copy(), ch.istep)

    def restore():
        ch.x[...], ch.u[...], ch.acc[...], ch.in_contact[...] = snap[:4]
        ch.istep = snap[4]

    def period():
        restore()
        ch.run(a, cfg.n_t)

    step = _best(period, repeat) / cfg.n_t / n
    # the drag's inputs at nstates steps of that period: x and v* after the drift of a step
    restore()
    states = []
    every = cfg.n_t // nstates
    half = ch.opts.integrator == K.INTEG_HALF_STEP
    for _ in range(nstates):
        ch.run(a, every - 1)
        dt = cfg.dt
        vstar = (ch.u + 0.5 * dt * ch.acc) if half else (ch.u + dt * ch.acc)
        x = (ch.x + dt * (ch.u + 0.5 * dt * ch.acc)).ravel()
        wt = 2.0 * math.pi / cfg.n_t * ((ch.istep + 1) % cfg.n_t)
        states.append((np.cos(k * x), np.sin(k * x), math.cos(wt), math.sin(wt),
                       vstar.ravel().copy()))
        ch.run(a, 1)
    sc, idx = K.new_scratch(n), np.zeros(n, np.int64)
    exact = ch.opts.drag == K.DRAG_EXACT
    af = a.ravel().copy()
    fast_v = np.full(n, 1e3)
    drag = closed = share = 0.0
    tail = (ch.P, ch.cxi, ch.sxi, ch.mom, sc, idx)
    for ck, sk, cwt, swt, vs in states:
        with_roots = (ncalls, exact, ck, sk, cwt, swt, af, vs) + tail
        no_roots = (ncalls, exact, ck, sk, cwt, swt, af, fast_v) + tail
        share += _drag_calls(1, *with_roots[1:]) / n / nstates
        drag += _best(functools.partial(_drag_calls, *with_roots), repeat) / ncalls / n
        closed += _best(functools.partial(_drag_calls, *no_roots), repeat) / ncalls / n
    drag /= nstates
    closed /= nstates
    root = (drag - closed) / share if share > 0 else float("nan")
    return dict(step=step, drag=drag, closed=closed, root=root, share=share,
                rest=step - drag)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--replicas", type=int, default=8)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--states", type=int, default=12)
    args = p.parse_args()
    print(f"R = {args.replicas}; ns per (replica-)floe and step, CPU time, best of"
          f" {args.repeat}; 'root' per floe with a root")
    print(f"{'drag':<11}{'N_f':>4}{'step':>8}{'drag':>8}{'closed':>8}{'root':>8}"
          f"{'share':>7}{'rest':>8}{'closed+rest':>13}")
    for mode in ("quadrature", "exact"):
        for L_x in (0.5, 1.5, 3.0):
            cfg = ModelConfig(L_x=L_x, T=1.2, drag_integration=mode, drag_every=1)  # every step
            r = {key: (v * 1e9 if key != "share" else v)
                 for key, v in parts(cfg, args.replicas, args.repeat, args.states).items()}
            print(f"{mode:<11}{cfg.n_floes:>4}{r['step']:>8.1f}{r['drag']:>8.1f}"
                  f"{r['closed']:>8.1f}{r['root']:>8.1f}{r['share']:>7.2f}{r['rest']:>8.1f}"
                  f"{r['closed'] + r['rest']:>13.1f}", flush=True)


if __name__ == "__main__":
    main()
