"""The floes where the drag's integrand changes sign: picked out (:func:`general_floes`) and
their drag sums completed by prefix sums in O(1) per root (:func:`prefix_sums`), for both drag
modes.

Called by the quadrature pass (:func:`floewave._drag.drag_pass`) and the exact pass
(:func:`floewave._exact_pass.exact_pass`) after their closed-form pass over every floe; the
method is in :func:`prefix_sums`'s docstring and docs/model.md §3. Flags and why:
:mod:`floewave._jit`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._jit import JITN
from ._layout import (
    LANES,
    M_CB,
    M_CHE,
    M_EXACT,
    M_H,
    M_HE,
    M_INV_KDX,
    M_KDX,
    M_N,
    M_NROOT,
    M_SB,
    M_SCALE,
    M_SHE,
    M_T1,
    M_T2,
    M_T3,
    SC_C,
    SC_GATHER,
    SC_S,
    SC_S2,
    SC_S3,
    SC_SIG,
)

__all__ = ["general_floes", "prefix_sums", "angle_unit"]

_TWO_PI = 2.0 * math.pi


@njit(**JITN)
def general_floes(flags, idx, everyone):
    """Write the indices of the floes with ``flags[i] == 1`` (all floes if ``everyone``)
    to the front of ``idx``; return their count. After the closed-form pass of
    :func:`floewave._exact_pass.drag_pass_exact`, :func:`floewave._drag.drag_pass`
    or :func:`floewave._exact_pass.exact_pass`, only those floes get the general evaluation."""
    n = flags.shape[0]
    if everyone:
        for i in range(n):
            idx[i] = i
        return n
    m = 0
    for i in range(n):      # branch-free compaction
        idx[m] = i
        m += 1 if flags[i] > 0.5 else 0
    return m


@njit(**JITN)
def angle_unit(x, y):
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
        bp = angle_unit(p * c + q * s, q * c - p * s)          # alpha - theta
        bm = angle_unit(p * c - q * s, -q * c - p * s)         # -alpha - theta
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

