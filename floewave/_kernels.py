"""Numba kernels: the DEM time loop of an ensemble of floe chains (private; use
:mod:`floewave.model`).

Everything here is nopython, cached, without fast-math (flags and why:
:mod:`floewave._jit`). The kernels see only numpy arrays and a :class:`KernelParams` named
tuple of numbers built once per point from the frozen :class:`~floewave.config.ModelConfig`.

**One kernel for R replicas.** The R chains of an ensemble (docs/model.md §4 'Ensembles') run in
lockstep: their states are rows of (R, N_f) arrays, and the kernel loops over the flattened
index ``j = r N_f + i``. Every per-floe loop (drift, drag, wave force, kick) has no
neighbour dependency and is vectorised across floes *and* replicas; the contact loop runs
over the N_f - 1 pairs of each replica. Nothing couples replicas: every number of replica r
is computed by the same operations on the same inputs whatever R is (tested bit for bit).

**Built from frozen options.** :func:`make_advance` builds the time loop for one
:class:`KernelOptions` (contact law, damping, clipping, integrator, drag mode, accumulate or
not) and caches it, as PyMPDATA's ``make_step_impl`` does: the options are constants of the
compiled code, so no option is tested inside the time loop, and the force evaluation is
written once. The built function is a closure over plain numbers only, so numba's on-disk
cache keys it by those numbers and loads it in a new process (a closure over another
*jitted* function would not be: numba pickles a dispatcher with a per-process id, and every
process would compile again). Helpers it calls are module-level functions.

Time integration (velocity Verlet, docs/model.md §3), per step n -> n+1::

    u_half = u_n + dt/2 acc_n
    x_{n+1} = x_n + dt u_half
    acc_{n+1} = a(x_{n+1}, v*, t_{n+1})       # eq. 8 / ((1 + C_m) m)
    u_{n+1} = u_half + dt/2 acc_{n+1}

with velocity-dependent forces (drag, contact damping) evaluated at
``v* = u_n + dt acc_n`` (``integrator = "predictor"``, second order) or at
``v* = u_half`` (``"half_step"``, as LIGGGHTS does; first order in the damping).

**Quadrature drag in O(1) per floe** (:func:`drag_pass`, :func:`prefix_sums`). The paper's
drag and dissipation are sums over the n_x = L_x/dx cells of a floe of |w| w and |w|^3,
``w_j = A cos(theta + phi_j) - v`` at the cell phases ``phi_j = -h + j k dx``. A floe where
w has one sign is summed in closed form from the cell tables' central moments; on the
others the sign of w changes only at the roots of ``A cos(theta + phi) = v``, so the sum is
the whole-floe sum plus, per root, twice a prefix sum of the cells before it (geometric sums
over the cell phases in closed form, :func:`prefix_sums`): a handful of operations per root
instead of a loop over n_x cells (50-300 at the paper's dx). Equal to the cell loop to
rounding (within 1e-13 of the floe's scale (|A| + |v|)^m n_x, tested against
:func:`drag_sums`; tables with k dx outside [KDX_MIN, KDX_MAX] take the cell loop).
"""
from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ._exact import (
    _H_POINT,
    SIG_ROW,
    drag_pass_exact,
    drag_sums_exact,
    exact_geometry,
    general_floes,
)
from ._jit import JIT, JITN
from .config import ModelConfig
from .forces import (
    effective_modulus,
    froude_krylov_coefficient,
    orbital_velocity_amplitude,
    restitution_beta,
)

# option codes (decided once from ModelConfig)
CONTACT_HERTZ_DISK = 0
CONTACT_LINEAR = 1
DAMPING_LIGGGHTS = 0
DAMPING_EXACT = 1
INTEG_PREDICTOR = 0
INTEG_HALF_STEP = 1
DRAG_QUADRATURE = 0
DRAG_EXACT = 1

# rows of the per-window statistics array ``stats`` (shape (N_STATS, R N_f))
ST_S3 = 0        # sum over steps and cells of |u_rel|^3            [m^3 s^-3]
ST_X = 1         # sum over steps of x_i                            [m]
ST_GAP = 2       # sum over steps of gap_i (pair i, i+1)            [m]
ST_CONTACT = 3   # steps in contact (pair i, i+1)                   [-]
ST_COLL = 4      # contact onsets (pair i, i+1)                     [-]
ST_FW = 5        # sum over steps of |F_w,i|                        [N]
ST_FC = 6        # sum over steps of |net contact force on i|       [N]
ST_FD = 7        # sum over steps of |F_d,i|                        [N]
N_STATS = 8

# rows of the drag scratch ``sc`` (shape (N_SC, R N_f + LANES)) of drag_pass /
# drag_pass_exact
SC_C = 0         # cos theta_i
SC_S = 1         # sin theta_i
SC_S2 = 2        # drag sum of |u_rel| u_rel
SC_S3 = 3        # drag sum of |u_rel|^3 (accumulating steps only)
SC_FLAG = 4      # 1: the floe needs the general evaluation
SC_SIG = SIG_ROW  # (5) sign the closed form gave the floe's whole-floe sums
SC_GATHER = 6    # rows 6-18: the general floes gathered by cell_sums / prefix_sums
N_GATHER = 13
N_SC = SC_GATHER + N_GATHER
W_UH = 0         # rows of advance's scratch ``work``: half-step velocity,
W_VS = 1         # velocity v* of the forces,
W_F = 2          # force,
W_CK = 3         # cos(k x), sin(k x),
W_SK = 4
W_FC = 5         # contact force of pair (j, j+1),
W_VC = 6         # velocity and cos, sin(k x) at the centre of a held drag's steps
W_CKC = 7        # (drag_every > 1),
W_SKC = 8
W_SC = 9         # then the drag scratch sc (N_SC rows)
N_WORK = W_SC + N_SC
LANES = 16       # gathered floes are padded to a multiple of this (vector body)


class KernelParams(NamedTuple):
    """Numbers the time loop needs, SI units (built by :func:`kernel_params`)."""

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
    drag_every: int    # steps between evaluations of the drag and dissipation sums [-]
    geom: tuple        # floewave._exact.exact_geometry(k L_x, n_x) (used when drag = EXACT)


def kernel_params(cfg: ModelConfig, k: float) -> KernelParams:
    """Build the kernel's coefficient tuple for ``cfg`` and wavenumber ``k``."""
    Ystar = effective_modulus(cfg)
    r = cfg.L_x / 2.0
    return KernelParams(
        dt=cfg.dt,
        n_t=cfg.n_t,
        k=k,
        omega=cfg.omega,
        c_wave=froude_krylov_coefficient(cfg, k),
        u_amp=orbital_velocity_amplitude(cfg, k),
        c_drag=cfg.rho_w * cfg.C_sd * cfg.L_y * (cfg.L_x / cfg.n_x),
        inv_mass=1.0 / ((1.0 + cfg.C_m) * cfg.mass),
        one_cm=1.0 + cfg.C_m,
        L_x=cfg.L_x,
        k_s=cfg.k_s,
        m_star=cfg.mass / 2.0,
        beta=restitution_beta(cfg.eps),
        kn_lin=Ystar * cfg.L_y * cfg.h_i / cfg.L_x,
        kn_disk=math.pi * Ystar * cfg.h_i,
        s_scale=(r / 2.0) / (2.0 * cfg.h_i**2),
        contact=CONTACT_HERTZ_DISK if cfg.contact == "hertz_disk" else CONTACT_LINEAR,
        damping=DAMPING_LIGGGHTS if cfg.damping == "liggghts" else DAMPING_EXACT,
        clip=1 if cfg.clip_attraction else 0,
        integrator=INTEG_PREDICTOR if cfg.integrator == "predictor" else INTEG_HALF_STEP,
        drag=DRAG_QUADRATURE if cfg.drag_integration == "quadrature" else DRAG_EXACT,
        drag_every=cfg.drag_every,
        geom=exact_geometry(k * cfg.L_x, float(cfg.n_x)),
    )


class KernelOptions(NamedTuple):
    """The frozen choices a time loop is built for (:func:`make_advance`)."""

    contact: int
    damping: int
    clip: int
    integrator: int
    drag: int
    drag_every: int    # evaluate the drag sums every this many steps (held in between)
    accumulate: bool   # add every step to the window statistics


def kernel_options(P: KernelParams, accumulate: bool) -> KernelOptions:
    """The options of ``P`` (its option codes) for a spin-up or an averaging loop."""
    return KernelOptions(int(P.contact), int(P.damping), int(P.clip), int(P.integrator),
                         int(P.drag), int(P.drag_every), bool(accumulate))


@njit(**JITN)
def contact_law(delta, v_n, P, contact, damping, clip):
    """Normal contact force [N] pushing a pair apart at overlap ``delta`` > 0:
    F = k_n delta - gamma_n v_n, ``v_n = u_{i+1} - u_i`` (positive while separating).

    k_n: ``hertz_disk`` f(s) (docs/model.md §3) or ``linear``; gamma_n = -beta sqrt(5 k_n m*)
    (liggghts) or -2 beta sqrt(k_n m*) (exact); clipped at 0 if ``clip``. The option codes
    are arguments so that a caller with constant options (the built time loop) gets them
    folded away.
    """
    kn = _stiffness(delta, P, contact)
    if damping == DAMPING_LIGGGHTS:
        gamma = -P.beta * math.sqrt(5.0 * kn * P.m_star)
    else:
        gamma = -2.0 * P.beta * math.sqrt(kn * P.m_star)
    F = kn * delta - gamma * v_n
    if clip == 1 and F < 0.0:
        F = 0.0
    return F


@njit(**JITN)
def _stiffness(delta, P, contact):
    """k_n [N m^-1] at overlap ``delta``: ``hertz_disk`` f(s) (docs/model.md §3) or ``linear``."""
    if contact == CONTACT_LINEAR:
        return P.kn_lin
    s = delta * P.s_scale
    return P.kn_disk * ((0.9117 * s * s + 0.2722 * s + 0.003324)
                        / (s * s + 1.524 * s + 0.03159))


@njit(**JITN)
def contact_stiffness(delta, P):
    """k_n for overlap ``delta`` [N m^-1] (the stiffness of :func:`contact_law`)."""
    return _stiffness(delta, P, P.contact)


@njit(**JITN)
def contact_force(delta, v_n, P):
    """:func:`contact_law` with the options of ``P``."""
    return contact_law(delta, v_n, P, P.contact, P.damping, P.clip)


@njit(**JITN)
def drag_sums(A, c, s, v, cxi, sxi):
    """Sums over the floe-bottom cells of |u_rel| u_rel and |u_rel|^3 (eqs. 15, 19): the
    paper's quadrature, cell by cell (the reference of the fast evaluation in the kernel).

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
M_FAST = 13      # 1: tables as built by FloeChain (closed forms and prefix sums usable)
M_H = 14         # h = k (L_x - dx) / 2, phase offset of the outer cell midpoints
M_KDX = 15       # delta = k dx, phase step between cells
M_INV_KDX = 16   # 1 / delta
M_NROOT = 17     # most roots of one family on a floe: floor(2 h / 2 pi) + 1
M_HE = 18        # k L_x / 2 = h + delta / 2, phase offset of the floe's ends
M_CHE = 19       # cos, sin of M_HE
M_SHE = 20
M_T1 = 21        # 1 / (2 sin(m delta / 2)), m = 1, 2, 3 (geometric sums of cos(m psi_j))
M_T2 = 22
M_T3 = 23
M_EXACT = 24     # 1: tables of the exact drag (exact_tables): roots at their own phase
M_SCALE = 25     # n_x / (k L_x): the exact drag's integrals in cells
N_MOM = 26
# the geometric sums are evaluated with Taylor series of sin, cos of d, |d| <= delta / 2
# (:func:`_sin_cos_small`): the prefix sums of drag_pass need delta = k dx up to this (at
# most 0.035 in the paper's grid); coarser tables are summed cell by cell
KDX_MAX = 0.05
# ... and down to this: the geometric sums carry 1 / (2 sin(m delta / 2)) ~ 1 / (m delta), so
# their rounding grows as eps / delta (measured: 1.6e-13 of the floe's scale at delta = 1e-3,
# 3e-12 at 5e-7); finer tables are summed cell by cell as well
KDX_MIN = 1e-3

_TWO_PI = 2.0 * math.pi


@njit(**JIT)
def drag_tables(cxi, sxi, P):
    """Moments of the cell tables for the closed-form sums of one-sign floes and the
    prefix sums of the others (:func:`drag_pass`); built once per chain."""
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
    # the cells are at offsets k xi_j = -h + j k dx, h = k (L_x - dx) / 2 (tables of
    # FloeChain: cxi = cos(k xi), sxi = sin(k xi), symmetric; anything else: no fast path)
    h = 0.5 * P.k * P.L_x * (n - 1) / n
    ch = cxi[n - 1]
    sh = sxi[n - 1]
    fast = 1.0
    if (n < 2 or abs(math.cos(h) - ch) > 1e-9 or abs(math.sin(h) - sh) > 1e-9
            or abs(cxi[0] - ch) > 1e-9 or abs(sxi[0] + sh) > 1e-9 or h <= 0.0):
        fast = 0.0
    else:
        kdx = 2.0 * h / (n - 1)
        if kdx > KDX_MAX or kdx < KDX_MIN:
            fast = 0.0
        for j in range(n):
            if (abs(math.cos(-h + j * kdx) - cxi[j]) > 1e-9
                    or abs(math.sin(-h + j * kdx) - sxi[j]) > 1e-9):
                fast = 0.0
    mom[M_CH] = ch
    mom[M_SH] = sh
    mom[M_CMAX] = ch if h < math.pi - 1e-6 else -2.0
    mom[M_FAST] = fast
    kdx = 2.0 * h / (n - 1) if n > 1 else 0.0
    mom[M_H] = h
    mom[M_KDX] = kdx
    mom[M_INV_KDX] = 1.0 / kdx if kdx > 0.0 else 0.0
    mom[M_NROOT] = math.floor(2.0 * h / _TWO_PI) + 1.0
    he = h + 0.5 * kdx
    mom[M_HE] = he
    mom[M_CHE] = math.cos(he)
    mom[M_SHE] = math.sin(he)
    for mm in range(1, 4):
        sm = math.sin(0.5 * mm * kdx)
        mom[M_T1 + mm - 1] = 0.5 / sm if sm != 0.0 else 0.0
    return mom


@njit(**JIT)
def exact_tables(geom):
    """The :func:`drag_tables` entries :func:`prefix_sums` reads, for the exact drag
    (dx -> 0) of ``geom = exact_geometry(k L_x, n_x)``: the floe spans [-kL/2, kL/2], a root
    contributes at its own phase (the integral up to it instead of the cells before it),
    ``int cos(m psi) = sin(m psi) / m``, all in the quadrature's units (times n_x / kL)."""
    h, ch, sh, scale, n_x, K20, K22, K31, K33 = geom
    mom = np.zeros(N_MOM)
    mom[M_N] = n_x
    mom[M_CB] = sh / h if h > _H_POINT else 1.0     # floe means of cos, sin of the phase
    mom[M_SB] = 0.0
    # (short floes, kL < 2e-3: the per-floe path, whose series keep the accuracy there)
    mom[M_FAST] = 1.0 if h > 1e-3 else 0.0
    mom[M_H] = h
    mom[M_HE] = h
    mom[M_CHE] = ch
    mom[M_SHE] = sh
    mom[M_NROOT] = math.floor(2.0 * h / _TWO_PI) + 1.0
    mom[M_T1] = scale
    mom[M_T2] = scale / 2.0
    mom[M_T3] = scale / 3.0
    mom[M_EXACT] = 1.0
    mom[M_SCALE] = scale
    return mom


@njit(**JITN)
def exact_pass(ck, sk, cwt, swt, a, vs, P, mom, accumulate, sc, idx):
    """The exact (dx -> 0) drag of every floe of the flattened ensemble, equal to
    :func:`~floewave._exact.drag_sums_exact` floe by floe to rounding; returns the number
    of floes with a root of w on them. ``mom`` from :func:`exact_tables`.

    The one-sign closed form of :func:`~floewave._exact.drag_pass_exact` (``defer``) for
    every floe (vectorised), then the floes with a root by :func:`prefix_sums`, as the
    quadrature's.
    A point-like floe (kL ~ 0) takes the per-floe path.
    """
    n = ck.shape[0]
    if sc.shape[0] < N_SC or sc.shape[1] < n + LANES or idx.shape[0] < n:
        raise ValueError("exact_pass: scratch too small (sc needs N_SC rows and R N_f + LANES"
                         " columns: new_scratch)")
    if mom[M_FAST] < 0.5:
        return drag_pass_exact(ck, sk, cwt, swt, a, P.u_amp, vs, P.geom, accumulate, sc, idx)
    m = drag_pass_exact(ck, sk, cwt, swt, a, P.u_amp, vs, P.geom, accumulate, sc, idx, True)
    prefix_sums(sc, idx, m, a, P.u_amp, vs, mom, accumulate)
    return m


@njit(**JITN)
def cell_sums(sc, idx, m, a, ua, vs, cxi, sxi, accumulate):
    """:func:`drag_sums` of the ``m`` floes ``idx[:m]`` into ``sc[2]`` (and ``sc[3]`` if
    ``accumulate``), bit for bit, vectorised across floes (the loop over cells outside, the
    loop over the gathered floes inside: no reduction in the inner loop, and each floe's sum
    runs over the cells in the source's order). Used on cell tables the prefix sums cannot
    take (``mom[M_FAST] = 0``)."""
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
    for j in range(cxi.shape[0]):
        cj = cxi[j]
        sj = sxi[j]
        for t in range(mp):
            ur = gA[t] * (gc[t] * cj - gs[t] * sj) - gv[t]
            au = abs(ur)
            g2[t] += au * ur
            g3[t] += au * ur * ur
    for t in range(m):
        sc[SC_S2, idx[t]] = g2[t]
        if accumulate:
            sc[SC_S3, idx[t]] = g3[t]


@njit(**JITN)
def _angle(x, y):
    """atan2(y, x) of a point on the unit circle, branch-free for the vectoriser:
    2 atan(y / (1 + x)) by the half-angle identity on the half with x >= 0, mirrored
    otherwise; both through an odd rational atan on |t| <= tan(pi/8) after one reduction."""
    ax = abs(x)
    # angle of (ax, |y|) in [0, pi/2]: t = |y| / (1 + ax) = tan(angle / 2) in [0, 1]
    t = abs(y) / (1.0 + ax)
    # atan(t), t in [0, 1]: reduce t > tan(pi/8) by atan(t) = pi/4 + atan((t-1)/(t+1))
    big = t > 0.41421356237309503
    u = (t - 1.0) / (t + 1.0) if big else t
    z = u * u
    # atan(u) for |u| <= tan(pi/8): u + u z P(z) / Q(z) (Cephes atan, relative error ~2e-16)
    p = ((((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z
           - 7.500855792314704667340e1) * z - 1.228866684490136173410e2) * z
         - 6.485021904942025371773e1)
    q = (((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z
           + 4.328810604912902668951e2) * z + 4.853903996359136964868e2) * z
         + 1.945506571482613964425e2)
    at = u + u * z * p / q
    if big:
        at += 0.25 * math.pi
    b = 2.0 * at
    if x < 0.0:
        b = math.pi - b
    return math.copysign(b, y)


@njit(**JITN)
def _sin_cos_small(x):
    """(sin x, cos x) for |x| <= KDX_MAX / 2 = 0.025 by Taylor series to x^7, x^8 (error
    < 1e-20)."""
    x2 = x * x
    sx = x * (1.0 - x2 * (1.0 / 6.0) * (1.0 - x2 * (1.0 / 20.0) * (
        1.0 - x2 * (1.0 / 42.0))))
    cx = 1.0 - x2 * 0.5 * (1.0 - x2 * (1.0 / 12.0) * (1.0 - x2 * (1.0 / 30.0) * (
        1.0 - x2 * (1.0 / 56.0))))
    return sx, cx


@njit(**JITN)
def prefix_sums(sc, idx, m, a, ua, vs, mom, accumulate):
    """Quadrature drag sums of the ``m`` floes ``idx[:m]`` whose w may change sign on the
    floe (equal to :func:`drag_sums` to rounding), into ``sc[2]`` (and ``sc[3]`` if
    ``accumulate``); on entry ``sc[SC_S2]``, ``sc[SC_S3]`` hold the closed form's signed
    whole-floe sums and ``sc[SC_SIG]`` its sign.

    Roots. With psi = theta + phi, w = A cos psi - v > 0 between a root of the family
    ``psi = -alpha`` and the next of ``+alpha`` (``cos alpha = v/A``), < 0 after it.
    Telescoping the signed sums over the segments between roots, with ``F(b) = sum_{j<b}
    w_j^2`` (G: w^3) and b the number of cells before a root::

        s2 = sigma_last F(n) + 2 sum_{+ roots} F(b) - 2 sum_{- roots} F(b)

    sigma_last the sign after the last root; F(n) is the closed form's whole-floe sum
    (central moments, no cancellation). A cell within rounding of a root may land on
    either side: its w is then ~1e-13 of A, its share nothing.

    Prefix sums without tables. ``w^2 = A^2/2 (1 + cos 2 psi) - 2 A v cos psi + v^2`` and
    ``w^3`` likewise in cos m psi, m <= 3; over cells ``psi_j = psi_0 + j delta``,
    ``sum_{j<b} cos(m psi_j) = [sin(m e_b) - sin(m e_0)] / (2 sin(m delta / 2))`` with
    ``e_b`` the left edge of cell b. The edge next to a root lies within delta/2 of it,
    and cos, sin of the root are (p, +-q): ``sin(m e_b)`` follows from Chebyshev's
    multiple angles and Taylor series of the offset (:func:`_sin_cos_small`); ``e_0`` is
    the floe's end, theta - k L_x / 2. No table, no gather, no library call: the loops
    over the gathered floes vectorise (tables read at a computed index do not).
    """
    h = mom[M_H]
    kdx = mom[M_KDX]
    inv_kdx = mom[M_INV_KDX]
    nroot = int(mom[M_NROOT])
    fnroot = float(nroot)
    nx = mom[M_N]
    cb = mom[M_CB]
    sbb = mom[M_SB]
    he = mom[M_HE]
    che = mom[M_CHE]
    she = mom[M_SHE]
    t1 = mom[M_T1]
    t2 = mom[M_T2]
    t3 = mom[M_T3]
    exact = mom[M_EXACT] > 0.5
    scale = mom[M_SCALE]
    gA = sc[SC_GATHER]         # |A|
    gc = sc[SC_GATHER + 1]     # cos, sin theta of |A| (theta + pi if A < 0)
    gs = sc[SC_GATHER + 2]
    gv = sc[SC_GATHER + 3]
    gp = sc[SC_GATHER + 4]     # first '+' root offset from the floe centre (1e300: none)
    gm = sc[SC_GATHER + 5]     # first '-' root offset
    g2 = sc[SC_GATHER + 6]
    g3 = sc[SC_GATHER + 7]
    gl = sc[SC_GATHER + 8]     # sign after the last root
    gpp = sc[SC_GATHER + 9]    # p = cos alpha = v / |A|, q = sin alpha
    gqq = sc[SC_GATHER + 10]
    gc2 = sc[SC_GATHER + 11]   # cos 2 alpha = p^2 - q^2, and cos 3 alpha
    gc3 = sc[SC_GATHER + 12]
    mp = ((m + LANES - 1) // LANES) * LANES
    # every floe (the common case of floes longer than ~1 m): idx is the identity, so copy
    # without it (a loop without indexed loads vectorises). general_floes writes increasing
    # indices, so idx[:m] is 0 .. m-1 exactly when its last entry is m - 1
    dense = m > 0 and idx[m - 1] == m - 1
    if dense:
        for t in range(m):
            _gather(sc, t, t, a, ua, vs, gA, gc, gs, gv)
    else:
        for t in range(m):
            _gather(sc, idx[t], t, a, ua, vs, gA, gc, gs, gv)
    for t in range(m, mp):      # padding lanes: A = v = 0, results unused
        gA[t] = 0.0
        gc[t] = 1.0
        gs[t] = 0.0
        gv[t] = 0.0
    for t in range(mp):
        A = gA[t]
        c = gc[t]
        s = gs[t]
        p = gv[t] / A if A > 0.0 else 0.0
        p = min(max(p, -1.0), 1.0)
        q = math.sqrt((1.0 - p) * (1.0 + p))
        gpp[t] = p
        gqq[t] = q
        gc2[t] = (p - q) * (p + q)
        gc3[t] = p * (4.0 * p * p - 3.0)
        bp = _angle(p * c + q * s, q * c - p * s)          # alpha - theta
        bm = _angle(p * c - q * s, -q * c - p * s)         # -alpha - theta
        rp = bp + _TWO_PI * np.ceil((-h - bp) * (1.0 / _TWO_PI))
        rm = bm + _TWO_PI * np.ceil((-h - bm) * (1.0 / _TWO_PI))
        none = q == 0.0 or A == 0.0     # tangent (|v| = |A|) or w constant: no sign change
        if none:
            rp = 1e300
            rm = 1e300
        gp[t] = rp
        gm[t] = rm
        # roots on the floe (the same expression decides below which roots count) and the
        # sign after the last one; none: the sign of w's mean
        # (at most nroot: the loop below enumerates that many, and a first root a few ulp
        # below -h with 2h a few ulp below a multiple of 2 pi would count one more)
        n_p = min(np.floor((h - rp) * (1.0 / _TWO_PI)) + 1.0, fnroot) if rp <= h else 0.0
        n_m = min(np.floor((h - rm) * (1.0 / _TWO_PI)) + 1.0, fnroot) if rm <= h else 0.0
        lp = rp + _TWO_PI * (n_p - 1.0) if n_p > 0.0 else -1e300
        lm = rm + _TWO_PI * (n_m - 1.0) if n_m > 0.0 else -1e300
        v = gv[t]
        mu = A * (c * cb - s * sbb) - v
        last = 1.0 if mu > 0.0 else -1.0
        if lp > lm:
            last = -1.0
        elif lm > lp:
            last = 1.0
        gl[t] = last
        # the prefix sums' terms of the floe's start edge e_0 = theta - k L_x / 2, once
        # per root of weight +-2: net weight 2 (n_p - n_m)
        wnet = 2.0 * (n_p - n_m)
        se = s * che - c * she
        ce = c * che + s * she
        S1 = se * t1
        S2 = 2.0 * se * ce * t2
        g2[t] = -wnet * (0.5 * A * A * S2 - 2.0 * A * v * S1)
        if accumulate:
            S3 = se * (3.0 - 4.0 * se * se) * t3
            g3[t] = -wnet * (0.25 * A * A * A * (3.0 * S1 + S3) - 1.5 * A * A * v * S2
                             + 3.0 * A * v * v * S1)
    for fam in range(2):
        rows = gp if fam == 0 else gm
        w = 2.0 if fam == 0 else -2.0
        ssign = 1.0 if fam == 0 else -1.0      # sin psi at the root: +q ('+'), -q ('-')
        for kk in range(nroot):
            off = _TWO_PI * kk
            fk = float(kk)
            for t in range(mp):
                r0 = rows[t]
                n_r = (min(np.floor((h - r0) * (1.0 / _TWO_PI)) + 1.0, fnroot)
                       if r0 <= h else 0.0)
                on = fk < n_r
                r = r0 + off if on else 0.0
                if exact:       # the integral up to the root (in cells): at the root
                    b = (min(r, he) + he) * scale
                    d = 0.0
                else:           # the cells before the root: up to the edge of cell b
                    b = np.floor((r + h) * inv_kdx) + 1.0
                    b = min(max(b, 0.0), nx)
                    d = (b * kdx - he) - r
                A = gA[t]
                v = gv[t]
                p = gpp[t]
                q = ssign * gqq[t]            # sin psi at the root, and its multiples
                s1, c1 = _sin_cos_small(d)
                s2d = 2.0 * s1 * c1
                c2d = (c1 - s1) * (c1 + s1)
                S1 = (q * c1 + p * s1) * t1
                S2 = (2.0 * p * q * c2d + gc2[t] * s2d) * t2
                F = (0.5 * A * A + v * v) * b + 0.5 * A * A * S2 - 2.0 * A * v * S1
                g2[t] += w * F if on else 0.0
                if accumulate:
                    s3d = s1 * (3.0 - 4.0 * s1 * s1)
                    c3d = c1 * (4.0 * c1 * c1 - 3.0)
                    S3 = (q * (3.0 - 4.0 * q * q) * c3d + gc3[t] * s3d) * t3
                    G = (0.25 * A * A * A * (3.0 * S1 + S3) - 1.5 * A * A * v * (b + S2)
                         + 3.0 * A * v * v * S1 - v * v * v * b)
                    g3[t] += w * G if on else 0.0
    if dense:
        for t in range(m):
            _finish(sc, t, t, gl, g2, g3, accumulate)
    else:
        for t in range(m):
            _finish(sc, idx[t], t, gl, g2, g3, accumulate)


@njit(**JITN)
def _gather(sc, i, t, a, ua, vs, gA, gc, gs, gv):
    """Lane ``t`` of :func:`prefix_sums` from floe ``i``: |A|, cos, sin theta of |A|, v."""
    A = a[i] * ua
    flip = A < 0.0             # A < 0 is |A| at theta + pi
    gA[t] = abs(A)
    gc[t] = -sc[SC_C, i] if flip else sc[SC_C, i]
    gs[t] = -sc[SC_S, i] if flip else sc[SC_S, i]
    gv[t] = vs[i]


@njit(**JITN)
def _finish(sc, i, t, gl, g2, g3, accumulate):
    """Floe ``i``'s drag sums from lane ``t`` of :func:`prefix_sums` and the closed form's
    signed whole-floe sums."""
    sig = sc[SC_SIG, i]
    last = gl[t]
    sc[SC_S2, i] = last * (sig * sc[SC_S2, i]) + g2[t]
    if accumulate:
        sc[SC_S3, i] = max(last * (sig * sc[SC_S3, i]) + g3[t], 0.0)


@njit(**JITN)
def drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx):
    """Quadrature drag sums of every floe of the flattened ensemble (equal to
    :func:`drag_sums` floe by floe, to rounding); returns the number of floes where w
    changes sign.

    ``theta_i`` from ``ck, sk = cos, sin(k x_i)`` and ``cwt, swt = cos, sin(omega t)``;
    fills ``sc[0], sc[1] = cos, sin theta_i``, ``sc[2] = s2``, ``sc[3] = s3`` (only if
    ``accumulate``); the other rows of ``sc`` and ``idx`` are scratch; ``mom`` from
    :func:`drag_tables`.

    A branch-free (vectorised) loop over all floes bounds w on the floe (the cosine over
    the span [theta - h, theta + h] lies between its end values, or reaches +-1 inside) and
    evaluates the whole-floe sums in closed form: with mu the mean of w_j and
    d_j = w_j - mu, ``sum w^2 = n mu^2 + sum d^2``, ``sum w^3 = n mu^3 + 3 mu sum d^2 +
    sum d^3`` (no cancellation). The floes where w may change sign are then completed by
    :func:`prefix_sums` (or by the cell loop :func:`cell_sums` on tables the prefix sums
    cannot take: ``mom[M_FAST] = 0``).
    """
    n = ck.shape[0]
    if sc.shape[0] < N_SC or sc.shape[1] < n + LANES or idx.shape[0] < n:
        raise ValueError("drag_pass: scratch too small (sc needs N_SC rows and R N_f + LANES"
                         " columns: new_scratch)")
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
        sc[SC_SIG, i] = sig
        sc[SC_FLAG, i] = 0.0 if w1 * w2 > 0.0 else 1.0
    if mom[M_FAST] > 0.5:
        m = general_floes(sc[SC_FLAG, :n], idx, False)
        prefix_sums(sc, idx, m, a, ua, vs, mom, accumulate)
    else:
        m = general_floes(sc[SC_FLAG, :n], idx, True)
        cell_sums(sc, idx, m, a, ua, vs, cxi, sxi, accumulate)
    return m


@njit(**JITN)
def floe_drag(A, c, s, v, accumulate, P, cxi, sxi):
    """(s2, s3): drag sums of one floe, by quadrature or exactly; s3 = 0 unless
    ``accumulate`` (the |u_rel|^3 sum is only needed in averaging windows)."""
    if P.drag == DRAG_EXACT:
        s2, s3 = drag_sums_exact(A, c, s, v, P.geom)
    else:
        s2, s3 = drag_sums(A, c, s, v, cxi, sxi)
    return s2, (s3 if accumulate else 0.0)


@functools.cache
def make_advance(opts: KernelOptions):
    """The time loop for ``opts``, compiled once per process (cached on disk by numba).

    ``advance(x, u, acc, a, x0, in_contact, istep, nsteps, nf, P, cxi, sxi, mom, stats,
    work, idx, init) -> istep`` advances the R = x.size / nf chains ``nsteps``
    steps in place (flattened (R, N_f) arrays: positions [m], velocities [m s^-1],
    accelerations [m s^-2] at step ``istep``; ``a`` the amplitudes [m], ``x0`` the initial
    positions on whose floes 0 and N_f - 1 the edge springs act, ``in_contact`` int8, 1 if
    pair (j, j+1) was in contact at the last evaluation). ``init``: first evaluate the
    forces at the current state with v* = u and set ``acc`` from them (a new amplitude
    profile); only in a loop built without ``accumulate``. ``stats`` (N_STATS, R N_f) gets
    every step when built with ``accumulate``. ``work`` (:func:`new_work`), ``idx``
    (int64, R N_f) are scratch; ``cxi, sxi`` the cell tables, ``mom`` their
    moments.

    cos, sin(k x_j) are computed once per call and then rotated by k dx_j each step
    (Taylor series of the rotation to O((k dx)^4), k dx ~ 1e-5: exact to rounding).
    """
    contact, damping, clip, integrator, drag, drag_every, accumulate = opts
    contact = int(contact)
    damping = int(damping)
    clip = int(clip)
    integrator = int(integrator)
    drag = int(drag)
    drag_every = int(drag_every)
    w_s3 = float(drag_every)
    accumulate = bool(accumulate)

    @njit(**JIT)
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
        R = nt // nf
        dt = P.dt
        uh = work[W_UH, :nt]
        vs = work[W_VS, :nt]
        F = work[W_F, :nt]
        ck = work[W_CK, :nt]
        sk = work[W_SK, :nt]
        Fc = work[W_FC, :nt]
        vc = work[W_VC, :nt]
        ckc = work[W_CKC, :nt]
        skc = work[W_SKC, :nt]
        sc = work[W_SC:]
        # a held drag is evaluated at the centre of the steps it holds, (drag_every - 1) / 2
        # steps ahead: the wave phase at that time, the floe moved on by v* and its velocity
        # by acc (a midpoint rule: second order in the hold)
        half = 0.5 * (drag_every - 1)
        h_dt = half * dt
        for j in range(nt):
            ck[j] = math.cos(P.k * x[j])
            sk[j] = math.sin(P.k * x[j])
        two_pi_nt = 2.0 * math.pi / P.n_t
        step = -1 if init else 0
        while step < nsteps:
            if step >= 0:
                istep += 1
                for j in range(nt):
                    uh[j] = u[j] + 0.5 * dt * acc[j]
                    if integrator == INTEG_PREDICTOR:
                        vs[j] = u[j] + dt * acc[j]
                    else:
                        vs[j] = uh[j]
                    dxj = dt * uh[j]
                    x[j] += dxj
                    e = P.k * dxj
                    e2 = e * e
                    ce = 1.0 - 0.5 * e2 + e2 * e2 * (1.0 / 24.0)
                    se = e * (1.0 - e2 * (1.0 / 6.0))
                    c_new = ck[j] * ce - sk[j] * se
                    sk[j] = sk[j] * ce + ck[j] * se
                    ck[j] = c_new
            else:
                for j in range(nt):
                    vs[j] = u[j]
            wt = two_pi_nt * (istep % P.n_t)
            cwt = math.cos(wt)
            swt = math.sin(wt)
            # --- forces of eq. 8, scaled to the left-hand side: (1 + C_m) F_w + F_d + F_c
            # + F_s. Wave (Froude-Krylov) and ice-water drag: the drag sums of all floes
            # first, then one loop over the floes
            # (drag_every > 1: the drag sums are evaluated on the steps istep = 0 mod
            # drag_every and at an ``init``, and held in ``sc`` on the steps between; the
            # dissipation sum of an evaluation stands for the drag_every steps it holds)
            fresh = drag_every == 1 or step < 0 or istep % drag_every == 0
            if drag_every == 1 or step < 0:
                if drag == DRAG_EXACT:
                    exact_pass(ck, sk, cwt, swt, a, vs, P, mom, accumulate, sc, idx)
                else:
                    drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc,
                              idx)
            else:
                if fresh:
                    wc = two_pi_nt * ((istep % P.n_t) + half)
                    cwc = math.cos(wc)
                    swc = math.sin(wc)
                    for j in range(nt):
                        vc[j] = vs[j] + h_dt * acc[j]
                        e = P.k * h_dt * vs[j]
                        e2 = e * e
                        ce = 1.0 - 0.5 * e2 + e2 * e2 * (1.0 / 24.0)
                        se = e * (1.0 - e2 * (1.0 / 6.0))
                        ckc[j] = ck[j] * ce - sk[j] * se
                        skc[j] = sk[j] * ce + ck[j] * se
                    if drag == DRAG_EXACT:
                        exact_pass(ckc, skc, cwc, swc, a, vc, P, mom, accumulate, sc, idx)
                    else:
                        drag_pass(ckc, skc, cwc, swc, a, vc, P, cxi, sxi, mom, accumulate,
                                  sc, idx)
                for j in range(nt):         # the wave phase of this step (wave force)
                    sc[SC_S, j] = sk[j] * cwt - ck[j] * swt
            for j in range(nt):
                Fw = P.c_wave * a[j] * sc[SC_S, j]
                Fd = P.c_drag * sc[SC_S2, j]
                F[j] = P.one_cm * Fw + Fd
                if accumulate:
                    if drag_every == 1:
                        stats[ST_S3, j] += sc[SC_S3, j]
                    elif fresh:
                        stats[ST_S3, j] += w_s3 * sc[SC_S3, j]
                    stats[ST_X, j] += x[j]
                    stats[ST_FW, j] += abs(Fw)
                    stats[ST_FD, j] += abs(Fd)
            # contacts between neighbours j, j+1 of each replica
            for r in range(R):
                o = r * nf
                for j in range(o, o + nf - 1):
                    gap = x[j + 1] - x[j] - P.L_x
                    touch = gap < 0.0
                    f = 0.0
                    if touch:       # (most pairs are apart: the law only where they touch)
                        f = contact_law(-gap, vs[j + 1] - vs[j], P, contact, damping, clip)
                    Fc[j] = f
                    if accumulate:
                        stats[ST_GAP, j] += gap
                        if touch:
                            stats[ST_CONTACT, j] += 1.0
                            if in_contact[j] == 0:
                                stats[ST_COLL, j] += 1.0
                    in_contact[j] = 1 if touch else 0
                Fc[o + nf - 1] = 0.0
                F[o] -= Fc[o]
                if accumulate:
                    stats[ST_FC, o] += abs(Fc[o])
                for j in range(o + 1, o + nf):
                    F[j] = (F[j] + Fc[j - 1]) - Fc[j]
                    if accumulate:
                        stats[ST_FC, j] += abs(Fc[j - 1] - Fc[j])
                # edge springs (boom and beach) on the first and last floe
                F[o] -= P.k_s * (x[o] - x0[o])
                F[o + nf - 1] -= P.k_s * (x[o + nf - 1] - x0[o + nf - 1])
            if step >= 0:
                for j in range(nt):
                    acc[j] = F[j] * P.inv_mass
                    u[j] = uh[j] + 0.5 * dt * acc[j]
            else:
                for j in range(nt):
                    acc[j] = F[j] * P.inv_mass
            step += 1
        return istep

    return advance


@njit(**JIT)
def confined_window(x0, a, nsteps, P, cxi, sxi, stats):
    """Floes held fixed (u = 0, docs/model.md §5): accumulate ``stats`` over ``nsteps`` steps.

    Only the wave-side rows (S3, X, FW, FD) are filled; gaps are constant.
    """
    n = x0.shape[0]
    two_pi_nt = 2.0 * math.pi / P.n_t
    ck = np.cos(P.k * x0)
    sk = np.sin(P.k * x0)
    for istep in range(nsteps):
        wt = two_pi_nt * (istep % P.n_t)
        cwt = math.cos(wt)
        swt = math.sin(wt)
        for i in range(n):
            c = ck[i] * cwt + sk[i] * swt
            s = sk[i] * cwt - ck[i] * swt
            s2, s3 = floe_drag(a[i] * P.u_amp, c, s, 0.0, True, P, cxi, sxi)
            Fw = P.c_wave * a[i] * s
            Fd = P.c_drag * s2
            stats[ST_S3, i] += s3
            stats[ST_X, i] += x0[i]
            stats[ST_FW, i] += abs(Fw)
            stats[ST_FD, i] += abs(Fd)


def new_scratch(n: int) -> np.ndarray:
    """Drag scratch ``sc`` of :func:`drag_pass` / :func:`~floewave._exact.drag_pass_exact`
    for ``n`` floes (all replicas): (N_SC, n + LANES)."""
    return np.zeros((N_SC, n + LANES))


def new_work(n: int) -> np.ndarray:
    """Scratch ``work`` of the time loop for ``n`` floes (all replicas):
    (N_WORK, n + LANES)."""
    return np.zeros((N_WORK, n + LANES))


def new_stats(n: int) -> np.ndarray:
    """Zeroed statistics array (N_STATS, n)."""
    return np.zeros((N_STATS, n))
