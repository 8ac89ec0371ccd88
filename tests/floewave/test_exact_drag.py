"""Closed-form ("exact") floe-bottom drag integrals (floewave._exact) against quadrature.

docs/model.md §3: the exact mode must agree with the quadrature mode as dx -> 0. Units: the exact
sums are the quadrature sums' limit in the same units, s = n_x / (kL) * int f(phi) dphi over
[theta - kL/2, theta + kL/2], f = |w| w (s2) or |w|^3 (s3), w = A cos(phi) - v.

Run ``python tests/floewave/test_exact_drag.py`` for the ns/call benchmark against ``drag_sums``.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from floewave import ModelConfig
from floewave import _kernels as K
from floewave._exact import (
    _integrals_merge,
    drag_force_exact,
    drag_integrals,
    drag_sums_exact,
    drag_sums_exact_phase,
    exact_geometry,
)
from floewave.forces import cell_offsets

try:
    import mpmath as mp
except ImportError:     # pragma: no cover
    mp = None


# ---------------------------------------------------------------- references ----------------

def fine_midpoint(A, theta, v, kL, n_x, n=200_000):
    """Midpoint quadrature with n cells, scaled to the n_x-cell units: (n_x/n) sum f."""
    phi = theta + kL * ((np.arange(n) + 0.5) / n - 0.5)
    w = A * np.cos(phi) - v
    aw = np.abs(w)
    return n_x / n * float(np.sum(aw * w)), n_x / n * float(np.sum(aw * w * w))


def mp_reference(A, theta, v, kL, n_x, dps=30):
    """mpmath quadrature split at the roots of A cos(phi) = v."""
    with mp.workdps(dps):
        A_, th, v_, kL_ = mp.mpf(A), mp.mpf(theta), mp.mpf(v), mp.mpf(kL)
        a, b = th - kL_ / 2, th + kL_ / 2
        pts = [a, b]
        if A_ > 0 and abs(v_) < A_:
            al = mp.acos(v_ / A_)
            n0 = int(mp.floor(a / (2 * mp.pi))) - 1
            n1 = int(mp.ceil(b / (2 * mp.pi))) + 1
            for n in range(n0, n1 + 1):
                for r in (al + 2 * mp.pi * n, -al + 2 * mp.pi * n):
                    if a < r < b:
                        pts.append(r)
        pts.sort()

        def w(x):
            return A_ * mp.cos(x) - v_

        I2 = mp.quad(lambda x: abs(w(x)) * w(x), pts)
        I3 = mp.quad(lambda x: abs(w(x)) ** 3, pts)
        return float(I2 * n_x / kL_), float(I3 * n_x / kL_)


def scales(A, v, n_x):
    """Natural size of s2, s3: n_x (A + |v|)^2, n_x (A + |v|)^3."""
    u = A + abs(v)
    return n_x * u * u, n_x * u ** 3


def random_cases(seed, n):
    """(A, theta, v, kL) covering |v| < A, |v| > A, v = 0, A = 0, |v| = A, roots at the
    floe ends, tiny and long floes (kL up to ~4 periods)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        A = rng.uniform(0.0, 1.5)
        theta = rng.uniform(-60.0, 60.0)
        v = A * rng.uniform(-1.0, 1.0)
        kL = rng.uniform(0.05, 9.0)
        kind = i % 10
        if kind == 1:
            v = 0.0
        elif kind == 2:
            A = 0.0
            v = rng.uniform(-1.0, 1.0)
        elif kind == 3:
            v = A * rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 3.0)       # |v| > A
        elif kind == 4:
            v = A * rng.choice([-1.0, 1.0]) * (1.0 - 10.0 ** rng.uniform(-15, -3))
        elif kind == 5 and A > 0:                                          # root at an end
            al = math.acos(v / A)
            theta = rng.choice([-1.0, 1.0]) * al + rng.choice([-1.0, 1.0]) * 0.5 * kL
        elif kind == 6:
            kL = 10.0 ** rng.uniform(-7, -1)
        elif kind == 7:
            kL = rng.uniform(2 * math.pi, 25.0)
        elif kind == 8:
            v = A * rng.choice([-1.0, 1.0])                                # |v| = A
        out.append((float(A), float(theta), float(v), float(kL)))
    return out


# ---------------------------------------------------------------- dx -> 0 limit -------------

@pytest.mark.parametrize("case", random_cases(1, 120))
def test_exact_equals_fine_quadrature_limit(case):
    """Drag force and dissipation sums equal the dx -> 0 quadrature limit to 1e-6."""
    A, theta, v, kL = case
    n_x = 50.0
    s2, s3 = drag_sums_exact_phase(A, theta, v, kL, n_x)
    r2, r3 = fine_midpoint(A, theta, v, kL, n_x)
    sc2, sc3 = scales(A, v, n_x)
    assert abs(s2 - r2) <= 1e-6 * max(abs(r2), 1e-3 * sc2), (s2, r2)
    assert abs(s3 - r3) <= 1e-6 * max(abs(r3), 1e-3 * sc3), (s3, r3)


@pytest.mark.skipif(mp is None, reason="mpmath not installed")
@pytest.mark.parametrize("case", random_cases(2, 60))
def test_exact_to_rounding_against_mpmath(case):
    """Closed form accurate to ~1e-14 of the scale n_x (A + |v|)^m (claim: few ulp)."""
    A, theta, v, kL = case
    n_x = 50.0
    s2, s3 = drag_sums_exact_phase(A, theta, v, kL, n_x)
    r2, r3 = mp_reference(A, theta, v, kL, n_x)
    sc2, sc3 = scales(A, v, n_x)
    assert abs(s2 - r2) <= 1e-14 * sc2 + 1e-300
    assert abs(s3 - r3) <= 1e-14 * sc3 + 1e-300


@pytest.mark.parametrize("case", [c for c in random_cases(3, 200) if abs(c[2]) < c[0]])
def test_fast_paths_equal_piecewise_reference(case):
    """Lobe/one-root/long-floe shortcuts equal the plain piece-by-piece sum."""
    A, theta, v, kL = case
    c, s = math.cos(theta), math.sin(theta)
    geom = exact_geometry(kL, 1.0)
    h, ch, sh = geom[0], geom[1], geom[2]
    I2, I3 = drag_integrals(A, c, s, v, geom)
    R2, R3 = _integrals_merge(A, c, s, v, h, ch, sh)
    sc2, sc3 = scales(A, v, kL)
    assert abs(I2 - R2) <= 1e-14 * sc2
    assert abs(I3 - R3) <= 1e-14 * sc3


# ---------------------------------------------------------------- vs the project quadrature -

def _f_second_derivative_bounds(A, v):
    """sup |f''| for f = |w| w and |w|^3, w = A cos(phi) - v (|w'|, |w''| <= A)."""
    u = A + abs(v)
    return 2.0 * (A * A + A * u), 3.0 * (2.0 * u * A * A + u * u * A)


def test_quadrature_converges_second_order_to_exact():
    """Without roots on the floe (smooth integrand) the n-cell midpoint sums converge to the
    exact value at second order in 1/n (relative error ratio 4 per doubling)."""
    A, theta, v, kL = 0.3, 0.7, 0.45, 1.5          # |v| > A: no roots
    errs2, errs3 = [], []
    for n in (10, 20, 40, 80, 160, 320):
        e2, e3 = drag_sums_exact_phase(A, theta, v, kL, float(n))
        q2, q3 = fine_midpoint(A, theta, v, kL, float(n), n=n)
        errs2.append(abs(q2 - e2) / abs(e2))
        errs3.append(abs(q3 - e3) / abs(e3))
    for errs in (errs2, errs3):
        orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
        assert np.all(np.abs(orders - 2.0) < 0.02), orders
        assert errs[-1] < 1e-5


def _project_tables(L_x, dx, k):
    cfg = ModelConfig(L_x=L_x, dx=dx)
    xi = cell_offsets(cfg)
    return cfg.n_x, np.cos(k * xi), np.sin(k * xi)


def test_exact_matches_project_drag_sums_within_midpoint_error():
    """floewave._kernels.drag_sums (L = 0.5 m, dx = 0.01 m, n_x = 50, k = 3 m^-1) differs
    from the exact sums by at most the midpoint-rule bound n_x (k dx)^2 / 24 sup|f''|
    (f = |w| w is C^1 with Lipschitz f', f = |w|^3 is C^2), and without roots on the floe
    by the Euler-Maclaurin leading term (k dx / 24) [f'(b) - f'(a)] to O(dx^3)."""
    L_x, dx, k = 0.5, 0.01, 3.0
    n_x, cxi, sxi = _project_tables(L_x, dx, k)
    assert n_x == 50
    geom = exact_geometry(k * L_x, float(n_x))
    delta = k * dx
    rng = np.random.default_rng(11)
    n_smooth = 0
    worst = 0.0
    for _ in range(3000):
        A = rng.uniform(0.0, 0.5)
        theta = rng.uniform(-math.pi, math.pi)
        v = rng.uniform(-0.7, 0.7)
        c, s = math.cos(theta), math.sin(theta)
        q2, q3 = K.drag_sums(A, c, s, v, cxi, sxi)
        e2, e3 = drag_sums_exact(A, c, s, v, geom)
        b2, b3 = _f_second_derivative_bounds(A, v)
        tol2 = n_x * delta ** 2 / 24.0 * b2 * (1 + 1e-9) + 1e-13
        tol3 = n_x * delta ** 2 / 24.0 * b3 * (1 + 1e-9) + 1e-13
        assert abs(e2 - q2) <= tol2
        assert abs(e3 - q3) <= tol3
        worst = max(worst, abs(e2 - q2) / tol2, abs(e3 - q3) / tol3)
        # no root on the floe: the leading Euler-Maclaurin term predicts the difference
        wa = A * math.cos(theta - 0.5 * k * L_x) - v
        wb = A * math.cos(theta + 0.5 * k * L_x) - v
        if np.all(A * np.cos(theta + np.linspace(-0.75, 0.75, 301)) - v > 1e-3) or \
                np.all(A * np.cos(theta + np.linspace(-0.75, 0.75, 301)) - v < -1e-3):
            n_smooth += 1
            dwa = -A * math.sin(theta - 0.5 * k * L_x)
            dwb = -A * math.sin(theta + 0.5 * k * L_x)
            lead2 = delta / 24.0 * (2 * abs(wb) * dwb - 2 * abs(wa) * dwa)
            lead3 = delta / 24.0 * (3 * abs(wb) * wb * dwb - 3 * abs(wa) * wa * dwa)
            sc2, sc3 = scales(A, v, n_x)
            assert abs((e2 - q2) - lead2) <= 1e-5 * sc2 * delta ** 2 + 1e-13
            assert abs((e3 - q3) - lead3) <= 1e-5 * sc3 * delta ** 2 + 1e-13
    assert n_smooth > 300
    assert worst > 0.05         # the bound is not vacuous: the error is O(dx^2), not 0


def test_exact_mode_agrees_with_quadrature_as_dx_to_zero_project_grid():
    """drag_sums on ever finer project grids (dx = 0.01 / 2^m) converges to exact."""
    L_x, k = 0.5, 3.0
    A, theta, v = 0.25, 0.4, 0.1        # roots on the floe
    c, s = math.cos(theta), math.sin(theta)
    prev = None
    for m in range(6):
        dx = 0.01 / 2 ** m
        n_x, cxi, sxi = _project_tables(L_x, dx, k)
        q2, q3 = K.drag_sums(A, c, s, v, cxi, sxi)
        e2, e3 = drag_sums_exact(A, c, s, v, exact_geometry(k * L_x, float(n_x)))
        err = max(abs(q2 / e2 - 1.0), abs(q3 / e3 - 1.0))
        if prev is not None:
            assert err < prev / 3.0
        prev = err
    assert prev < 1e-6


# ---------------------------------------------------------------- symmetries and limits -----

SYM_CASES = random_cases(4, 80)


@pytest.mark.parametrize("case", SYM_CASES)
def test_symmetries(case):
    """w -> -w (theta + pi, v -> -v): s2 -> -s2, s3 -> s3; A -> -A is theta + pi;
    reflection theta -> -theta leaves both unchanged (symmetric interval)."""
    A, theta, v, kL = case
    n_x = 50.0
    geom = exact_geometry(kL, n_x)
    c, s = math.cos(theta), math.sin(theta)
    s2, s3 = drag_sums_exact(A, c, s, v, geom)
    m2, m3 = drag_sums_exact(A, -c, -s, -v, geom)
    n2, n3 = drag_sums_exact(-A, c, s, -v, geom)
    r2, r3 = drag_sums_exact(A, c, -s, v, geom)
    sc2, sc3 = scales(A, v, n_x)
    tol2, tol3 = 1e-14 * sc2 + 1e-300, 1e-14 * sc3 + 1e-300
    assert abs(m2 + s2) <= tol2 and abs(m3 - s3) <= tol3
    assert abs(n2 + s2) <= tol2 and abs(n3 - s3) <= tol3
    assert abs(r2 - s2) <= tol2 and abs(r3 - s3) <= tol3
    assert s3 >= 0.0
    assert drag_force_exact(A, c, s, v, geom) == s2


@pytest.mark.parametrize("case", SYM_CASES)
def test_additivity_over_floe_halves(case):
    """The integral over a floe is the sum over its two halves (n_x/2 cells each)."""
    A, theta, v, kL = case
    n_x = 50.0
    s2, s3 = drag_sums_exact_phase(A, theta, v, kL, n_x)
    a2, a3 = drag_sums_exact_phase(A, theta - 0.25 * kL, v, 0.5 * kL, 0.5 * n_x)
    b2, b3 = drag_sums_exact_phase(A, theta + 0.25 * kL, v, 0.5 * kL, 0.5 * n_x)
    sc2, sc3 = scales(A, v, n_x)
    assert abs(a2 + b2 - s2) <= 1e-13 * sc2 + 1e-300
    assert abs(a3 + b3 - s3) <= 1e-13 * sc3 + 1e-300


def test_closed_values_and_limits():
    n_x = 50.0
    A = 0.7
    # a full period, v = 0: int |cos|cos = 0, int |cos|^3 = 8/3, whatever theta
    for theta in (0.0, 0.3, 2.0, -5.0):
        s2, s3 = drag_sums_exact_phase(A, theta, 0.0, 2 * math.pi, n_x)
        assert abs(s2) < 1e-14 * n_x * A * A
        assert abs(s3 - n_x / (2 * math.pi) * 8.0 / 3.0 * A ** 3) < 1e-14 * n_x * A ** 3
    # whole periods: independent of theta for any v
    ref = drag_sums_exact_phase(A, 0.1, 0.3, 4 * math.pi, n_x)
    for theta in (1.0, 2.5, -3.0):
        got = drag_sums_exact_phase(A, theta, 0.3, 4 * math.pi, n_x)
        assert abs(got[0] - ref[0]) < 1e-13 * n_x and abs(got[1] - ref[1]) < 1e-13 * n_x
    # A = 0: constant relative velocity
    s2, s3 = drag_sums_exact_phase(0.0, 1.0, 0.4, 1.5, n_x)
    assert abs(s2 + n_x * 0.16) < 1e-14 and abs(s3 - n_x * 0.064) < 1e-14
    assert drag_sums_exact_phase(0.0, 1.0, 0.0, 1.5, n_x) == (0.0, 0.0)
    # |v| >= A: constant sign
    s2, s3 = drag_sums_exact_phase(A, 0.0, A, 1.5, n_x)        # double root at the centre
    assert s2 < 0.0 < s3
    r2, r3 = fine_midpoint(A, 0.0, A, 1.5, n_x)
    assert abs(s2 - r2) < 1e-8 * n_x * A * A and abs(s3 - r3) < 1e-8 * n_x * A ** 3
    assert drag_sums_exact_phase(A, 0.3, -2 * A, 1.5, n_x)[0] > 0.0
    # tiny floe: n_x f(theta); kL = 0 exactly: the point limit itself
    for kL in (1e-9, 1e-30, 0.0):
        theta, v = 0.8, 0.2
        w = A * math.cos(theta) - v
        s2, s3 = drag_sums_exact_phase(A, theta, v, kL, n_x)
        assert s2 == pytest.approx(n_x * abs(w) * w, rel=1e-12)
        assert s3 == pytest.approx(n_x * abs(w) ** 3, rel=1e-12)
    # tiny floe with a root on it: |w| <~ A kL there; values at rounding level of the scale
    al = math.acos(0.2 / A)
    s2, s3 = drag_sums_exact_phase(A, al + 1e-9, 0.2, 1e-8, n_x)
    sc2, sc3 = scales(A, 0.2, n_x)
    assert abs(s2) < 1e-15 * sc2 and 0.0 <= s3 < 1e-15 * sc3


@pytest.mark.skipif(mp is None, reason="mpmath not installed")
def test_geometry_constants():
    """exact_geometry's whole-floe moments of cos^2, cos^3 (also small h, no cancellation)."""
    for kL in (1e-6, 1e-3, 0.3, 1.5, 2.0, 9.0):
        h, ch, sh, scale, n_x, K20, K22, K31, K33 = exact_geometry(kL, 50.0)
        assert scale == pytest.approx(50.0 / kL, rel=1e-15) and n_x == 50.0
        for theta in (0.0, 0.4, 2.2):
            c = math.cos(theta)
            with mp.workdps(40):
                lo, hi = mp.mpf(theta) - mp.mpf(h), mp.mpf(theta) + mp.mpf(h)
                m2 = mp.quad(lambda x: mp.cos(x) ** 2, [lo, hi])
                m3 = mp.quad(lambda x: mp.cos(x) ** 3, [lo, hi])
            assert abs(K20 + K22 * c * c - float(m2)) <= 1e-15 * kL
            assert abs(K31 * c + K33 * c ** 3 - float(m3)) <= 1e-15 * kL


# ---------------------------------------------------------------- property test -------------

try:
    from hypothesis import given, settings
    from hypothesis import strategies as st
except ImportError:     # pragma: no cover
    given = None

if given is not None:
    @settings(max_examples=300, deadline=None)
    @given(A=st.one_of(st.just(0.0), st.floats(1e-3, 2.0)), theta=st.floats(-200.0, 200.0),
           ratio=st.one_of(st.sampled_from([0.0, 1.0, -1.0]),
                           st.floats(-2.5, 2.5).filter(lambda r: abs(r) > 1e-12)),
           kL=st.one_of(st.just(0.0), st.floats(1e-12, 14.0)),
           n_x=st.integers(1, 400))
    def test_property_exact_vs_quadrature_bound_and_additivity(A, theta, ratio, kL, n_x):
        """For any state (physical magnitudes, no underflow): |exact - 4096-cell midpoint|
        within the midpoint bound, the halves add up, s3 >= 0, and sign(s2) = -sign(v)
        when |v| > A."""
        v = ratio * A if A > 0 else ratio
        n_x = float(n_x)
        s2, s3 = drag_sums_exact_phase(A, theta, v, kL, n_x)
        sc2, sc3 = scales(A, v, n_x)
        n = 4096
        q2, q3 = fine_midpoint(A, theta, v, kL, n_x, n=n)
        b2, b3 = _f_second_derivative_bounds(A, v)
        d = kL / n
        assert abs(s2 - q2) <= n_x * d * d / 24.0 * b2 * (1 + 1e-6) + 1e-12 * sc2 + 1e-300
        assert abs(s3 - q3) <= n_x * d * d / 24.0 * b3 * (1 + 1e-6) + 1e-12 * sc3 + 1e-300
        a2, a3 = drag_sums_exact_phase(A, theta - 0.25 * kL, v, 0.5 * kL, 0.5 * n_x)
        c2, c3 = drag_sums_exact_phase(A, theta + 0.25 * kL, v, 0.5 * kL, 0.5 * n_x)
        assert abs(a2 + c2 - s2) <= 1e-12 * sc2 + 1e-300
        assert abs(a3 + c3 - s3) <= 1e-12 * sc3 + 1e-300
        assert s3 >= 0.0
        if abs(v) > A:
            assert s2 * v < 0.0


# ---------------------------------------------------------------- benchmark (manual) --------

def bench(N=10_000_000, L_x=0.5, dx=0.01, k=3.0):   # pragma: no cover
    """ns per call of drag_sums_exact vs drag_sums (n_x = L_x/dx cells), kernel-like inputs:
    the phase jumps by ~1.6 rad between calls (neighbouring floes), v varies slowly."""
    import time

    from numba import njit

    n_x, cxi, sxi = _project_tables(L_x, dx, k)
    geom = exact_geometry(k * L_x, float(n_x))

    @njit(fastmath=True)
    def run(n, A, vamp, exact):
        c, s, cv, sv = 1.0, 0.0, 1.0, 0.0
        ce, se = math.cos(1.6180339887), math.sin(1.6180339887)
        cp, sp = math.cos(0.0123), math.sin(0.0123)
        acc = 0.0
        for _ in range(n):
            c, s = c * ce - s * se, s * ce + c * se
            cv, sv = cv * cp - sv * sp, sv * cp + cv * sp
            if exact:
                s2, s3 = drag_sums_exact(A, c, s, vamp * sv, geom)
            else:
                s2, s3 = K.drag_sums(A, c, s, vamp * sv, cxi, sxi)
            acc += s2 + s3
        return acc

    print(f"L_x={L_x} dx={dx} k={k} n_x={n_x} kL={k * L_x:.2f}: ns/call (best of 3, {N:.0e})")
    for A, vamp, label in [(0.3, 0.2, "|v| < A (roots often on the floe)"),
                           (0.3, 0.0, "v = 0"), (0.3, 0.6, "|v| up to 2A"),
                           (0.0, 0.2, "A = 0")]:
        res = {}
        for exact in (True, False):
            run(10, A, vamp, exact)
            best = min(_timed(run, N, A, vamp, exact, time) for _ in range(3))
            res[exact] = best / N * 1e9
        print(f"  {label:36s} exact {res[True]:6.2f}   quadrature {res[False]:6.2f}")


def _timed(run, N, A, vamp, exact, time):   # pragma: no cover
    t = time.perf_counter()
    run(N, A, vamp, exact)
    return time.perf_counter() - t


if __name__ == "__main__":   # pragma: no cover
    bench()
    bench(L_x=1.5)
    bench(L_x=3.0)
