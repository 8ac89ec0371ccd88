"""Contacts on their own clock: the time loop of ``integrator = "respa"`` (private; built by
:func:`make_advance_respa`, run by :class:`floewave.chain.FloeChain` like the loop of
:func:`floewave._kernels.make_advance`, with the same arguments).

**Why.** A contact must be resolved in about 20 steps (dt = 1e-3 s: the restitution table of
docs/model.md §3 within 0.01), while the waves, the drag and the edge springs change on
T / 100 or slower; yet pairs touch in only about a quarter of the floe-steps of the paper's
grid. So the forces are split by their clock (r-RESPA, Tuckerman, Berne & Martyna 1992,
J. Chem. Phys. 97, 1990; LAMMPS ``run_style respa``): with M = ``drag_every`` and the outer
step Dt = M dt, per outer step::

    u += Dt/2 a_slow                                  # slow half-kick
    M inner steps of dt under the contact force alone  # velocity Verlet, v* predictor
    a_slow = (eq. 8 without F_c at x(t + Dt), v*) / ((1 + C_m) m)
    u += Dt/2 a_slow                                  # slow half-kick

The slow force is eq. 8's (1 + C_m) F_w + F_d (:mod:`floewave._force_terms`), its
velocity-dependent drag at v* = u + Dt/2 a_slow (the end-of-step velocity predicted, as
``integrator = "predictor"`` does for every step). The inner steps are those of the
predictor integrator with F_c and the edge springs F_s (their period, 0.26 s for a lab
floe of 0.5 m, is only 26 outer steps of 10 ms: as a slow force they biased the far end's
amplitude against the reference runs), so an isolated collision without waves is resolved
exactly as there. The first and last floe of a chain are therefore always sub-stepped.

**Only the pairs that may touch are sub-stepped.** After the slow half-kick every floe
moves at constant velocity unless it touches a neighbour, so the gap of a pair of free
floes is linear over the outer step: the pair is *active* if that line reaches 0 (or it
touches now). Maximal runs of floes joined by active pairs are *clusters*; a cluster's
floes take the M inner steps, every other floe one drift x += Dt u. A collision inside a
cluster can push its end floe into a free neighbour within the outer step: each inner step
checks the gaps to the free neighbours (at their linear positions), and if one closes, that
pair is made active, the replica's outer step is started again from its saved state, and
the grown cluster is sub-stepped (the check repeats until no gap to a free floe closes).

**Statistics** (``accumulate``) are those of every step, as the other loop keeps them: the
sums over the M steps of x and the gaps (exact for free floes and pairs, whose positions
are linear in time; step by step in the clusters), contact steps, onsets and |net contact
force| step by step (zero outside the clusters); the wave force, the drag and the
dissipation sum of eq. 19 are evaluated once per outer step and stand for its M steps.
"""
from __future__ import annotations

import functools
import math

from numba import njit

from ._force_terms import contact_force, edge_spring, skin_drag, skin_drag_sums, wave_force
from ._jit import JITN
from ._layout import (
    INTEG_MTS,
    LANES,
    N_STATS,
    N_WORK,
    SC_S2,
    SC_S3,
    ST_COLL,
    ST_CONTACT,
    ST_FC,
    ST_FD,
    ST_FW,
    ST_GAP,
    ST_S3,
    ST_X,
    W_ACT,
    W_AF,
    W_AFS,
    W_CK,
    W_CKC,
    W_F,
    W_FC,
    W_ICS,
    W_SC,
    W_SK,
    W_SKC,
    W_TCOLL,
    W_TCON,
    W_TFC,
    W_TGAP,
    W_TX,
    W_UH,
    W_US,
    W_VC,
    W_VS,
    W_XS,
)

__all__ = ["make_advance_respa"]


@njit(**JITN)
def slow_forces(x, vs, a, x0, ck, sk, cwt, swt, P, cxi, sxi, mom, accumulate, sc, idx, drag,
                nf, F, stats, weight):
    """eq. 8's slow side, (1 + C_m) F_w + F_d [N], of every floe at positions ``x``
    (``ck, sk`` = cos, sin(k x)), wave phase ``cwt, swt`` and velocity ``vs`` into ``F``;
    with ``accumulate`` the dissipation sum, |F_w| and |F_d| of this evaluation added to
    ``stats`` with the ``weight`` of the steps it stands for."""
    nt = x.shape[0]
    skin_drag_sums(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx, drag)
    for j in range(nt):
        Fw = wave_force(a[j], sk[j] * cwt - ck[j] * swt, P)
        Fd = skin_drag(sc[SC_S2, j], P)
        F[j] = P.one_cm * Fw + Fd
        if accumulate:
            stats[ST_S3, j] += weight * sc[SC_S3, j]
            stats[ST_FW, j] += weight * abs(Fw)
            stats[ST_FD, j] += weight * abs(Fd)


@njit(**JITN)
def contact_accelerations(x, x0, vs, af, Fc, in_contact, o, nf, P, contact, damping, clip):
    """The fast acceleration ``af`` (contacts and edge springs) of floes o .. o + nf - 1 at
    positions ``x`` and velocities ``vs`` (a new amplitude profile's first evaluation);
    ``in_contact`` set from the overlaps."""
    for j in range(o, o + nf - 1):
        gap = x[j + 1] - x[j] - P.L_x
        Fc[j] = contact_force(gap, vs[j + 1] - vs[j], P, contact, damping, clip)
        in_contact[j] = 1 if gap < 0.0 else 0
    Fc[o + nf - 1] = 0.0
    af[o] = (-Fc[o] + edge_spring(x[o], x0[o], P)) * P.inv_mass
    for j in range(o + 1, o + nf):
        af[j] = (Fc[j - 1] - Fc[j]) * P.inv_mass
    e = o + nf - 1
    af[e] = (Fc[e - 1] - Fc[e] + edge_spring(x[e], x0[e], P)) * P.inv_mass


@njit(**JITN)
def cluster_steps(x, x0, u, af, acs, in_contact, work, cs, ce, o, nf, M, P, contact,
                  damping, clip, accumulate, held):
    """M inner steps of dt under the contact force alone for the cluster of floes cs .. ce
    (pairs cs .. ce - 1 all active), velocity Verlet with the damping at v* = u + dt af;
    the outer step's statistics into the ``W_T*`` rows. Returns the pair (i, i + 1) to a
    free neighbour whose gap closed (then the step must be taken again with it active),
    else -1. The free neighbours are at their linear positions from ``W_XS``."""
    dt = P.dt
    uh = work[W_UH]
    vs = work[W_VS]
    Fc = work[W_FC]
    xs = work[W_XS]
    tx = work[W_TX]
    tgap = work[W_TGAP]
    tcon = work[W_TCON]
    tcoll = work[W_TCOLL]
    tfc = work[W_TFC]
    left = cs > o
    right = ce < o + nf - 1
    for s in range(1, M + 1):
        for j in range(cs, ce + 1):
            aj = af[j] + acs[j] if held else af[j]
            uh[j] = u[j] + 0.5 * dt * aj
            vs[j] = u[j] + dt * aj
            x[j] += dt * uh[j]
        for j in range(cs, ce):
            gap = x[j + 1] - x[j] - P.L_x
            touch = gap < 0.0
            Fc[j] = contact_force(gap, vs[j + 1] - vs[j], P, contact, damping, clip)
            if accumulate:
                tgap[j] += gap
                if touch:
                    tcon[j] += 1.0
                    if in_contact[j] == 0:
                        tcoll[j] += 1.0
            in_contact[j] = 1 if touch else 0
        for j in range(cs, ce + 1):
            f = 0.0
            if j > cs:
                f += Fc[j - 1]
            if j < ce:
                f -= Fc[j]
            fs = 0.0
            if j == o or j == o + nf - 1:       # the edge springs: on this clock too
                fs = edge_spring(x[j], x0[j], P)
            af[j] = (f + fs) * P.inv_mass
            u[j] = uh[j] + 0.5 * dt * (af[j] + acs[j] if held else af[j])
            if accumulate:
                tx[j] += x[j]
                tfc[j] += abs(f)
        # the gaps to the free neighbours, which move on their lines
        ts = s * dt
        if left:
            nb = xs[cs - 1] + ts * u[cs - 1]
            if held:
                nb += 0.5 * ts * ts * acs[cs - 1]
            g = x[cs] - nb - P.L_x
            if g < 0.0:
                return cs - 1
            if accumulate:
                tgap[cs - 1] += g
        if right:
            nb = xs[ce + 1] + ts * u[ce + 1]
            if held:
                nb += 0.5 * ts * ts * acs[ce + 1]
            g = nb - x[ce] - P.L_x
            if g < 0.0:
                return ce
            if accumulate:
                tgap[ce] += g
    return -1


@njit(**JITN)
def replica_step(x, x0, u, af, acs, in_contact, work, o, nf, M, P, contact, damping, clip,
                 accumulate, stats, held):
    """One outer step's contacts and drift of the replica of floes o .. o + nf - 1 (after
    the slow half-kick): the active pairs, the clusters sub-stepped (again with a pair made
    active whenever a gap to a free floe closed), every other floe drifted; then its
    statistics into ``stats``. Returns how many times the step was started again."""
    Dt = M * P.dt
    xs = work[W_XS]
    us = work[W_US]
    afs = work[W_AFS]
    ics = work[W_ICS]
    act = work[W_ACT]
    tx = work[W_TX]
    tgap = work[W_TGAP]
    tcon = work[W_TCON]
    tcoll = work[W_TCOLL]
    tfc = work[W_TFC]
    end = o + nf
    for j in range(o, end):
        xs[j] = x[j]
        us[j] = u[j]
        afs[j] = af[j]
        ics[j] = in_contact[j]
    for j in range(o, end - 1):
        g0 = x[j + 1] - x[j] - P.L_x
        vn = u[j + 1] - u[j]
        an = acs[j + 1] - acs[j] if held else 0.0
        g1 = g0 + Dt * vn + 0.5 * Dt * Dt * an
        gmin = min(g0, g1)
        if an > 0.0 and vn < 0.0 and -vn < an * Dt:       # the gap's minimum inside
            gmin = min(gmin, g0 - 0.5 * vn * vn / an)
        act[j] = 1.0 if gmin < 0.0 else 0.0
    act[end - 1] = 0.0
    retries = 0
    while True:
        # two clusters one pair apart become one: every pair left out then has a free floe
        # (the first and last floe, on their edge springs, are always sub-stepped)
        for j in range(o, end - 1):
            if act[j] == 0.0:
                left_in = j == o or act[j - 1] == 1.0
                right_in = j + 1 == end - 1 or act[j + 1] == 1.0
                if left_in and right_in:
                    act[j] = 1.0
        if accumulate:
            for j in range(o, end):
                tx[j] = 0.0
                tgap[j] = 0.0
                tcon[j] = 0.0
                tcoll[j] = 0.0
                tfc[j] = 0.0
        closed = -1
        j = o
        while j < end:
            if (j < end - 1 and act[j] == 1.0) or j == o or j == end - 1:
                ce = j
                while ce < end - 1 and act[ce] == 1.0:
                    ce += 1
                closed = cluster_steps(x, x0, u, af, acs, in_contact, work, j, ce, o, nf, M,
                                       P, contact, damping, clip, accumulate, held)
                if closed >= 0:
                    break
                j = ce + 1
            else:
                j += 1
        if closed < 0:
            break
        act[closed] = 1.0
        retries += 1
        for j in range(o, end):
            x[j] = xs[j]
            u[j] = us[j]
            af[j] = afs[j]
            in_contact[j] = int(ics[j])
    # the free floes: one drift (their sums over the M steps exact: x is linear)
    mm = 0.5 * M * (M + 1) * P.dt
    m2 = M * (M + 1) * (2 * M + 1) / 12.0 * P.dt * P.dt     # sum over s of (s dt)^2 / 2
    for j in range(o, end):
        free = j != o and j != end - 1 and act[j - 1] == 0.0 and act[j] == 0.0
        if free:
            if accumulate:
                tx[j] = M * x[j] + mm * u[j] + (m2 * acs[j] if held else 0.0)
            if held:
                x[j] += Dt * u[j] + 0.5 * Dt * Dt * acs[j]
                u[j] += Dt * acs[j]
            else:
                x[j] += Dt * u[j]
            af[j] = 0.0
    for j in range(o, end - 1):
        if act[j] == 0.0:
            in_contact[j] = 0
            a_free = j != o and act[j - 1] == 0.0
            b_free = j + 1 != end - 1 and act[j + 1] == 0.0
            if accumulate and a_free and b_free:
                # (u of the pair's floes is that of the step's start: both free, their
                # velocities were set above only after these sums in the held case)
                tgap[j] = M * (xs[j + 1] - xs[j] - P.L_x) + mm * (us[j + 1] - us[j])
                if held:
                    tgap[j] += m2 * (acs[j + 1] - acs[j])
    if accumulate:
        for j in range(o, end):
            stats[ST_X, j] += tx[j]
            stats[ST_FC, j] += tfc[j]
        for j in range(o, end - 1):
            stats[ST_GAP, j] += tgap[j]
            stats[ST_CONTACT, j] += tcon[j]
            stats[ST_COLL, j] += tcoll[j]
    return retries


@functools.cache
def make_advance_respa(opts):
    """The multiple-time-stepping loop (module docstring) for ``opts``
    (:class:`floewave._kernels.KernelOptions`; ``drag_every`` is M, the inner steps per
    outer step), compiled once per process (cached on disk by numba).

    Same arguments and return as the loop of :func:`floewave._kernels.make_advance`;
    ``acc`` holds the slow acceleration, the scratch row ``W_AF`` the contact acceleration
    (kept from call to call: a state of the chain), ``nsteps`` and ``istep`` are multiples
    of M.
    """
    contact, damping, clip, integrator, drag, M, _, accumulate = opts
    held = int(integrator) == INTEG_MTS
    contact = int(contact)
    damping = int(damping)
    clip = int(clip)
    drag = int(drag)
    M = int(M)
    accumulate = bool(accumulate)

    @njit(**JITN)
    def advance(x, u, acc, a, x0, in_contact, istep, nsteps, nf, P, cxi, sxi, mom, stats,
                work, idx, init):
        nt = x.shape[0]
        if (work.shape[0] < N_WORK or work.shape[1] < nt + LANES or idx.shape[0] < nt
                or nf < 2 or nt % nf != 0):
            raise ValueError("advance: scratch too small (work needs N_WORK rows and"
                             " R N_f + LANES columns: new_work) or R N_f not a multiple"
                             " of N_f >= 2")
        if init and accumulate:
            raise ValueError("advance: init only in a loop that does not accumulate")
        if (u.shape[0] != nt or acc.shape[0] != nt or a.shape[0] != nt or x0.shape[0] != nt
                or in_contact.shape[0] != nt
                or (accumulate and (stats.shape[0] < N_STATS or stats.shape[1] != nt))):
            raise ValueError("advance: x, u, acc, a, x0, in_contact (and stats) must all"
                             " have R N_f entries (stats: N_STATS rows)")
        if nsteps % M != 0 or istep % M != 0:
            raise ValueError("advance (respa): nsteps and istep must be multiples of the"
                             " inner steps per outer step (drag_every)")
        Dt = M * P.dt
        vs = work[W_VS, :nt]
        F = work[W_F, :nt]
        ck = work[W_CK, :nt]
        sk = work[W_SK, :nt]
        Fc = work[W_FC]
        af = work[W_AF]
        sc = work[W_SC:]
        xs = work[W_XS, :nt]
        xm = work[W_VC, :nt]           # (held: the outer step's centre state)
        cm = work[W_CKC, :nt]
        sm = work[W_SKC, :nt]
        two_pi_nt = 2.0 * math.pi / P.n_t
        for j in range(nt):
            ck[j] = math.cos(P.k * x[j])
            sk[j] = math.sin(P.k * x[j])
        if init:
            for j in range(nt):
                vs[j] = u[j]
            wt = two_pi_nt * (istep % P.n_t)
            slow_forces(x, vs, a, x0, ck, sk, math.cos(wt), math.sin(wt), P, cxi, sxi, mom,
                        False, sc, idx, drag, nf, F, stats, 0.0)
            for j in range(nt):
                acc[j] = F[j] * P.inv_mass
            for o in range(0, nt, nf):
                contact_accelerations(x, x0, u, af, Fc, in_contact, o, nf, P, contact,
                                      damping, clip)
        for _ in range(nsteps // M):
            if held:
                # the slow force held over the outer step, evaluated at its centre: the
                # state moved on by Dt/2 at the current velocity and acceleration
                for j in range(nt):
                    at = acc[j] + af[j]
                    xm[j] = x[j] + 0.5 * Dt * u[j] + 0.125 * Dt * Dt * at
                    vs[j] = u[j] + 0.5 * Dt * at
                    cm[j] = math.cos(P.k * xm[j])
                    sm[j] = math.sin(P.k * xm[j])
                wm = two_pi_nt * ((istep % P.n_t) + 0.5 * M)
                slow_forces(xm, vs, a, x0, cm, sm, math.cos(wm), math.sin(wm), P, cxi, sxi,
                            mom, accumulate, sc, idx, drag, nf, F, stats, float(M))
                for j in range(nt):
                    acc[j] = F[j] * P.inv_mass
                for o in range(0, nt, nf):
                    replica_step(x, x0, u, af, acc, in_contact, work, o, nf, M, P, contact,
                                 damping, clip, accumulate, stats, True)
                istep += M
                continue
            for j in range(nt):
                u[j] += 0.5 * Dt * acc[j]
            for o in range(0, nt, nf):
                replica_step(x, x0, u, af, acc, in_contact, work, o, nf, M, P, contact, damping,
                             clip, accumulate, stats, False)
            istep += M
            wt = two_pi_nt * (istep % P.n_t)
            for j in range(nt):
                # cos, sin(k x) rotated by k dx of this outer step (|k dx| <= 0.1: the
                # series to (k dx)^8 is exact to rounding; else evaluated afresh)
                e = P.k * (x[j] - xs[j])
                if abs(e) > 0.1:
                    ck[j] = math.cos(P.k * x[j])
                    sk[j] = math.sin(P.k * x[j])
                    vs[j] = u[j] + 0.5 * Dt * acc[j]
                    continue
                e2 = e * e
                ce = 1.0 - e2 * (0.5 - e2 * (1.0 / 24.0 - e2 * (1.0 / 720.0
                                                                - e2 * (1.0 / 40320.0))))
                se = e * (1.0 - e2 * (1.0 / 6.0 - e2 * (1.0 / 120.0 - e2 * (1.0 / 5040.0))))
                c_new = ck[j] * ce - sk[j] * se
                sk[j] = sk[j] * ce + ck[j] * se
                ck[j] = c_new
                vs[j] = u[j] + 0.5 * Dt * acc[j]
            slow_forces(x, vs, a, x0, ck, sk, math.cos(wt), math.sin(wt), P, cxi, sxi, mom,
                        accumulate, sc, idx, drag, nf, F, stats, float(M))
            for j in range(nt):
                acc[j] = F[j] * P.inv_mass
                u[j] += 0.5 * Dt * acc[j]
        return istep

    return advance
