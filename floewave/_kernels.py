"""The DEM time loop of an ensemble of floe chains, built from frozen options (private; use
:mod:`floewave.model`), with its parameters, a chain's whole set-up (:func:`chain_kernel`),
the confined window and the scratch arrays.

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
written once (:func:`make_confined_window` likewise, for the drag mode of fixed floes);
:class:`KernelParams` holds numbers only. The built function is a closure over plain
numbers only, so numba's on-disk cache keys it by those numbers and loads it in a new
process (a closure over another *jitted* function would not be: numba pickles a dispatcher
with a per-process id, and every process would compile again). Helpers it calls are
module-level functions.

Time integration (velocity Verlet, docs/model.md §3), per step n -> n+1::

    u_half = u_n + dt/2 acc_n
    x_{n+1} = x_n + dt u_half
    acc_{n+1} = a(x_{n+1}, v*, t_{n+1})       # eq. 8 / ((1 + C_m) m)
    u_{n+1} = u_half + dt/2 acc_{n+1}

with velocity-dependent forces (drag, contact damping) evaluated at
``v* = u_n + dt acc_n`` (``integrator = "predictor"``, second order) or at
``v* = u_half`` (``"half_step"``, as LIGGGHTS does; first order in the damping).

The parts it calls live in the other kernel files (``floewave._jit.KERNEL_SOURCES``): the
forces of eq. 8, one small function each, and their sum in :mod:`floewave._force_terms`
(numba inlines the sum into the loop, and LLVM the terms: the loop compiles to the code it
compiled to when the forces were written inline; ``advance`` is compiled without reference
counting, which it never needs, so the inlined call costs no reference-count operations), the
contact law in :mod:`floewave._contact`, the quadrature drag in :mod:`floewave._drag`, the
exact drag in :mod:`floewave._exact` (per floe) and :mod:`floewave._exact_pass`, the floes
with a root of either in :mod:`floewave._prefix`, and the option codes and array layouts in
:mod:`floewave._layout` (re-exported here).
"""
from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

# (contact_stiffness, cell_sums, drag_pass, drag_tables, exact_pass, exact_tables:
# re-exported)
from ._contact import contact_stiffness  # noqa: F401
from ._drag import cell_sums, drag_pass, drag_sums, drag_tables  # noqa: F401
from ._exact import drag_sums_exact, exact_geometry
from ._exact_pass import exact_pass, exact_tables  # noqa: F401
from ._force_terms import eq8_forces, skin_drag, skin_drag_sums, wave_force
from ._jit import JIT, JITN
from ._layout import *  # noqa: F403 (option codes and row layouts, re-exported)
from ._layout import (
    CONTACT_HERTZ_DISK,
    CONTACT_LINEAR,
    DAMPING_EXACT,
    DAMPING_LIGGGHTS,
    DRAG_EXACT,
    DRAG_QUADRATURE,
    HOLD_LINEAR,
    HOLD_MIDPOINT,
    INTEG_HALF_STEP,
    INTEG_MTS,
    INTEG_PREDICTOR,
    INTEG_RESPA,
    LANES,
    N_SC,
    N_STATS,
    N_WORK,
    SC_S,
    SC_S2,
    ST_FD,
    ST_FW,
    ST_S3,
    ST_X,
    W_CK,
    W_CKC,
    W_D0,
    W_DI,
    W_DS,
    W_F,
    W_FC,
    W_SC,
    W_SK,
    W_SKC,
    W_UH,
    W_VC,
    W_VS,
)
from ._respa import make_advance_respa
from .config import ModelConfig
from .forces import cell_offsets, time_loop_coefficients


class KernelParams(NamedTuple):
    """Numbers the time loop needs, SI units (built by :func:`kernel_params`); the choices
    it is built for are :class:`KernelOptions`, constants of the compiled code."""

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
    geom: tuple        # floewave._exact.exact_geometry(k L_x, n_x) (the exact drag's)


def kernel_params(cfg: ModelConfig, k: float) -> KernelParams:
    """Build the kernel's coefficient tuple for ``cfg`` and wavenumber ``k``: the step, the
    wave, and eq. 8's coefficients (:func:`floewave.forces.time_loop_coefficients`)."""
    return KernelParams(dt=cfg.dt, n_t=cfg.n_t, k=k, omega=cfg.omega, L_x=cfg.L_x,
                        geom=exact_geometry(k * cfg.L_x, float(cfg.n_x)),
                        **time_loop_coefficients(cfg, k))


class KernelOptions(NamedTuple):
    """The frozen choices a time loop is built for (:func:`make_advance`)."""

    contact: int
    damping: int
    clip: int
    integrator: int
    drag: int
    drag_every: int    # evaluate the drag sums every this many steps (held in between)
    hold: int          # how a held drag is evaluated (``HOLD_*``, drag_every > 1)
    accumulate: bool   # add every step to the window statistics


def kernel_options(cfg: ModelConfig, accumulate: bool) -> KernelOptions:
    """The options (codes) of ``cfg`` for a spin-up or an averaging loop."""
    return KernelOptions(
        contact=CONTACT_HERTZ_DISK if cfg.contact == "hertz_disk" else CONTACT_LINEAR,
        damping=DAMPING_LIGGGHTS if cfg.damping == "liggghts" else DAMPING_EXACT,
        clip=1 if cfg.clip_attraction else 0,
        integrator={"predictor": INTEG_PREDICTOR, "half_step": INTEG_HALF_STEP,
                    "respa": INTEG_RESPA, "mts": INTEG_MTS}[cfg.integrator],
        drag=DRAG_QUADRATURE if cfg.drag_integration == "quadrature" else DRAG_EXACT,
        drag_every=int(cfg.drag_every),
        hold=HOLD_LINEAR if cfg.drag_hold == "linear" else HOLD_MIDPOINT,
        accumulate=bool(accumulate))


@njit(**JITN)
def floe_drag(A, c, s, v, accumulate, drag, P, cxi, sxi):
    """(s2, s3): drag sums of one floe, by quadrature or exactly (``drag``: ``DRAG_*``);
    s3 = 0 unless ``accumulate`` (the |u_rel|^3 sum is only needed in averaging windows)."""
    if drag == DRAG_EXACT:
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
    contact, damping, clip, integrator, drag, drag_every, hold, accumulate = opts
    contact = int(contact)
    damping = int(damping)
    clip = int(clip)
    integrator = int(integrator)
    drag = int(drag)
    drag_every = int(drag_every)
    linear = drag_every > 1 and int(hold) == HOLD_LINEAR
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
        d0 = work[W_D0, :nt]
        ds = work[W_DS, :nt]
        di = work[W_DI, :nt]
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
            # --- forces of eq. 8 (eq8_forces), the drag sums of all floes first
            # (drag_every > 1: the drag sums are evaluated on the steps istep = 0 mod
            # drag_every and at an ``init``, and held in ``sc`` on the steps between; the
            # dissipation sum of an evaluation stands for the drag_every steps it holds)
            fresh = drag_every == 1 or step < 0 or istep % drag_every == 0
            if drag_every == 1 or step < 0 or (linear and fresh):
                skin_drag_sums(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc,
                               idx, drag)
                if linear:
                    # "linear": the sums of the true state of this step; the slope from
                    # the last evaluation (none across an ``init``: new amplitudes)
                    fi = float(istep)
                    for j in range(nt):
                        s2 = sc[SC_S2, j]
                        gap = fi - di[j]
                        ds[j] = (s2 - d0[j]) / gap if (step >= 0 and gap > 0.0) else 0.0
                        d0[j] = s2
                        di[j] = fi
            elif linear:
                # between evaluations: extrapolated along the last slope
                fi = float(istep)
                for j in range(nt):
                    sc[SC_S2, j] = d0[j] + ds[j] * (fi - di[j])
                    sc[SC_S, j] = sk[j] * cwt - ck[j] * swt
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
                    skin_drag_sums(ckc, skc, cwc, swc, a, vc, P, cxi, sxi, mom, accumulate,
                                   sc, idx, drag)
                for j in range(nt):         # the wave phase of this step (wave force)
                    sc[SC_S, j] = sk[j] * cwt - ck[j] * swt
            eq8_forces(F, Fc, x, vs, a, x0, sc, in_contact, stats, nf, P, contact, damping,
                       clip, accumulate, drag_every, fresh)
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


class ChainKernel(NamedTuple):
    """A chain's kernel set up for ``cfg`` and one wavenumber (:func:`chain_kernel`)."""

    P: KernelParams
    opts: KernelOptions    # the spin-up loop's options (``accumulate`` off)
    cxi: np.ndarray        # cos(k xi), sin(k xi) at the cell offsets xi (forces.cell_offsets)
    sxi: np.ndarray
    mom: tuple             # the tables' moments for the drag mode the loops run
    spin: object           # make_advance(opts)
    average: object        # make_advance of the same options with ``accumulate`` on


def chain_kernel(cfg: ModelConfig, k: float) -> ChainKernel:
    """The kernel's whole set-up for a chain of ``cfg`` at wavenumber ``k``: coefficients,
    options, cell tables and their moments, and the two compiled time loops (spin-up,
    averaging)."""
    opts = kernel_options(cfg, False)
    make = (make_advance_respa if opts.integrator in (INTEG_RESPA, INTEG_MTS)
            else make_advance)
    spin = make(opts)
    average = make(opts._replace(accumulate=True))
    P = kernel_params(cfg, k)
    xi = cell_offsets(cfg)
    cxi = np.cos(k * xi)
    sxi = np.sin(k * xi)
    # the tables' moments for the drag mode the loops run (prefix_sums reads either)
    mom = exact_tables(P.geom) if opts.drag == DRAG_EXACT else drag_tables(cxi, sxi, P)
    return ChainKernel(P, opts, cxi, sxi, mom, spin, average)


@functools.cache
def make_confined_window(drag: int):
    """The confined window for drag mode ``drag`` (``DRAG_*``), compiled once per process
    (cached on disk by numba; the mode is a constant of the compiled code, as the options of
    :func:`make_advance` are).

    ``confined_window(x0, a, nsteps, P, cxi, sxi, stats)``: floes held fixed (u = 0,
    docs/model.md §5) at ``x0``, amplitudes ``a``: accumulate ``stats`` over ``nsteps``
    steps. Only the wave-side rows (S3, X, FW, FD) are filled; gaps are constant.
    """
    drag = int(drag)

    @njit(**JIT)
    def confined_window(x0, a, nsteps, P, cxi, sxi, stats):
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
                if drag == DRAG_EXACT:
                    s2, s3 = drag_sums_exact(a[i] * P.u_amp, c, s, 0.0, P.geom)
                else:
                    s2, s3 = drag_sums(a[i] * P.u_amp, c, s, 0.0, cxi, sxi)
                Fw = wave_force(a[i], s, P)
                Fd = skin_drag(s2, P)
                stats[ST_S3, i] += s3
                stats[ST_X, i] += x0[i]
                stats[ST_FW, i] += abs(Fw)
                stats[ST_FD, i] += abs(Fd)

    return confined_window


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
