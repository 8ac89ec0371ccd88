"""The quadrature drag: the paper's floe-bottom sums (eqs. 15, 19) over the n_x = L_x/dx cells
of every floe, in O(1) per floe (:func:`drag_pass`), and their cell-by-cell reference
(:func:`drag_sums`).

**In O(1) per floe** (:func:`drag_pass`, :func:`~floewave._prefix.prefix_sums`). The paper's
drag and dissipation are sums over the n_x = L_x/dx cells of a floe of |w| w and |w|^3,
``w_j = A cos(theta + phi_j) - v`` at the cell phases ``phi_j = -h + j k dx``. A floe where
w has one sign is summed in closed form from the cell tables' central moments; on the
others the sign of w changes only at the roots of ``A cos(theta + phi) = v``, so the sum is
the whole-floe sum plus, per root, twice a prefix sum of the cells before it (geometric
sums over the cell phases in closed form, :func:`~floewave._prefix.prefix_sums`): a handful
of operations per root instead of a loop over n_x cells (50-300 at the paper's dx). Equal
to the cell loop to rounding (within 1e-13 of the floe's scale (|A| + |v|)^m n_x, tested
against :func:`drag_sums`; tables with k dx outside [KDX_MIN, KDX_MAX] take the cell loop).

Flags and why: :mod:`floewave._jit`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._jit import JIT, JITN
from ._layout import (
    KDX_MAX,
    KDX_MIN,
    LANES,
    M_CB,
    M_CH,
    M_CHE,
    M_CMAX,
    M_FAST,
    M_H,
    M_HE,
    M_INV_KDX,
    M_KDX,
    M_N,
    M_NROOT,
    M_SB,
    M_SH,
    M_SHE,
    M_T1,
    M_TCCC,
    M_TCCS,
    M_TCSS,
    M_TSSS,
    M_VCC,
    M_VCS,
    M_VSS,
    N_MOM,
    N_SC,
    SC_C,
    SC_FLAG,
    SC_GATHER,
    SC_S,
    SC_S2,
    SC_S3,
    SC_SIG,
)
from ._prefix import general_floes, prefix_sums

__all__ = ["drag_sums", "drag_tables", "drag_pass", "cell_sums"]

_TWO_PI = 2.0 * math.pi


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
