"""The exact drag (dx -> 0) of every floe of the flattened ensemble: the closed-form pass
(:func:`drag_pass_exact`) and its completion by prefix sums (:func:`exact_pass`).

The per-floe integrals are :mod:`floewave._exact`; the floes with a root of the integrand are
completed by :func:`floewave._prefix.prefix_sums` as the quadrature's are. Flags and why:
:mod:`floewave._jit`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._exact import H_POINT, drag_sums_exact
from ._jit import JIT, JITN
from ._layout import (
    LANES,
    M_CB,
    M_CHE,
    M_EXACT,
    M_FAST,
    M_H,
    M_HE,
    M_N,
    M_NROOT,
    M_SB,
    M_SCALE,
    M_SHE,
    M_T1,
    M_T2,
    M_T3,
    N_MOM,
    N_SC,
    SC_SIG,
)
from ._prefix import general_floes, prefix_sums

__all__ = ["drag_pass_exact", "exact_tables", "exact_pass"]

_TWO_PI = 2.0 * math.pi


@njit(**JITN)
def drag_pass_exact(ck, sk, cwt, swt, a, u_amp, vs, geom, accumulate, sc, idx,
                    defer=False):
    """:func:`drag_sums_exact` of every floe of a chain; returns the number of floes that
    needed the general (root-finding) evaluation.

    ``defer``: only the closed-form pass, for :func:`exact_pass` to
    complete the floes with a root (``idx[:m]``): their whole-floe sums stay signed (s3 not
    clipped) and ``sc[SC_SIG]`` gets the sign the closed form gave them (``sc`` then
    needs SC_SIG + 1 rows).

    ``theta_i = k x_i - omega t`` from ``ck, sk = cos, sin(k x_i)`` and ``cwt, swt = cos,
    sin(omega t)``; ``A_i = a_i u_amp``, ``v_i = vs[i]``. Fills ``sc[0], sc[1] = cos, sin
    theta_i``, ``sc[2] = s2``, ``sc[3] = s3`` (only if ``accumulate``); ``sc[4]`` and the
    int array ``idx`` are scratch (``sc`` has at least 5 rows and n columns, ``idx`` n entries,
    n the floes of all replicas).

    Two passes, same results as calling :func:`drag_sums_exact` floe by floe: a branch-free
    (vectorised) loop over all floes evaluates the one-sign case ``sigma W`` of
    :func:`drag_integrals` and flags the floes with a root of ``w`` on them; only those are
    then evaluated by :func:`drag_sums_exact` (at the benchmark state ~70 % of the floes
    of 0.5 m need no root).
    """
    n = ck.shape[0]
    h, ch, sh, scale, _n_x, K20, K22, K31, K33 = geom
    long_floe = h >= math.pi
    for i in range(n):
        c = ck[i] * cwt + sk[i] * swt
        s = sk[i] * cwt - ck[i] * swt
        sc[0, i] = c
        sc[1, i] = s
        A = a[i] * u_amp
        v = vs[i]
        # as drag_integrals: A < 0 is |A| with theta + pi
        neg = A < 0.0
        A = abs(A)
        c = -c if neg else c
        s = -s if neg else s
        X = A * c
        A2 = A * A
        v2 = v * v
        K1X = 2.0 * sh * X
        C2 = K20 * A2 + K22 * X * X
        W2 = C2 - 2.0 * v * K1X + 2.0 * h * v2
        Q2 = (A - v) * (A + v)
        Q = math.sqrt(max(Q2, 0.0))
        vc = v * c
        Ach = A * ch
        root = Q2 > 0.0 and (long_floe or vc + Q * s >= Ach or vc - Q * s >= Ach)
        wc = X - v
        sig = 1.0 if wc > 0.0 or (wc == 0.0 and v < 0.0) else -1.0
        sc[2, i] = scale * (sig * W2)
        if accumulate:
            W3 = X * (K31 * A2 + K33 * X * X) - 3.0 * v * C2 + 3.0 * v2 * K1X \
                - 2.0 * h * v2 * v
            sc[3, i] = scale * (sig * W3 if defer and root else max(sig * W3, 0.0))
        if defer:
            sc[SC_SIG, i] = sig
        sc[4, i] = 1.0 if root else 0.0
    m = general_floes(sc[4, :n], idx, h <= H_POINT)
    if defer:
        return m
    for t in range(m):
        i = idx[t]
        s2, s3 = drag_sums_exact(a[i] * u_amp, sc[0, i], sc[1, i], vs[i], geom)
        sc[2, i] = s2
        if accumulate:
            sc[3, i] = s3
    return m


@njit(**JIT)
def exact_tables(geom):
    """The :func:`drag_tables` entries :func:`prefix_sums` reads, for the exact drag
    (dx -> 0) of ``geom = exact_geometry(k L_x, n_x)``: the floe spans [-kL/2, kL/2], a root
    contributes at its own phase (the integral up to it instead of the cells before it),
    ``int cos(m psi) = sin(m psi) / m``, all in the quadrature's units (times n_x / kL)."""
    h, ch, sh, scale, n_x, K20, K22, K31, K33 = geom
    mom = np.zeros(N_MOM)
    mom[M_N] = n_x
    mom[M_CB] = sh / h if h > H_POINT else 1.0     # floe means of cos, sin of the phase
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

