"""Plain vectorised-numpy implementation of the same DEM time step as :mod:`._kernels`.

Used as an independent check of the numba kernel (tests) and as the speed peer in
``benchmarks/bench_kernel.py``. Same update formulas, vectorised over floes and drag cells;
no statistics accumulation. Laid out as the kernel: one function per force of eq. 8 (as
:mod:`floewave._force_terms`), :func:`forces` their sum, :func:`advance` the time loop.
"""
from __future__ import annotations

import math

import numpy as np

from . import _kernels as K


def wave_force(x: np.ndarray, a: np.ndarray, wt: float, P: K.KernelParams) -> np.ndarray:
    """Froude-Krylov force F_w,i = c_wave a_i sin(k x_i - omega t) on every floe [N], wave
    phase ``wt`` = omega t (:func:`floewave._force_terms.wave_force`)."""
    return P.c_wave * a * np.sin(P.k * x - wt)


def skin_drag(x: np.ndarray, v: np.ndarray, a: np.ndarray, wt: float, P: K.KernelParams,
              cxi: np.ndarray, sxi: np.ndarray) -> np.ndarray:
    """Skin drag F_d on every floe [N] (eq. 15 summed over the drag cells), wave phase
    ``wt`` (:func:`floewave._force_terms.skin_drag`)."""
    th = P.k * x - wt
    s, c = np.sin(th), np.cos(th)
    ur = (a * P.u_amp)[:, None] * (c[:, None] * cxi[None, :] - s[:, None] * sxi[None, :]) \
        - v[:, None]
    return P.c_drag * np.sum(np.abs(ur) * ur, axis=1)


def contact_force(x: np.ndarray, v: np.ndarray, P: K.KernelParams,
                  opts: K.KernelOptions) -> np.ndarray:
    """Contact force between floes i and i + 1 (N_f - 1 values, > 0 pushes them apart) [N]:
    the contact law of :mod:`._contact` (stiffness, damping, optional clipping: ``opts``;
    :func:`floewave._force_terms.contact_force`)."""
    delta = -(x[1:] - x[:-1] - P.L_x)
    touch = delta > 0
    d = np.where(touch, delta, 0.0)
    if opts.contact == K.CONTACT_LINEAR:
        kn = np.full_like(d, P.kn_lin)
    else:
        sv = d * P.s_scale
        kn = P.kn_disk * (0.9117 * sv**2 + 0.2722 * sv + 0.003324) / (sv**2 + 1.524 * sv
                                                                        + 0.03159)
    coef = math.sqrt(5.0) if opts.damping == K.DAMPING_LIGGGHTS else 2.0
    gamma = -P.beta * coef * np.sqrt(kn * P.m_star)
    Fc = np.where(touch, kn * d - gamma * (v[1:] - v[:-1]), 0.0)
    if opts.clip:
        Fc = np.maximum(Fc, 0.0)
    return Fc


def edge_spring(x: float, x_start: float, P: K.KernelParams) -> float:
    """Edge-spring force F_s = -k_s (x - x(0)) [N] on the first or last floe
    (:func:`floewave._force_terms.edge_spring`)."""
    return -(P.k_s * (x - x_start))


def forces(x: np.ndarray, v: np.ndarray, a: np.ndarray, x0: np.ndarray, wt: float,
           P: K.KernelParams, opts: K.KernelOptions, cxi: np.ndarray, sxi: np.ndarray,
           Fd: np.ndarray | None = None) -> np.ndarray:
    """The right-hand side of eq. 8 on every floe [N]
    (:func:`floewave._force_terms.eq8_forces`)::

        F_i = (1 + C_m) F_w,i + F_d,i + F_c,i + F_s,i

    ``Fd`` a held drag (else evaluated here)."""
    if Fd is None:
        Fd = skin_drag(x, v, a, wt, P, cxi, sxi)
    F = P.one_cm * wave_force(x, a, wt, P) + Fd
    Fc = contact_force(x, v, P, opts)
    F[:-1] -= Fc
    F[1:] += Fc
    F[0] += edge_spring(x[0], x0[0], P)
    F[-1] += edge_spring(x[-1], x0[-1], P)
    return F


def advance(x, u, acc, a, x0, istep, nsteps, P, opts, cxi, sxi, held=None, slope=None,
            i_last=None):
    """Numpy twin of the time loop :func:`floewave._kernels.make_advance` builds, for one
    chain (``x[1:] - x[:-1]`` pairs every neighbour; no statistics); returns istep.

    ``opts.drag_every`` = K > 1: the drag is evaluated on the steps istep = 0 mod K at the
    centre of the K steps it is then held for, (K - 1) / 2 steps ahead: the wave phase of
    that time, the floe moved on by its force velocity and that velocity moved on by acc;
    ``held`` is the drag [N] held when the loop starts (the kernel's, for a start inside a
    hold). ``opts.hold`` linear (``drag_hold = "linear"``): evaluated at the true state of
    the steps istep = 0 mod K and extrapolated between them along the slope from the
    evaluation before; ``held``, ``slope`` (per step) and ``i_last`` (its step) are the
    kernel's at the start."""
    dt = P.dt
    n_hold = int(opts.drag_every)
    h = 0.5 * (n_hold - 1) * dt
    Fd = held
    # drag_hold "linear": the last evaluation [N], its slope per step [N], its step
    linear = n_hold > 1 and opts.hold == K.HOLD_LINEAR
    last, i_last = held, (istep if i_last is None else i_last)
    if slope is None and held is not None:
        slope = np.zeros_like(held)
    for _ in range(nsteps):
        istep += 1
        uh = u + 0.5 * dt * acc
        vs = u + dt * acc if opts.integrator == K.INTEG_PREDICTOR else uh
        x += dt * uh
        wt = 2.0 * math.pi / P.n_t * (istep % P.n_t)
        if n_hold == 1:
            F = forces(x, vs, a, x0, wt, P, opts, cxi, sxi)
        elif linear:
            if istep % n_hold == 0 or last is None:
                new = skin_drag(x, vs, a, wt, P, cxi, sxi)
                slope = ((new - last) / (istep - i_last) if last is not None
                         else np.zeros_like(new))
                last, i_last = new, istep
            F = forces(x, vs, a, x0, wt, P, opts, cxi, sxi, last + slope * (istep - i_last))
        else:
            if istep % n_hold == 0 or Fd is None:
                wc = 2.0 * math.pi / P.n_t * ((istep % P.n_t) + 0.5 * (n_hold - 1))
                Fd = skin_drag(x + h * vs, vs + h * acc, a, wc, P, cxi, sxi)
            F = forces(x, vs, a, x0, wt, P, opts, cxi, sxi, Fd)
        acc[:] = F * P.inv_mass
        u[:] = uh + 0.5 * dt * acc
    return istep


def _fast_step(x, u, af, acs, in_contact, x0, P, opts, stats):
    """One inner step of dt of the contact clock's twins for every floe: velocity Verlet
    under the contacts and edge springs (``af``, the predictor's v*) plus the held slow
    acceleration ``acs`` (0 for r-RESPA); the step's sums into ``stats`` if given."""
    dt = P.dt
    uh = u + 0.5 * dt * (af + acs)
    vs = u + dt * (af + acs)
    x += dt * uh
    Fc = contact_force(x, vs, P, opts)
    gap = x[1:] - x[:-1] - P.L_x
    touch = gap < 0.0
    f = np.zeros_like(x)
    f[:-1] -= Fc
    f[1:] += Fc
    fs = np.zeros_like(x)
    fs[0] = edge_spring(x[0], x0[0], P)
    fs[-1] = edge_spring(x[-1], x0[-1], P)
    af[:] = (f + fs) * P.inv_mass
    u[:] = uh + 0.5 * dt * (af + acs)
    if stats is not None:
        stats[K.ST_X] += x
        stats[K.ST_GAP, :-1] += gap
        stats[K.ST_CONTACT, :-1] += touch
        stats[K.ST_COLL, :-1] += touch & (in_contact[:-1] == 0)
        stats[K.ST_FC] += np.abs(f)
    in_contact[:-1] = touch


def _slow_sums(stats, M, x, v, a, wt, Fw, Fd, P, cxi, sxi):
    """The slow evaluation's |F_w|, |F_d| and dissipation sum (eq. 19) with weight M."""
    stats[K.ST_FW] += M * np.abs(Fw)
    stats[K.ST_FD] += M * np.abs(Fd)
    th = P.k * x - wt
    ur = (a * P.u_amp)[:, None] * (np.cos(th)[:, None] * cxi[None, :]
                                   - np.sin(th)[:, None] * sxi[None, :]) - v[:, None]
    stats[K.ST_S3] += M * np.sum(np.abs(ur) ** 3, axis=1)


def advance_respa(x, u, acc, af, in_contact, a, x0, istep, nsteps, P, opts, cxi, sxi,
                  stats=None):
    """Numpy twin of the ``integrator = "respa"`` loop (:mod:`floewave._respa`) for one chain:
    the same splitting, but every floe takes the M = ``opts.drag_every`` inner steps and
    every pair's contact force is evaluated at each (no clusters: the kernel's choice of
    which floes to sub-step must not matter); the edge springs are fast forces too. ``acc``
    the slow, ``af`` the contact acceleration, ``in_contact`` (int8) as the kernel keeps
    them; ``stats`` (N_STATS, N_f) gets the sums the kernel's averaging loop keeps (x and
    gaps step by step, F_w, F_d and the dissipation sum of the slow evaluations with weight
    M). Returns istep."""
    M = int(opts.drag_every)
    dt = P.dt
    Dt = M * dt
    m_inv = P.inv_mass
    for _ in range(nsteps // M):
        u += 0.5 * Dt * acc
        for _ in range(M):
            _fast_step(x, u, af, 0.0, in_contact, x0, P, opts, stats)
        istep += M
        wt = 2.0 * math.pi / P.n_t * (istep % P.n_t)
        vs = u + 0.5 * Dt * acc
        Fw = wave_force(x, a, wt, P)
        Fd = skin_drag(x, vs, a, wt, P, cxi, sxi)
        F = P.one_cm * Fw + Fd
        acc[:] = F * m_inv
        u += 0.5 * Dt * acc
        if stats is not None:
            _slow_sums(stats, M, x, vs, a, wt, Fw, Fd, P, cxi, sxi)
    return istep


def advance_mts(x, u, acc, af, in_contact, a, x0, istep, nsteps, P, opts, cxi, sxi,
                stats=None):
    """Numpy twin of the ``integrator = "mts"`` loop (:mod:`floewave._respa`, held slow
    force) for one chain: per outer step of M = ``opts.drag_every`` steps the slow force
    evaluated once at the step's predicted centre and held, every floe taking the M steps
    under it and the contact force (no clusters). Arguments as :func:`advance_respa`."""
    M = int(opts.drag_every)
    dt = P.dt
    Dt = M * dt
    m_inv = P.inv_mass
    for _ in range(nsteps // M):
        at = acc + af
        xm = x + 0.5 * Dt * u + 0.125 * Dt * Dt * at
        vm = u + 0.5 * Dt * at
        wm = 2.0 * math.pi / P.n_t * ((istep % P.n_t) + 0.5 * M)
        Fw = wave_force(xm, a, wm, P)
        Fd = skin_drag(xm, vm, a, wm, P, cxi, sxi)
        F = P.one_cm * Fw + Fd
        acc[:] = F * m_inv
        if stats is not None:
            _slow_sums(stats, M, xm, vm, a, wm, Fw, Fd, P, cxi, sxi)
        for _ in range(M):
            _fast_step(x, u, af, acc, in_contact, x0, P, opts, stats)
        istep += M
    return istep
