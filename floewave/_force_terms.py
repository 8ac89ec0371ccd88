"""The forces of eq. 8 in the time loop: one small function per term, and their sum
:func:`eq8_forces` (docs/model.md §3)::

    (1 + C_m) m du_i/dt = (1 + C_m) F_w,i + F_d,i + F_c,i + F_s,i        (eq. 8)

(the added-mass force F_v = C_m (F_w - m du/dt) moved to the left-hand side). The terms are
functions of numbers, which LLVM inlines into the loop that calls them
(:func:`floewave._kernels.make_advance`); their coefficients are formulas of
:mod:`floewave.forces`, collected in :class:`~floewave._kernels.KernelParams` ``P``. Option
codes (``contact``, ``accumulate``, ...) are arguments, so that the built loop, which passes
constants, gets them folded away. Flags and why: :mod:`floewave._jit`.

:func:`eq8_forces` is inlined by numba itself (``inline="always"``, before typing): LLVM does
not inline a function of its size (seen in the generated code, 2026-12-04: it stayed a
function of its own, called every step with 17 arrays, ~120 machine words of arguments).
Inlined into a loop compiled without reference counting (``advance``: ``_nrt=False``), the
call adds no reference-count operations: the loop's machine code has the vector instructions
of the loop that wrote the forces inline and 3-7 % fewer instructions (static count); a
callgrind count of 360 spin-up steps of 8 x 84 floes ran 0.9 % more (2026-12-04).
"""
from __future__ import annotations

from numba import njit

from ._contact import contact_law
from ._drag import drag_pass
from ._exact_pass import exact_pass
from ._jit import JITN
from ._layout import (
    DRAG_EXACT,
    SC_S,
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
)

__all__ = ["wave_force", "skin_drag", "skin_drag_sums", "contact_force", "edge_spring",
           "eq8_forces"]


@njit(**JITN)
def wave_force(a, s, P):
    """Froude-Krylov force F_w,i = c_wave a_i sin(k x_i - omega t) [N] of a floe of amplitude
    ``a`` [m], ``s`` = sin(k x_i - omega t) (docs/model.md §3; ``P.c_wave``:
    :func:`floewave.forces.froude_krylov_coefficient`)."""
    return P.c_wave * a * s


@njit(**JITN)
def skin_drag(s2, P):
    """Ice-water skin drag F_d,i = rho_w C_sd L_y dx s2 [N] (eq. 15) of a floe whose
    floe-bottom sum of |u_rel| u_rel is ``s2`` [m^2 s^-2] (:func:`skin_drag_sums`)."""
    return P.c_drag * s2


@njit(**JITN)
def skin_drag_sums(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx, drag):
    """The floe-bottom sums of every floe of the flattened ensemble at wave phase
    theta_i = k x_i - omega t (``ck, sk = cos, sin(k x_i)``, ``cwt, swt = cos, sin(omega
    t)``), floe velocities ``vs``: ``sc[SC_S2]`` = sum |u_rel| u_rel (eq. 15),
    ``sc[SC_S3]`` = sum |u_rel|^3 (eq. 19, only if ``accumulate``), ``sc[SC_S]`` = sin
    theta_i. By quadrature over the n_x cells (:func:`floewave._drag.drag_pass`) or exactly,
    dx -> 0 (:func:`floewave._exact_pass.exact_pass`), as ``drag`` (``DRAG_*``) says."""
    if drag == DRAG_EXACT:
        exact_pass(ck, sk, cwt, swt, a, vs, P, mom, accumulate, sc, idx)
    else:
        drag_pass(ck, sk, cwt, swt, a, vs, P, cxi, sxi, mom, accumulate, sc, idx)


@njit(**JITN)
def contact_force(gap, v_n, P, contact, damping, clip):
    """Contact force [N] of the pair (i, i+1) with gap ``gap`` = x_{i+1} - x_i - L_x [m],
    positive when it pushes them apart: 0 while they are apart, else the contact law of
    :func:`floewave._contact.contact_law` at overlap -gap, ``v_n = u_{i+1} - u_i``."""
    f = 0.0
    if gap < 0.0:       # (most pairs are apart: the law only where they touch)
        f = contact_law(-gap, v_n, P, contact, damping, clip)
    return f


@njit(**JITN)
def edge_spring(x, x_start, P):
    """Edge-spring force F_s = -k_s (x_i(t) - x_i(0)) [N] of the tank's boom and beach,
    on the first and last floe of a chain (docs/model.md §3)."""
    return -(P.k_s * (x - x_start))


@njit(inline="always", **JITN)
def eq8_forces(F, Fc, x, vs, a, x0, sc, in_contact, stats, nf, P, contact, damping, clip,
               accumulate, drag_every, fresh):
    """The right-hand side of eq. 8 for every floe of the flattened ensemble into ``F`` [N]::

        F_i = (1 + C_m) F_w,i + F_d,i + F_c,i + F_s,i

    F_w: :func:`wave_force`, F_d: :func:`skin_drag` (the sums in ``sc``:
    :func:`skin_drag_sums`, held over ``drag_every`` steps), F_c,i = Fc_{i-1} - Fc_i with
    Fc_i the :func:`contact_force` of pair (i, i+1), kept in ``Fc`` (0 for the last floe of
    each chain of ``nf``), F_s: :func:`edge_spring` on the first and last floe of each chain.
    Velocity-dependent terms at ``vs`` (v*). ``in_contact`` [int8] gets 1 for the pairs that
    touch. ``accumulate``: add this step to the window statistics ``stats`` (ST_* rows),
    the dissipation sum s3 with the weight of the ``drag_every`` steps it stands for on the
    ``fresh`` steps that evaluated it.
    """
    nt = x.shape[0]
    w_s3 = float(drag_every)
    for j in range(nt):
        Fw = wave_force(a[j], sc[SC_S, j], P)
        Fd = skin_drag(sc[SC_S2, j], P)
        F[j] = P.one_cm * Fw + Fd
        if accumulate:
            if drag_every == 1:
                stats[ST_S3, j] += sc[SC_S3, j]
            elif fresh:
                stats[ST_S3, j] += w_s3 * sc[SC_S3, j]
            stats[ST_X, j] += x[j]
            stats[ST_FW, j] += abs(Fw)
            stats[ST_FD, j] += abs(Fd)
    for r in range(nt // nf):
        o = r * nf
        for j in range(o, o + nf - 1):
            gap = x[j + 1] - x[j] - P.L_x
            touch = gap < 0.0
            Fc[j] = contact_force(gap, vs[j + 1] - vs[j], P, contact, damping, clip)
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
        F[o] += edge_spring(x[o], x0[o], P)
        F[o + nf - 1] += edge_spring(x[o + nf - 1], x0[o + nf - 1], P)
