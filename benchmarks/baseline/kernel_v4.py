"""Numba kernels: the DEM time loop (private; use :mod:`floewave.model`).

Everything here is nopython, cached, without fast-math (flags and why:
:mod:`floewave._jit`). The kernels see only numpy arrays and a
:class:`KernelParams` named tuple of numbers built once per point from the frozen
:class:`~floewave.config.ModelConfig`; option switches are small integers fixed for the
whole call (loop-invariant branches, no Python objects in the time loop).

Time integration (velocity Verlet, docs/model.md §3), per step n -> n+1::

    u_half = u_n + dt/2 acc_n
    x_{n+1} = x_n + dt u_half
    acc_{n+1} = a(x_{n+1}, v*, t_{n+1})       # eq. 8 / ((1 + C_m) m)
    u_{n+1} = u_half + dt/2 acc_{n+1}

with velocity-dependent forces (drag, contact damping) evaluated at
``v* = u_n + dt acc_n`` (``integrator = "predictor"``, second order) or at
``v* = u_half`` (``"half_step"``, as LIGGGHTS does; first order in the damping).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from floewave._exact import drag_force_exact, drag_pass_exact, drag_sums_exact, general_floes
from floewave._jit import JIT as _JIT
from floewave._jit import JITN as _JITN

# not cached on disk: this file calls floewave/_exact.py but is not one of the kernel files
# whose cache key covers all of them (floewave._jit.KernelSourcesLocator), so a cached copy
# could run an old _exact.py
JIT = dict(_JIT, cache=False)
JITN = dict(_JITN, cache=False)

# option codes (decided once from ModelConfig)
CONTACT_HERTZ_DISK = 0
CONTACT_LINEAR = 1
DAMPING_LIGGGHTS = 0
DAMPING_EXACT = 1
INTEG_PREDICTOR = 0
INTEG_HALF_STEP = 1
DRAG_QUADRATURE = 0
DRAG_EXACT = 1

# rows of the per-window statistics array ``stats`` (shape (N_STATS, N_f))
ST_S3 = 0        # sum over steps and cells of |u_rel|^3            [m^3 s^-3]
ST_X = 1         # sum over steps of x_i                            [m]
ST_GAP = 2       # sum over steps of gap_i (pair i, i+1)            [m]
ST_CONTACT = 3   # steps in contact (pair i, i+1)                   [-]
ST_COLL = 4      # contact onsets (pair i, i+1)                     [-]
ST_FW = 5        # sum over steps of |F_w,i|                        [N]
ST_FC = 6        # sum over steps of |net contact force on i|       [N]
ST_FD = 7        # sum over steps of |F_d,i|                        [N]
N_STATS = 8

# rows of the drag scratch ``sc`` (shape (N_SC, N_f)) of drag_pass / drag_pass_exact
SC_C = 0         # cos theta_i
SC_S = 1         # sin theta_i
SC_S2 = 2        # drag sum of |u_rel| u_rel
SC_S3 = 3        # drag sum of |u_rel|^3 (accumulating steps only)
SC_FLAG = 4      # 1: the floe needs the general evaluation
SC_GATHER = 5    # rows 5-10: the general floes gathered by cell_sums (A, c, s, v, s2, s3)
N_SC = 11
N_WORK = 5 + N_SC   # rows of advance's scratch ``work``
LANES = 16          # cell_sums pads its gathered floes to a multiple of this

# steps of the plain per-floe drag loop after a two-pass step that found >3/4 of the floes
# needing the general evaluation (see advance)
TWO_PASS_RETRY = 64


class KernelParams(NamedTuple):
    """Numbers the time loop needs, SI units (built by ``model.kernel_params``)."""

    dt: float          # time step [s]
    n_t: int           # steps per period [-]
    k: float           # wavenumber [m^-1]
    omega: float       # angular frequency [s^-1]
    c_wave: float      # F_w,i = c_wave a_i sin(k x_i - omega t) / a ... per unit a [N m^-1]
    u_amp: float       # surface orbital velocity per unit amplitude, omega / tanh(kh) [s^-1]
    c_drag: float      # rho_w C_sd L_y dx [kg m^-2 ... ] so F_d = c_drag sum |u|u [N s^2 m^-2]
    inv_mass: float    # 1 / ((1 + C_m) m) [kg^-1]
    one_cm: float      # 1 + C_m [-]
    L_x: float         # floe length [m]
    k_s: float         # edge-spring constant [N m^-1]
    m_star: float      # reduced mass m/2 [kg]
    beta: float        # ln(eps) / sqrt(ln(eps)^2 + pi^2) [-]
    kn_lin: float      # linear contact stiffness Y* L_y h_i / L_x [N m^-1]
    kn_disk: float     # hertz_disk prefactor pi Y* h_i [N m^-1]
    s_scale: float     # s = delta * s_scale, s_scale = R* / (2 h_i^2) [m^-1]
    contact: int       # CONTACT_*
    damping: int       # DAMPING_*
    clip: int          # 1: clip contact force at 0
    integrator: int    # INTEG_*
    drag: int          # DRAG_*: quadrature on the dx grid or the exact (dx -> 0) integrals
    geom: tuple        # floewave._exact.exact_geometry(k L_x, n_x) (used when drag = EXACT)


@njit(**JITN)
def contact_stiffness(delta, P):
    """k_n for overlap ``delta`` [N m^-1] (docs/model.md §3: hertz_disk f(s) or linear)."""
    if P.contact == CONTACT_LINEAR:
        return P.kn_lin
    s = delta * P.s_scale
    f = (0.9117 * s * s + 0.2722 * s + 0.003324) / (s * s + 1.524 * s + 0.03159)
    return P.kn_disk * f


@njit(**JITN)
def contact_force(delta, v_n, P):
    """Normal contact force [N] pushing a pair apart: F = k_n delta - gamma_n v_n.

    ``v_n = u_{i+1} - u_i`` (positive while separating); gamma_n = -beta sqrt(5 k_n m*)
    (liggghts) or -2 beta sqrt(k_n m*) (exact); clipped at 0 if ``P.clip``.
    """
    kn = contact_stiffness(delta, P)
    if P.damping == DAMPING_LIGGGHTS:
        gamma = -P.beta * math.sqrt(5.0 * kn * P.m_star)
    else:
        gamma = -2.0 * P.beta * math.sqrt(kn * P.m_star)
    F = kn * delta - gamma * v_n
    if P.clip == 1 and F < 0.0:
        F = 0.0
    return F


@njit(**JITN)
def drag_sums(A, c, s, v, cxi, sxi):
    """Sums over the floe-bottom cells of |u_rel| u_rel and |u_rel|^3 (eqs. 15, 19).

    u_rel_j = A cos(theta + k xi_j) - v = A (c cxi_j - s sxi_j) - v, with c, s the cosine
    and sine of the phase theta at the floe centre.
    """
    s2 = 0.0
    s3 = 0.0
    for j in range(cxi.shape[0]):
        ur = A * (c * cxi[j] - s * sxi[j]) - v
        au = abs(ur)
        s2 += au * ur
        s3 += au * ur * ur
    return s2, s3


@njit(**JITN)
def drag_force_sum(A, c, s, v, cxi, sxi):
    """Sum over the floe-bottom cells of |u_rel| u_rel only (see :func:`drag_sums`)."""
    s2 = 0.0
    for j in range(cxi.shape[0]):
        ur = A * (c * cxi[j] - s * sxi[j]) - v
        s2 += abs(ur) * ur
    return s2


# entries of the cell-table moments of :func:`drag_tables`
M_N = 0          # number of cells n_x
M_CB = 1         # mean of cxi
M_SB = 2         # mean of sxi
M_VCC = 3        # sum (cxi - M_CB)^2
M_VCS = 4        # sum (cxi - M_CB)(sxi - M_SB)
M_VSS = 5        # sum (sxi - M_SB)^2
M_TCCC = 6       # third central moments: sum dc^3, dc^2 ds, dc ds^2, ds^3
M_TCCS = 7
M_TCSS = 8
M_TSSS = 9
M_CMAX = 10      # cos h (h: offset of the outer cell midpoints), -2 if h >= pi
M_CH = 11        # cos h
M_SH = 12        # sin h
M_FAST = 13      # 1: closed form for one-sign floes usable (tables as built by FloeChain)
N_MOM = 14


@njit(**JIT)
def drag_tables(cxi, sxi, P):
    """Moments of the cell tables for the closed-form sums of one-sign floes
    (:func:`drag_pass`); built once per chain (``FloeChain.mom``)."""
    n = cxi.shape[0]
    mom = np.zeros(N_MOM)
    cb = 0.0
    sb = 0.0
    for j in range(n):
        cb += cxi[j]
        sb += sxi[j]
    cb /= n
    sb /= n
    for j in range(n):
        dc = cxi[j] - cb
        ds = sxi[j] - sb
        mom[M_VCC] += dc * dc
        mom[M_VCS] += dc * ds
        mom[M_VSS] += ds * ds
        mom[M_TCCC] += dc * dc * dc
        mom[M_TCCS] += dc * dc * ds
        mom[M_TCSS] += dc * ds * ds
        mom[M_TSSS] += ds * ds * ds
    mom[M_N] = n
    mom[M_CB] = cb
    mom[M_SB] = sb
    # the cells are at offsets k xi_j in [-h, h], h = k (L_x - dx) / 2 (tables of
    # FloeChain: cxi = cos(k xi), sxi = sin(k xi), symmetric; anything else: no fast path)
    h = 0.5 * P.k * P.L_x * (n - 1) / n
    ch = cxi[n - 1]
    sh = sxi[n - 1]
    fast = 1.0
    if (abs(math.cos(h) - ch) > 1e-9 or abs(math.sin(h) - sh) > 1e-9
            or abs(cxi[0] - ch) > 1e-9 or abs(sxi[0] + sh) > 1e-9):
        fast = 0.0
    mom[M_CH] = ch
    mom[M_SH] = sh
    mom[M_CMAX] = ch if h < math.pi - 1e-6 else -2.0
    mom[M_FAST] = fast
    return mom


@njit(**JITN)
def cell_sums(sc, idx, m, a, ua, vs, cxi, sxi, accumulate):
    """:func:`drag_sums` (``accumulate``) or :func:`drag_force_sum` of the ``m`` floes
    ``idx[:m]`` into ``sc[2]`` (and ``sc[3]``), vectorised across floes.

    Bit for bit the per-floe functions (tested): the kernels are compiled without
    fast-math (:mod:`floewave._jit`), so a sum over cells cannot be vectorised along the
    cells (that needs re-association). Instead the floes' A = a u_amp, cos theta,
    sin theta, v are gathered into contiguous rows of ``sc`` (rows SC_GATHER ...; lanes
    padded with zeros to a multiple of LANES, which the loop vectoriser needs for its
    vector body), the loop over cells is outside and the loop over floes inside: no
    reduction in the inner loop, so it vectorises across floes, and each floe's sum runs
    over the cells in the source's order with the source's expression. Four cells per
    pass keep each floe's running sums in registers for four additions.
    """
    gA = sc[SC_GATHER]
    gc = sc[SC_GATHER + 1]
    gs = sc[SC_GATHER + 2]
    gv = sc[SC_GATHER + 3]
    g2 = sc[SC_GATHER + 4]
    g3 = sc[SC_GATHER + 5]
    for t in range(m):
        i = idx[t]
        gA[t] = a[i] * ua
        gc[t] = sc[SC_C, i]
        gs[t] = sc[SC_S, i]
        gv[t] = vs[i]
    mp = ((m + LANES - 1) // LANES) * LANES
    for t in range(m, mp):      # padding lanes: u_rel = 0, results unused
        gA[t] = 0.0
        gc[t] = 0.0
        gs[t] = 0.0
        gv[t] = 0.0
    for t in range(mp):
        g2[t] = 0.0
        g3[t] = 0.0
    nx = cxi.shape[0]
    nb = nx - nx % 4
    if accumulate:
        for jb in range(0, nb, 4):
            c0 = cxi[jb]
            c1 = cxi[jb + 1]
            c2 = cxi[jb + 2]
            c3 = cxi[jb + 3]
            s0 = sxi[jb]
            s1 = sxi[jb + 1]
            s2 = sxi[jb + 2]
            s3 = sxi[jb + 3]
            for t in range(mp):
                A = gA[t]
                c = gc[t]
                s = gs[t]
                v = gv[t]
                p = g2[t]
                q = g3[t]
                ur = A * (c * c0 - s * s0) - v
                au = abs(ur)
                p += au * ur
                q += au * ur * ur
                ur = A * (c * c1 - s * s1) - v
                au = abs(ur)
                p += au * ur
                q += au * ur * ur
                ur = A * (c * c2 - s * s2) - v
                au = abs(ur)
                p += au * ur
                q += au * ur * ur
                ur = A * (c * c3 - s * s3) - v
                au = abs(ur)
                p += au * ur
                q += au * ur * ur
                g2[t] = p
                g3[t] = q
        for j in range(nb, nx):
            cj = cxi[j]
            sj = sxi[j]
            for t in range(mp):
                ur = gA[t] * (gc[t] * cj - gs[t] * sj) - gv[t]
                au = abs(ur)
                g2[t] += au * ur
                g3[t] += au * ur * ur
        for t in range(m):
            sc[SC_S2, idx[t]] = g2[t]
            sc[SC_S3, idx[t]] = g3[t]
    else:
        for jb in range(0, nb, 4):
            c0 = cxi[jb]
            c1 = cxi[jb + 1]
            c2 = cxi[jb + 2]
            c3 = cxi[jb + 3]
            s0 = sxi[jb]
            s1 = sxi[jb + 1]
            s2 = sxi[jb + 2]
            s3 = sxi[jb + 3]
            for t in range(mp):
                A = gA[t]
                c = gc[t]
                s = gs[t]
                v = gv[t]
                p = g2[t]
                ur = A * (c * c0 - s * s0) - v
                p += abs(ur) * ur
                ur = A * (c * c1 - s * s1) - v
                p += abs(ur) * ur
                ur = A * (c * c2 - s * s2) - v
                p += abs(ur) * ur
                ur = A * (c * c3 - s * s3) - v
                p += abs(ur) * ur
                g2[t] = p
        for j in range(nb, nx):
            cj = cxi[j]
            sj = sxi[j]
            for t in range(mp):
                ur = gA[t] * (gc[t] * cj - gs[t] * sj) - gv[t]
                g2[t] += abs(ur) * ur
        for t in range(m):
            sc[SC_S2, idx[t]] = g2[t]


@njit(**JITN)
def drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx, everyone):
    """Quadrature drag sums of every floe (:func:`drag_sums` / :func:`drag_force_sum`);
    returns the number of floes that needed the cell loop.

    ``theta_i`` from ``ck, sk = cos, sin(k x_i)`` and ``cwt, swt = cos, sin(omega t)``;
    fills ``sc[0], sc[1] = cos, sin theta_i``, ``sc[2] = s2``, ``sc[3] = s3`` (only if
    ``accumulate``); ``sc`` has N_SC rows, the others and ``idx`` are scratch; ``mom`` from
    :func:`drag_tables`.

    Two passes: a branch-free (vectorised) loop over all floes bounds u_rel on the floe
    (the cosine over the span [theta - h, theta + h] lies between its end values, or
    reaches +-1 inside) and evaluates the sums of the floes where u_rel has one sign in
    closed form from the table moments: with mu the mean of u_j and d_j = u_j - mu,
    ``sum u^2 = n mu^2 + sum d^2``, ``sum u^3 = n mu^3 + 3 mu sum d^2 + sum d^3``
    (sums of non-negative terms up to the small third moment: no cancellation; equal to
    the cell loop to rounding). Only the other floes run the cell loop
    (:func:`cell_sums`, vectorised across them). ``everyone``: no closed forms, every floe
    by the cell loop (long floes, where one-sign floes are rare).
    """
    n = ck.shape[0]
    if sc.shape[0] < N_SC or sc.shape[1] < n + LANES or idx.shape[0] < n:
        raise ValueError("drag_pass: scratch too small (sc needs N_SC rows and N_f + LANES"
                         " columns: new_scratch)")
    if everyone:
        for i in range(n):
            sc[SC_C, i] = ck[i] * cwt + sk[i] * swt
            sc[SC_S, i] = sk[i] * cwt - ck[i] * swt
            idx[i] = i
        cell_sums(sc, idx, n, a, P.u_amp, vs, cxi, sxi, accumulate)
        return n
    nn = mom[M_N]
    cb = mom[M_CB]
    sbb = mom[M_SB]
    vcc = mom[M_VCC]
    vcs = mom[M_VCS]
    vss = mom[M_VSS]
    tccc = mom[M_TCCC]
    tccs = mom[M_TCCS]
    tcss = mom[M_TCSS]
    tsss = mom[M_TSSS]
    ch = mom[M_CH]
    sh = mom[M_SH]
    cmax = mom[M_CMAX]
    ua = P.u_amp
    for i in range(n):
        c = ck[i] * cwt + sk[i] * swt
        s = sk[i] * cwt - ck[i] * swt
        sc[SC_C, i] = c
        sc[SC_S, i] = s
        A = a[i] * ua
        v = vs[i]
        X = A * c
        Y = A * s
        # range of A cos over the span: the ends, and A (-A) if cos = 1 (-1) inside it
        e1 = X * ch + Y * sh
        e2 = X * ch - Y * sh
        hi = max(e1, e2)
        lo = min(e1, e2)
        if c >= cmax:
            hi = max(hi, A)
            lo = min(lo, A)
        if -c >= cmax:
            hi = max(hi, -A)
            lo = min(lo, -A)
        w1 = hi - v
        w2 = lo - v
        sig = 1.0 if w1 > 0.0 else -1.0
        mu = X * cb - Y * sbb - v
        d2 = X * X * vcc - 2.0 * X * Y * vcs + Y * Y * vss
        sc[SC_S2, i] = sig * (nn * mu * mu + d2)
        if accumulate:
            d3 = (X * X * X * tccc - 3.0 * X * X * Y * tccs
                  + 3.0 * X * Y * Y * tcss - Y * Y * Y * tsss)
            sc[SC_S3, i] = sig * (nn * mu * mu * mu + 3.0 * mu * d2 + d3)
        sc[SC_FLAG, i] = 0.0 if w1 * w2 > 0.0 else 1.0
    m = general_floes(sc[SC_FLAG, :n], idx, mom[M_FAST] < 0.5)
    cell_sums(sc, idx, m, a, ua, vs, cxi, sxi, accumulate)
    return m


@njit(**JITN)
def floe_drag(A, c, s, v, accumulate, P, cxi, sxi):
    """(s2, s3): drag sums of one floe, by quadrature or exactly; s3 = 0 unless
    ``accumulate`` (the |u_rel|^3 sum is only needed in averaging windows)."""
    if P.drag == DRAG_EXACT:
        if accumulate:
            return drag_sums_exact(A, c, s, v, P.geom)
        return drag_force_exact(A, c, s, v, P.geom), 0.0
    if accumulate:
        return drag_sums(A, c, s, v, cxi, sxi)
    return drag_force_sum(A, c, s, v, cxi, sxi), 0.0


@njit(**JITN)
def wave_drag_update(i, x, a, s, s2, s3, P, F, accumulate, stats):
    """F_i = (1 + C_m) F_w,i + F_d,i from sin(theta_i) = ``s`` and the drag sums; stats."""
    Fw = P.c_wave * a[i] * s
    Fd = P.c_drag * s2
    F[i] = P.one_cm * Fw + Fd
    if accumulate:
        stats[ST_S3, i] += s3
        stats[ST_X, i] += x[i]
        stats[ST_FW, i] += abs(Fw)
        stats[ST_FD, i] += abs(Fd)


@njit(**JITN)
def eval_forces(x, vs, a, x0, ck, sk, cwt, swt, P, cxi, sxi, F, in_contact, accumulate,
                stats, mom, sc, idx, two_pass):
    """Total force of eq. 8 scaled to the left-hand side, (1 + C_m) F_w + F_d + F_c + F_s,
    on every floe at positions ``x`` and velocities ``vs``.

    The phase theta_i = k x_i - omega t enters through ck, sk = cos, sin(k x_i) and
    cwt, swt = cos, sin(omega t): cos theta = ck cwt + sk swt, sin theta = sk cwt - ck swt.
    Fills ``F`` [N]; when ``accumulate``, adds this step to ``stats`` and counts contact
    onsets against ``in_contact`` (always updated).

    Drag by :func:`drag_pass` / :func:`~floewave._exact.drag_pass_exact` (``mom``, scratch
    ``sc`` of N_SC rows, ``idx``); ``two_pass``: closed forms where they apply, else the
    general evaluation of every floe. Returns the number of floes that needed the general
    evaluation (-1 without ``two_pass``).
    """
    n = x.shape[0]
    m = -1
    # wave (Froude-Krylov) + ice-water drag: the drag sums of all floes first, then one
    # loop over the floes
    if P.drag == DRAG_EXACT:
        if two_pass:
            m = drag_pass_exact(ck, sk, cwt, swt, a, P.u_amp, vs, P.geom, accumulate, sc,
                                idx)
        else:
            for i in range(n):
                c = ck[i] * cwt + sk[i] * swt
                s = sk[i] * cwt - ck[i] * swt
                sc[SC_S, i] = s
                if accumulate:
                    s2, s3 = drag_sums_exact(a[i] * P.u_amp, c, s, vs[i], P.geom)
                    sc[SC_S3, i] = s3
                else:
                    s2 = drag_force_exact(a[i] * P.u_amp, c, s, vs[i], P.geom)
                sc[SC_S2, i] = s2
    else:
        m = drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx,
                      not two_pass)
        if not two_pass:
            m = -1
    for i in range(n):
        wave_drag_update(i, x, a, sc[SC_S, i], sc[SC_S2, i], sc[SC_S3, i], P, F,
                         accumulate, stats)
    # contacts between neighbours i, i+1
    Fc_prev = 0.0   # force of pair (i-1, i) pushing floe i towards +x
    for i in range(n - 1):
        gap = x[i + 1] - x[i] - P.L_x
        Fc = 0.0
        if gap < 0.0:
            Fc = contact_force(-gap, vs[i + 1] - vs[i], P)
            F[i] -= Fc
            F[i + 1] += Fc
        if accumulate:
            stats[ST_GAP, i] += gap
            stats[ST_FC, i] += abs(Fc_prev - Fc)
            if gap < 0.0:
                stats[ST_CONTACT, i] += 1.0
                if in_contact[i] == 0:
                    stats[ST_COLL, i] += 1.0
        in_contact[i] = 1 if gap < 0.0 else 0
        Fc_prev = Fc
    if accumulate:
        stats[ST_FC, n - 1] += abs(Fc_prev)
    # edge springs (boom and beach) on the first and last floe
    F[0] -= P.k_s * (x[0] - x0[0])
    F[n - 1] -= P.k_s * (x[n - 1] - x0[n - 1])
    return m


@njit(**JIT)
def initial_acceleration(x, u, a, x0, istep, P, cxi, sxi, acc, in_contact):
    """acc = F / ((1 + C_m) m) at step ``istep`` with velocities ``u`` (fills ``acc``)."""
    F = np.empty_like(x)
    dummy = np.zeros((N_STATS, x.shape[0]))
    wt = 2.0 * math.pi / P.n_t * (istep % P.n_t)
    ck = np.cos(P.k * x)
    sk = np.sin(P.k * x)
    eval_forces(x, u, a, x0, ck, sk, math.cos(wt), math.sin(wt), P, cxi, sxi, F, in_contact,
                False, dummy, np.zeros(N_MOM), np.zeros((N_SC, x.shape[0] + LANES)),
                np.zeros(x.shape[0], np.int64), False)
    for i in range(x.shape[0]):
        acc[i] = F[i] * P.inv_mass


@njit(**JIT)
def advance(x, u, acc, a, x0, in_contact, istep, nsteps, accumulate, P, cxi, sxi, stats,
            work, mom, idx):
    """Advance the floe chain ``nsteps`` time steps in place; return the new step index.

    Parameters
    ----------
    x, u, acc : (N_f,) positions [m], velocities [m s^-1], accelerations [m s^-2] at step
        ``istep`` (updated in place).
    a : (N_f,) wave amplitude attached to each floe [m].
    x0 : (N_f,) initial positions (edge springs act on floes 0 and N_f - 1) [m].
    in_contact : (N_f,) int8, 1 if pair (i, i+1) was in contact at the last step.
    istep : int, index of the current step (t = istep dt; the phase is taken modulo n_t).
    accumulate : bool, add this window to ``stats`` (rows ST_*).
    cxi, sxi : (n_x,) cos(k xi_j), sin(k xi_j) at the cell midpoints xi_j relative to the
        floe centre.
    work : (N_WORK, N_f + LANES) scratch (:func:`new_work`): half-step velocity, v*,
        force, cos(k x), sin(k x), and rows 5... for the drag (``sc`` of
        :func:`drag_pass`, N_SC rows).
    mom : :func:`drag_tables` of ``cxi, sxi``; idx : (N_f,) int64 scratch.

    cos, sin(k x_i) are computed once per call and then rotated by k dx_i each step
    (Taylor series of the rotation to O((k dx)^4), k dx ~ 1e-5: exact to rounding).

    The drag is evaluated in two passes (:func:`drag_pass`, :func:`~floewave._exact.
    drag_pass_exact`: closed forms for the floes where they apply, vectorised over floes,
    the general evaluation only for the others) unless a step finds more than 3/4 of the
    floes needing the general one (long floes: one-sign floes are rare there); then the
    plain per-floe loop is used for TWO_PASS_RETRY steps before the next two-pass trial.
    Same results to rounding either way.
    """
    n = x.shape[0]
    if work.shape[0] < N_WORK or work.shape[1] < n + LANES or idx.shape[0] < n:
        raise ValueError("advance: scratch too small (work needs N_WORK rows and N_f + LANES"
                         " columns: new_work)")
    dt = P.dt
    uh = work[0, :n]
    vs = work[1, :n]
    F = work[2, :n]
    ck = work[3, :n]
    sk = work[4, :n]
    sc = work[5:]
    for i in range(n):
        ck[i] = math.cos(P.k * x[i])
        sk[i] = math.sin(P.k * x[i])
    two_pi_nt = 2.0 * math.pi / P.n_t
    # drag in two passes (closed form where it applies, the general evaluation for the
    # rest) unless most floes need the general one (long floes): then the plain per-floe
    # loop, and a new two-pass trial every TWO_PASS_RETRY steps
    wait = 0
    for _ in range(nsteps):
        istep += 1
        for i in range(n):
            uh[i] = u[i] + 0.5 * dt * acc[i]
            if P.integrator == INTEG_PREDICTOR:
                vs[i] = u[i] + dt * acc[i]
            else:
                vs[i] = uh[i]
            dxi = dt * uh[i]
            x[i] += dxi
            e = P.k * dxi
            e2 = e * e
            ce = 1.0 - 0.5 * e2 + e2 * e2 * (1.0 / 24.0)
            se = e * (1.0 - e2 * (1.0 / 6.0))
            c_new = ck[i] * ce - sk[i] * se
            sk[i] = sk[i] * ce + ck[i] * se
            ck[i] = c_new
        wt = two_pi_nt * (istep % P.n_t)
        m = eval_forces(x, vs, a, x0, ck, sk, math.cos(wt), math.sin(wt), P, cxi, sxi, F,
                        in_contact, accumulate, stats, mom, sc, idx, wait == 0)
        if m < 0:
            wait -= 1
        elif 4 * m > 3 * n:
            wait = TWO_PASS_RETRY
        for i in range(n):
            acc[i] = F[i] * P.inv_mass
            u[i] = uh[i] + 0.5 * dt * acc[i]
    return istep


@njit(**JIT)
def confined_window(x0, a, nsteps, P, cxi, sxi, stats):
    """Floes held fixed (u = 0, docs/model.md §5): accumulate ``stats`` over ``nsteps`` steps.

    Only the wave-side rows (S3, X, FW, FD) are filled; gaps are constant.
    """
    n = x0.shape[0]
    two_pi_nt = 2.0 * math.pi / P.n_t
    ck = np.cos(P.k * x0)
    sk = np.sin(P.k * x0)
    F = np.empty(n)
    for istep in range(nsteps):
        wt = two_pi_nt * (istep % P.n_t)
        cwt = math.cos(wt)
        swt = math.sin(wt)
        for i in range(n):
            c = ck[i] * cwt + sk[i] * swt
            s = sk[i] * cwt - ck[i] * swt
            s2, s3 = floe_drag(a[i] * P.u_amp, c, s, 0.0, True, P, cxi, sxi)
            wave_drag_update(i, x0, a, s, s2, s3, P, F, True, stats)


def new_scratch(n: int) -> np.ndarray:
    """Drag scratch ``sc`` of :func:`drag_pass` / :func:`~floewave._exact.drag_pass_exact`
    for ``n`` floes: (N_SC, n + LANES)."""
    return np.zeros((N_SC, n + LANES))


def new_work(n: int) -> np.ndarray:
    """Scratch ``work`` of :func:`advance` for ``n`` floes: (N_WORK, n + LANES)."""
    return np.zeros((N_WORK, n + LANES))


def new_stats(n: int) -> np.ndarray:
    """Zeroed statistics array (N_STATS, n)."""
    return np.zeros((N_STATS, n))
