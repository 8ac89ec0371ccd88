"""Closed-form ("exact") floe-bottom integrals of the quadratic ice-water drag (docs/model.md §3).

The quadrature mode (:func:`floewave._kernels.drag_sums`) sums over the ``n_x = L_x / dx``
cells of a floe, at the cell midpoints ``xi_j``,

    s2 = sum_j |w_j| w_j,     s3 = sum_j |w_j|^3,     w_j = A cos(theta + k xi_j) - v,

(drag force ``F_d = rho_w C_sd L_y dx s2``; ``s3`` feeds the dissipation). The exact mode
returns the limit ``dx -> 0`` of the same sums, **in the same units** (a count of cells times
velocity^2 resp. velocity^3)::

    s2 = n_x / (k L) * int_{theta - kL/2}^{theta + kL/2} |w(phi)| w(phi) dphi
    s3 = n_x / (k L) * int_{theta - kL/2}^{theta + kL/2} |w(phi)|^3     dphi
    w(phi) = A cos(phi) - v,

so ``s2``, ``s3`` drop in wherever the quadrature sums are used (``n_x / (kL) = 1 / (k dx)``;
``rho_w C_sd L_y dx s2 = rho_w C_sd L_y int |u_rel| u_rel dxi``). The caller passes ``n_x``
once, through :func:`exact_geometry`.

Method. ``|w| w = sigma w^2`` and ``|w|^3 = sigma w^3`` with ``sigma = sign(w)`` constant
between the roots of ``A cos(phi) = v`` (``phi = +-alpha + 2 pi n``, ``cos alpha = p = v/A``,
``sin alpha = q = sqrt(1 - p^2)``; none if ``|v| >= A``). Everything is relative to the floe
centre, ``u = phi - theta in [-h, h]``, ``h = kL/2``; ``theta`` itself is never needed (the
kernel carries only ``c = cos theta``, ``s = sin theta``). With ``sigma_a`` the sign at the
start ``u = -h``::

    I = sigma_a (W - 2 J)

``W`` = integrals of ``w^2``, ``w^3`` over the whole floe, polynomials in ``X = A c`` and
``v`` with per-run constants (``int cos = 2 sin h c``, ``int cos^2 = K20 + K22 c^2``,
``int cos^3 = K31 c + K33 c^3``, :func:`exact_geometry`); ``J`` = the same integrals over the
pieces of sign ``-sigma_a``: whole lobes between consecutive roots (closed form: ``[-alpha,
alpha]`` or ``[alpha, 2 pi - alpha]``) plus, for an odd number of roots, the piece from the
last root to the end ``[beta, h]``. On a piece ``[phi_1, phi_2]``::

    int w^2 = (A^2/2 + v^2) D0 + A^2/2 D2 - 2 A v D1
    int w^3 = A^3 (D1 - D3/3) - 3/2 A^2 v (D0 + D2) + 3 A v^2 D1 - v^3 D0
    D0 = phi_2 - phi_1, D1 = [sin phi], D2 = [sin phi cos phi], D3 = [sin^3 phi]

(``[g] = g(phi_2) - g(phi_1)``), with ``cos, sin`` at the floe end from ``c, s`` rotated by
``h`` and at a root ``(p, +-q)``.

Cheapness (no allocation, no Python objects, no library transcendental call):

* ``|v| >= A`` or no root on the floe (the common case): ``sigma W``, ~30 flops;
* ``h < pi``: root family ``+alpha`` (``-alpha``) lies on the floe iff the cosine of its
  offset from the centre, ``(v c + Q s) / A`` (``(v c - Q s) / A``), ``Q = A q``, is
  ``>= cos h``. Two roots: one whole lobe (which one: the one not containing the antipode
  ``theta + pi``) needs ``alpha``; one root: its offset ``beta`` from ``(cos beta, sin
  beta)``. Angles come from :func:`_angle`, an inline atan2 on the unit circle (fdlibm's
  rational asin on an argument ``<= 0.5``, ~1 ulp of pi);
* ``h >= pi`` (``kL >= 2 pi``): both families' offsets are computed, the roots on the floe
  counted; whole lobes are constants, only the piece after the last root is evaluated:
  O(1) for any number of periods.

Accuracy. ``[sin]``, ``[sin cos]`` over a short piece (half-width ``d < 0.1``) use the
product forms ``2 cos(mid) sin d``, ``2 cos(2 mid) sin d cos d`` with Taylor ``sin d, cos d``
(exact to rounding) and the midpoint by rotating the piece's start; longer pieces use plain
differences; ``K20 = h - sin h cos h`` by its series for small ``h``. The absolute error is a
few ulp of ``(A + |v|)^m kL``, i.e. ~1e-15 relative to the scale ``(A + |v|)^m n_x``
(``m = 2, 3``) for any ``kL`` (``kL -> 0``: ``s -> n_x f(theta)``; ``kL = 0`` returns exactly
``n_x f(theta)``). Only the linear term needs the root offsets to full accuracy.
"""
from __future__ import annotations

import math

from numba import njit

from ._jit import JITN as JIT  # no allocation anywhere here: no reference counting

__all__ = ["exact_geometry", "drag_integrals", "drag_sums_exact", "drag_force_exact",
           "drag_sums_exact_phase", "drag_pass_exact", "general_floes"]

_TWO_PI = 2.0 * math.pi
# half-width below which s = n_x f(theta) exactly: the floe average differs from the centre
# value by O(h^2) (f = |w| w is C^1), below rounding; also avoids underflow for tiny kL
_H_POINT = 1.0e-17
# the scratch row of drag_pass_exact(defer=True)'s closed-form signs
# (floewave._kernels.SC_SIG)
SIG_ROW = 5


@njit(**JIT)
def _h_minus_sincos(h):
    """h - sin h cos h = (x - sin x) / 2, x = 2h, without cancellation for small h."""
    x = 2.0 * h
    if x > 1.0:
        return h - math.sin(h) * math.cos(h)
    x2 = x * x
    term = x * x2 / 6.0
    acc = 0.0
    n = 3
    while abs(term) > 1e-18 * abs(acc) or acc == 0.0:
        acc += term
        term *= -x2 / ((n + 1) * (n + 2))
        n += 2
        if term == 0.0:
            break
    return 0.5 * acc


@njit(**JIT)
def exact_geometry(kL, n_x):
    """Per-run constants of the exact drag (a tuple of floats; build once, pass to every call).

    kL : floe length times wavenumber [rad] (``k L_x``), ``>= 0``.
    n_x : number of quadrature cells ``L_x / dx`` the sums are expressed in [-].

    Returns ``(h, cos h, sin h, n_x / kL, n_x, K20, K22, K31, K33)`` with ``h = kL / 2`` and
    the whole-floe moments ``int_{-h}^{h} cos^2(theta + u) du = K20 + K22 cos^2 theta``,
    ``int cos^3 = K31 cos theta + K33 cos^3 theta`` (``int cos = 2 sin h cos theta``).
    """
    h = 0.5 * kL
    sh = math.sin(h)
    ch = math.cos(h)
    scale = n_x / kL if h > _H_POINT else float(n_x)
    K20 = _h_minus_sincos(h)                   # h - sh ch
    K22 = 2.0 * sh * ch                        # sin 2h
    K31 = 2.0 * sh * sh * sh                   # (3/2) sh - sin(3h) / 2
    K33 = 2.0 * sh - (8.0 / 3.0) * sh * sh * sh    # (2/3) sin 3h
    return (h, ch, sh, scale, float(n_x), K20, K22, K31, K33)


# asin on |x| <= 0.5: x + x R(x^2), R the rational approximation of fdlibm's e_asin.c
# (relative error < 2.5e-16 there). Its coefficients carry this notice:
#   Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
#   Developed at SunPro, a Sun Microsystems, Inc. business.
#   Permission to use, copy, modify, and distribute this software is freely granted,
#   provided that this notice is preserved.
_PS0 = 1.66666666666666657415e-01
_PS1 = -3.25565818622400915405e-01
_PS2 = 2.01212532134862925881e-01
_PS3 = -4.00555345006794114027e-02
_PS4 = 7.91534994289814532176e-04
_PS5 = 3.47933107596021167570e-05
_QS1 = -2.40339491173441421878e+00
_QS2 = 2.02094576023350569471e+00
_QS3 = -6.88283971605453293030e-01
_QS4 = 7.70381505559019352791e-02


@njit(**JIT)
def _asin_small(x):
    """asin(x) for |x| <= 0.5, inline (no library call)."""
    z = x * x
    num = z * (_PS0 + z * (_PS1 + z * (_PS2 + z * (_PS3 + z * (_PS4 + z * _PS5)))))
    den = 1.0 + z * (_QS1 + z * (_QS2 + z * (_QS3 + z * _QS4)))
    return x + x * (num / den)


@njit(**JIT)
def _angle(x, y):
    """atan2(y, x) for a point (x, y) on the unit circle, inline: asin of an argument
    <= 0.5 (of |y|, of x, or of sin(angle/2) = sqrt((1 - |x|)/2)); absolute error ~1 ulp
    of pi."""
    ax = abs(x)
    ay = abs(y)
    if ay <= 0.5:
        b = _asin_small(ay)
        if x < 0.0:
            b = math.pi - b
    elif ax <= 0.5:
        b = 0.5 * math.pi - _asin_small(x)
    else:
        b = 2.0 * _asin_small(math.sqrt(0.5 * (1.0 - ax)))
        if x < 0.0:
            b = math.pi - b
    return math.copysign(b, y)


@njit(**JIT)
def _piece(du, c1, s1, c2, s2):
    """D1 = [sin], D2 = [sin cos], D3 = [sin^3] over a piece of length ``du`` from the point
    (c1, s1) to (c2, s2) on the unit circle.

    Half-width ``d < 0.1``: product form with Taylor sin d, cos d (no cancellation); longer
    pieces: plain differences (absolute error a few ulp, relative ~1e-15 of the piece).
    """
    d = 0.5 * du
    if d < 0.1:
        d2 = d * d
        sd = d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0) * (
            1.0 - d2 * (1.0 / 42.0) * (1.0 - d2 * (1.0 / 72.0)))))
        cd = 1.0 - d2 * 0.5 * (1.0 - d2 * (1.0 / 12.0) * (1.0 - d2 * (1.0 / 30.0) * (
            1.0 - d2 * (1.0 / 56.0) * (1.0 - d2 * (1.0 / 90.0)))))
        cm = c1 * cd - s1 * sd
        sm = s1 * cd + c1 * sd
        D1 = 2.0 * cm * sd
        D2 = 2.0 * (cm * cm - sm * sm) * sd * cd
    else:
        D1 = s2 - s1
        D2 = s2 * c2 - s1 * c1
    D3 = D1 * (s1 * s1 + s1 * s2 + s2 * s2)
    return D1, D2, D3


@njit(**JIT)
def _combine(A, v, P0, P1, P2, P3):
    """(int |w| w, int |w|^3) from the signed sums P_m = sum sigma D_m."""
    A2 = A * A
    v2 = v * v
    I2 = (0.5 * A2 + v2) * P0 + 0.5 * A2 * P2 - 2.0 * A * v * P1
    I3 = (A2 * A * (P1 - P3 * (1.0 / 3.0)) - 1.5 * A2 * v * (P0 + P2) + 3.0 * A * v2 * P1
          - v2 * v * P0)
    return I2, I3


@njit(**JIT)
def _first_roots(A, c, s, v, h):
    """(p, q, r+, r-): p = cos alpha = v/A, q = sin alpha, and the offsets from the floe
    centre of the first root of each family (alpha + 2 pi n, -alpha + 2 pi n) at or after
    the start u = -h (``|v| < A``)."""
    p = v / A
    q = math.sqrt((1.0 - p) * (1.0 + p))
    bp = _angle(p * c + q * s, q * c - p * s)           # alpha - theta
    bm = _angle(p * c - q * s, -q * c - p * s)          # -alpha - theta
    rp = max(bp + _TWO_PI * math.ceil((-h - bp) * (1.0 / _TWO_PI)), -h)
    rm = max(bm + _TWO_PI * math.ceil((-h - bm) * (1.0 / _TWO_PI)), -h)
    return p, q, rp, rm


@njit(**JIT)
def _integrals_merge(A, c, s, v, h, ch, sh):
    """Piecewise reference for :func:`drag_integrals` (any ``h``, ``|v| < A``, ``A > 0``):
    offsets of both root families, roots on the floe merged in order, each piece evaluated
    and summed with its sign. Slower; kept as an independent cross-check for the tests."""
    ca = c * ch + s * sh
    sa = s * ch - c * sh
    cb = c * ch - s * sh
    sb = s * ch + c * sh
    p, q, rp, rm = _first_roots(A, c, s, v, h)
    # w > 0 before a '+' root (alpha), w < 0 before a '-' root (-alpha)
    sig = 1.0 if rp < rm else -1.0
    P0 = 0.0
    P1 = 0.0
    P2 = 0.0
    P3 = 0.0
    u1 = -h
    c1 = ca
    s1 = sa
    while True:
        if rp <= rm:
            r = rp
            sr = q
        else:
            r = rm
            sr = -q
        if r > h:
            break
        if r < u1:
            r = u1
        D1, D2, D3 = _piece(r - u1, c1, s1, p, sr)
        P0 += sig * (r - u1)
        P1 += sig * D1
        P2 += sig * D2
        P3 += sig * D3
        sig = -sig
        u1 = r
        c1 = p
        s1 = sr
        if rp <= rm:
            rp += _TWO_PI
        else:
            rm += _TWO_PI
    D1, D2, D3 = _piece(h - u1, c1, s1, cb, sb)
    P0 += sig * (h - u1)
    P1 += sig * D1
    P2 += sig * D2
    P3 += sig * D3
    return _combine(A, v, P0, P1, P2, P3)


@njit(**JIT)
def _lobe(A, v, p, q, alpha, positive):
    """(int w^2, int w^3) over a whole positive lobe [-alpha, alpha] or negative lobe
    [alpha, 2 pi - alpha] (between consecutive roots)."""
    if positive:
        L0 = 2.0 * alpha
        L1 = 2.0 * q
    else:
        L0 = _TWO_PI - 2.0 * alpha
        L1 = -2.0 * q
    return _combine(A, v, L0, L1, L1 * p, L1 * q * q)


@njit(**JIT)
def _long_floe(A, c, s, v, h, ch, sh):
    """Roots on a floe of any length (used for ``h >= pi``), ``|v| < A``: returns
    ``(J2, J3, sigma_a)`` with ``I = sigma_a (W - 2 J)``, ``J`` the integrals of ``w^2``,
    ``w^3`` over the pieces of sign ``-sigma_a``: ``n_full`` whole lobes of one kind, plus
    the piece from the last root to the end if the number of roots is odd. O(1) work."""
    p, q, rp, rm = _first_roots(A, c, s, v, h)
    # numbers of roots of each family on the floe
    n_p = math.floor((h - rp) * (1.0 / _TWO_PI)) + 1.0 if rp <= h else 0.0
    n_m = math.floor((h - rm) * (1.0 / _TWO_PI)) + 1.0 if rm <= h else 0.0
    nroots = n_p + n_m
    if rp < rm:     # '+' first: w > 0 at the start, negative lobes between root pairs
        sig = 1.0
        r_last = rp + _TWO_PI * (n_p - 1.0)
        sr = q
    else:
        sig = -1.0
        r_last = rm + _TWO_PI * (n_m - 1.0)
        sr = -q
    n_full = math.floor(0.5 * nroots)
    J2 = 0.0
    J3 = 0.0
    if n_full > 0.0:
        L2, L3 = _lobe(A, v, p, q, _angle(p, q), sig < 0.0)
        J2 = n_full * L2
        J3 = n_full * L3
    if nroots - 2.0 * n_full > 0.5:
        r_last = min(r_last, h)
        D1, D2, D3 = _piece(h - r_last, p, sr, c * ch - s * sh, s * ch + c * sh)
        P2, P3 = _combine(A, v, h - r_last, D1, D2, D3)
        J2 += P2
        J3 += P3
    return J2, J3, sig


@njit(**JIT)
def drag_integrals(A, c, s, v, geom):
    """Integrals over phi in [theta - h, theta + h] of |w| w and |w|^3, w = A cos(phi) - v.

    A : velocity amplitude (A < 0 is taken as |A| with theta + pi), c, s : cos, sin theta,
    v : floe velocity, geom : :func:`exact_geometry`.
    Returns (I2, I3) [velocity^2 rad, velocity^3 rad] (``I = 0`` for ``h = 0``).

    With ``W`` the integrals of ``w^2``, ``w^3`` over the whole floe (polynomials in
    ``X = A cos theta`` with the constants of ``geom``) and ``sigma_a`` the sign at the start,
    for ``h < pi``: no root on the floe: ``sigma W``; one root at offset ``beta``:
    ``sigma_a (W - 2 J[beta, h])``; two roots: ``sigma_a (W - 2 J[lobe])`` with the lobe
    between them a whole positive (``[-alpha, alpha]``) or negative (``[alpha, 2pi - alpha]``)
    lobe, namely the one not containing the antipode ``theta + pi`` of the floe centre.
    """
    h, ch, sh, _scale, _n_x, K20, K22, K31, K33 = geom
    if A < 0.0:
        A = -A
        c = -c
        s = -s
    # whole floe: int w^2 = A^2 <cos^2> - 2 A v <cos> + v^2 2h, int w^3 likewise
    X = A * c
    A2 = A * A
    v2 = v * v
    K1X = 2.0 * sh * X
    C2 = K20 * A2 + K22 * X * X                # A^2 int cos^2
    W2 = C2 - 2.0 * v * K1X + 2.0 * h * v2
    W3 = X * (K31 * A2 + K33 * X * X) - 3.0 * v * C2 + 3.0 * v2 * K1X - 2.0 * h * v2 * v
    Q2 = (A - v) * (A + v)              # A^2 q^2: roots exist iff |v| < A
    if Q2 > 0.0:
        if h >= math.pi:
            J2, J3, sig = _long_floe(A, c, s, v, h, ch, sh)
            return sig * (W2 - 2.0 * J2), sig * (W3 - 2.0 * J3)
        Q = math.sqrt(Q2)
        # A cos(+-alpha - theta) >= A cos h: root family '+' ('-') on the floe (h < pi)
        vc = v * c
        Ach = A * ch
        inp = vc + Q * s >= Ach
        inm = vc - Q * s >= Ach
        if inp or inm:
            iA = 1.0 / A
            p = v * iA
            q = Q * iA
            if inp and inm:
                # the lobe between the roots is the one not containing the antipode
                # theta + pi; w(antipode) > 0: negative lobe between, '+' root first
                sig = 1.0 if A * c + v < 0.0 else -1.0
                # acos(p) as _angle(p, q): consistent with q near |p| = 1
                J2, J3 = _lobe(A, v, p, q, _angle(p, q), sig < 0.0)
            else:
                # one root, at offset beta: sigma_a (W - 2 J[beta, h])
                if inp:
                    sig = 1.0
                    sr = q
                    x = p * c + q * s
                    y = q * c - p * s
                else:
                    sig = -1.0
                    sr = -q
                    x = p * c - q * s
                    y = -q * c - p * s
                beta = min(max(_angle(x, y), -h), h)
                D1, D2, D3 = _piece(h - beta, p, sr, c * ch - s * sh, s * ch + c * sh)
                J2, J3 = _combine(A, v, h - beta, D1, D2, D3)
            return sig * (W2 - 2.0 * J2), sig * (W3 - 2.0 * J3)
    # one sign on the whole floe (|v| >= A, or no root on it); |v| = A, c = 1: w <= 0
    wc = X - v
    sig = 1.0 if wc > 0.0 or (wc == 0.0 and v < 0.0) else -1.0
    return sig * W2, sig * W3


@njit(**JIT)
def drag_sums_exact(A, c, s, v, geom):
    """Exact (dx -> 0) counterpart of :func:`floewave._kernels.drag_sums`: (s2, s3).

    Same arguments as ``drag_sums(A, c, s, v, cxi, sxi)`` with the cell tables replaced by
    ``geom = exact_geometry(k L_x, n_x)``. Returns, in the quadrature's units (cells times
    velocity^2 resp. ^3),
    ``s2 = n_x/(kL) int |w| w dphi``, ``s3 = n_x/(kL) int |w|^3 dphi`` over the floe,
    ``w = A cos(phi) - v``; drag force ``rho_w C_sd L_y dx s2`` as in the quadrature mode.
    ``kL = 0`` gives the limit ``n_x f(theta)``.
    """
    if geom[0] <= _H_POINT:
        w = A * c - v
        aw = abs(w)
        return geom[4] * aw * w, geom[4] * aw * w * w
    I2, I3 = drag_integrals(A, c, s, v, geom)
    # |w|^3 >= 0: clip a rounding-level negative value (only when w ~ 0 on the whole floe)
    return geom[3] * I2, geom[3] * max(I3, 0.0)


@njit(**JIT)
def drag_force_exact(A, c, s, v, geom):
    """Only ``s2`` of :func:`drag_sums_exact`."""
    return drag_sums_exact(A, c, s, v, geom)[0]


@njit(**JIT)
def drag_sums_exact_phase(A, theta, v, kL, n_x):
    """Convenience form ``(A, theta, v, kL, n_x) -> (s2, s3)`` of :func:`drag_sums_exact`
    (computes cos, sin theta and the geometry on every call; use the other in loops)."""
    return drag_sums_exact(A, math.cos(theta), math.sin(theta), v, exact_geometry(kL, n_x))


@njit(**JIT)
def general_floes(flags, idx, everyone):
    """Write the indices of the floes with ``flags[i] == 1`` (all floes if ``everyone``)
    to the front of ``idx``; return their count. After the closed-form pass of
    :func:`drag_pass_exact`, :func:`floewave._kernels.drag_pass` or
    :func:`floewave._kernels.exact_pass`, only those floes get the general evaluation."""
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


@njit(**JIT)
def drag_pass_exact(ck, sk, cwt, swt, a, u_amp, vs, geom, accumulate, sc, idx,
                    defer=False):
    """:func:`drag_sums_exact` of every floe of a chain; returns the number of floes that
    needed the general (root-finding) evaluation.

    ``defer``: only the closed-form pass, for :func:`floewave._kernels.exact_pass` to
    complete the floes with a root (``idx[:m]``): their whole-floe sums stay signed (s3 not
    clipped) and ``sc[SIG_ROW]`` gets the sign the closed form gave them (``sc`` then
    needs SIG_ROW + 1 rows).

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
            sc[SIG_ROW, i] = sig
        sc[4, i] = 1.0 if root else 0.0
    m = general_floes(sc[4, :n], idx, h <= _H_POINT)
    if defer:
        return m
    for t in range(m):
        i = idx[t]
        s2, s3 = drag_sums_exact(a[i] * u_amp, sc[0, i], sc[1, i], vs[i], geom)
        sc[2, i] = s2
        if accumulate:
            sc[3, i] = s3
    return m
