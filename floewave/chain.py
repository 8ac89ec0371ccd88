"""The 1-D floe chain (docs/model.md §1): its state, or that of R chains in lockstep, and the
compiled time loop around it (set up by :func:`floewave._kernels.chain_kernel`). The attenuation
iteration (:mod:`floewave.iteration`) runs its windows on it."""
from __future__ import annotations

import numpy as np

from . import _kernels as K
from .config import ModelConfig
from .errors import NumericalError

__all__ = ["FloeChain"]


class FloeChain:
    """State of the 1-D floe chain (docs/model.md §1), or of R chains in lockstep (an ensemble:
    one row of ``x0`` per replica), and the compiled time loop around it.

    The R chains share every coefficient and differ only in state; one call of the kernel
    advances them all (:func:`floewave._kernels.make_advance`), replica by replica the same
    numbers whatever R is.
    """

    def __init__(self, cfg: ModelConfig, k: float, x0: np.ndarray | None = None):
        self.cfg = cfg
        self.k = k
        n = cfg.n_floes
        # x_1 = L_x / 2, x_{i+1} = x_i + L_x + d_f: the ice edge is x = 0 (uniform
        # placement; an ensemble passes each replica's own arrangement as a row)
        if x0 is None:
            x0 = cfg.L_x / 2.0 + np.arange(n) * (cfg.L_x + cfg.d_f)
        self.x0 = np.ascontiguousarray(x0, dtype=float)
        if self.x0.ndim not in (1, 2) or self.x0.shape[-1] < 2:
            raise ValueError(f"x0 must be (N_f,) or (R, N_f) with N_f >= 2, not"
                             f" {self.x0.shape}")
        self.n = self.x0.shape[-1]
        self.replicas = self.x0.size // self.n
        self.work = K.new_work(self.x0.size)
        (self.P, self.opts, self.cxi, self.sxi, self.mom, self._spin,
         self._average) = K.chain_kernel(cfg, k)
        self.idx = np.zeros(self.x0.size, np.int64)
        self.reset()

    def reset(self) -> None:
        """Back to the initial state: floes at rest at x0, t = 0."""
        self.x = self.x0.copy()
        self.u = np.zeros_like(self.x0)
        self.acc = np.zeros_like(self.x0)
        self.in_contact = np.zeros(self.x0.shape, dtype=np.int8)
        self.istep = 0
        self._acc_ready = False
        self._acc_a = np.zeros(0)

    def _loop(self, fn, a, nsteps, stats, init) -> None:
        self.istep = fn(self.x.ravel(), self.u.ravel(), self.acc.ravel(), a.ravel(),
                        self.x0.ravel(), self.in_contact.ravel(), self.istep, nsteps, self.n,
                        self.P, self.cxi, self.sxi, self.mom, stats, self.work,
                        self.idx, init)

    def run(self, a: np.ndarray, nsteps: int, stats: np.ndarray | None = None) -> None:
        """Advance ``nsteps`` steps with amplitudes ``a`` (shape of ``x0``, or one profile
        for every replica); accumulate into ``stats`` if given ((N_STATS, N_f) for one
        chain, (N_STATS, R, N_f) or (N_STATS, R N_f) for R).

        The first half-kick uses the acceleration of the current state *with these
        amplitudes*: it is recomputed whenever ``a`` differs from the amplitudes it was
        computed with (a new iteration), not carried over from the previous iteration's
        amplitudes (issue *trust*: that carried the old wave force into one step per
        iteration).
        """
        a = np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float), self.x0.shape))
        if not self._acc_ready or not np.array_equal(a, self._acc_a):
            # the kernel re-evaluates every replica; a replica whose amplitudes did not
            # change keeps its acceleration (as it would run alone: replica r's numbers
            # must not depend on the others)
            keep = (np.all(a == self._acc_a, axis=-1) if self._acc_ready
                    else np.zeros(a.shape[:-1], dtype=bool))
            saved = self.acc.copy()
            # the drag sums held between evaluations (``drag_every`` > 1), likewise
            held = [h.copy() for h in self._held_rows()]
            self._loop(self._spin, a, 0, np.zeros((K.N_STATS, 0)), True)
            self.acc[keep] = saved[keep]
            for h, old in zip(self._held_rows(), held, strict=True):
                h[keep] = old[keep]
            self._acc_a = a.copy()
            self._acc_ready = True
        if stats is None:
            self._loop(self._spin, a, nsteps, np.zeros((K.N_STATS, 0)), False)
        else:
            every = self.cfg.drag_every
            if every > 1 and (nsteps % every or self.istep % every):
                # each drag evaluation's dissipation stands for drag_every steps: a window of
                # other bounds would hold another number of steps than it divides by
                raise ValueError(f"statistics over {nsteps} steps from step {self.istep}:"
                                 f" both must be multiples of drag_every = {every}")
            flat = stats.reshape(K.N_STATS, self.x0.size)
            if not np.shares_memory(flat, stats):
                raise ValueError("stats must be a contiguous (N_STATS, ...) array")
            self._loop(self._average, a, nsteps, flat, False)

    def window(self, a: np.ndarray, n_spin: int, n_average: int, stats: np.ndarray) -> None:
        """One window of the attenuation iteration (docs/model.md §4 steps 2-3) with
        amplitudes ``a``: ``n_spin`` steps, then ``n_average`` steps accumulating into
        ``stats`` (:meth:`run`), then :meth:`check`."""
        self.run(a, n_spin)
        self.run(a, n_average, stats)
        self.check()

    def _held_drag(self) -> np.ndarray:
        """The drag sums the time loop holds between evaluations, (R, N_f) view."""
        return self.work[K.W_SC + K.SC_S2, :self.x0.size].reshape(self.x0.shape)

    def _held_rows(self) -> list[np.ndarray]:
        """Every row of scratch a held drag carries from step to step ((R, N_f) views):
        the sums held, and for ``drag_hold = "linear"`` the last evaluation, its slope and
        its step."""
        rows = [K.W_SC + K.SC_S2, K.W_D0, K.W_DS, K.W_DI, K.W_AF]
        return [self.work[r, :self.x0.size].reshape(self.x0.shape) for r in rows]

    def check(self) -> None:
        """Raise :class:`NumericalError` on a non-finite state or floes out of order."""
        if not (np.all(np.isfinite(self.x)) and np.all(np.isfinite(self.u))):
            raise NumericalError(f"DEM diverged: non-finite state at step {self.istep}")
        d = np.diff(self.x, axis=-1).reshape(self.replicas, -1)
        if np.any(d <= 0.0):
            r, i = np.unravel_index(int(np.argmin(d)), d.shape)
            where = f" (replica {r})" if self.replicas > 1 else ""
            raise NumericalError(f"floes {i + 1} and {i + 2} passed through each other at"
                                 f" step {self.istep}{where}")
