"""The numba kernel against the independent vectorised-numpy twin of the same time step."""
import numpy as np
import pytest

from floewave import ModelConfig, solve_dispersion
from floewave import _reference as ref
from floewave.model import FloeChain


@pytest.mark.parametrize("opts", [
    dict(),
    dict(contact="linear", damping="exact"),
    dict(clip_attraction=True, integrator="half_step", eps=0.2),
    dict(dispersion="ep", L_x=1.5, d_f=0.0),
    dict(drag_every=1),
    dict(drag_every=4, L_x=3.0, integrator="half_step", drag_hold="midpoint"),
    dict(drag_every=4, L_x=3.0, integrator="half_step", drag_hold="linear"),
    dict(drag_every=8, drag_hold="linear"),
    dict(drag_every=8, drag_hold="midpoint"),
])
def test_numba_kernel_equals_numpy_twin(opts):
    """(The default holds the drag over drag_every = 4 steps; the twin holds it alike, from
    the drag the kernel holds when the twin takes over: for ``drag_hold = "linear"`` the
    last evaluation, its slope and its step.)"""
    # the paper's dt: 5000 steps of 1e-4 s stay short of chaos amplifying rounding (and
    # resolve the linear law's contacts)
    cfg = ModelConfig(**{"dt": 1e-4, **opts})
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = cfg.a0 * np.linspace(1.0, 0.6, cfg.n_floes)
    chain.run(a, 3000)                   # develop contacts first
    x, u, acc = chain.x.copy(), chain.u.copy(), chain.acc.copy()
    istep = chain.istep
    held = chain.P.c_drag * chain._held_drag().copy()
    _, d0, ds, di = (h.copy() for h in chain._held_rows()[:4])
    if cfg.drag_every > 1 and cfg.drag_hold == "linear":   # the last evaluation, its slope
        held, slope, i_last = chain.P.c_drag * d0, chain.P.c_drag * ds, int(di[0])
        assert np.all(di == i_last) and i_last <= istep
    else:
        slope = i_last = None
    chain.run(a, 2000)
    ref.advance(x, u, acc, a, chain.x0, istep, 2000, chain.P, chain.opts, chain.cxi, chain.sxi,
                held=held, slope=slope, i_last=i_last)
    assert np.any(np.diff(x) - cfg.L_x < 0), "no contact exercised"
    np.testing.assert_allclose(chain.x, x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(chain.u, u, rtol=0, atol=1e-10)


def _random_floes(rng, n, A0):
    """Phases and velocities covering one-sign floes, roots on the floe, |v| = |A|, A < 0."""
    th = rng.uniform(-np.pi, np.pi, n)
    a = np.full(n, A0)
    a[::7] *= -1.0                                  # A < 0 taken as |A| with theta + pi
    v = A0 * rng.uniform(-1.6, 1.6, n)
    v[::5] = A0 * np.sign(rng.uniform(-1, 1, n // 5 + 1))[: v[::5].shape[0]]   # |v| = A
    v[3::11] = 0.0
    return th, a, v


@pytest.mark.parametrize("L_x,T", [(0.5, 1.2), (1.5, 1.2), (3.0, 1.2), (3.0, 1.1),
                                   (3.0, 2.0), (1.5, 1.1)])
@pytest.mark.parametrize("accumulate", [False, True])
def test_two_pass_drag_equals_per_floe_sums(L_x, T, accumulate):
    """drag_pass (closed form for one-sign floes, prefix sums over the roots for the rest),
    exact_pass (the same for the exact integrals) and drag_pass_exact (one-sign case,
    root-finding for the rest) equal the per-floe cell loop drag_sums / the exact
    drag_sums_exact to 1e-13 of the floe's scale n_x (|A| + |v|)^m,
    with floes of up to kL = 10 rad (four roots of w on a floe), and both passes are
    exercised."""
    from floewave import _kernels as K
    from floewave._exact import drag_sums_exact
    from floewave._exact_pass import drag_pass_exact
    cfg = ModelConfig(L_x=L_x, T=T)
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    P = chain.P
    mom = K.drag_tables(chain.cxi, chain.sxi, P)
    assert mom[K.M_FAST] == 1.0
    rng = np.random.default_rng(3)
    n = 400
    th, a, v = _random_floes(rng, n, 1.0)
    ck, sk = np.cos(th + 0.3), np.sin(th + 0.3)     # theta = (th + 0.3) - 0.3
    cwt, swt = np.cos(0.3), np.sin(0.3)
    P1 = P._replace(u_amp=0.05)
    emom = K.exact_tables(P.geom)
    for exact in (False, True, "kernel"):
        sc = K.new_scratch(n)
        idx = np.zeros(n, np.int64)
        if exact == "kernel":       # the kernel's exact path: prefix sums over the roots
            m = K.exact_pass(ck, sk, cwt, swt, a, v * 0.05, P1, emom, accumulate, sc, idx)
        elif exact:
            m = drag_pass_exact(ck, sk, cwt, swt, a, P1.u_amp, v * 0.05, P.geom, accumulate,
                                sc, idx)
        else:
            m = K.drag_pass(ck, sk, cwt, swt, a, v * 0.05, P1, chain.cxi, chain.sxi, mom,
                            accumulate, sc, idx)
        assert 0 < m < n
        for i in range(n):
            c = ck[i] * cwt + sk[i] * swt
            s = sk[i] * cwt - ck[i] * swt
            A = a[i] * 0.05
            vi = v[i] * 0.05
            if exact:
                q2, q3 = drag_sums_exact(A, c, s, vi, P.geom)
            else:
                q2, q3 = K.drag_sums(A, c, s, vi, chain.cxi, chain.sxi)
            scale = cfg.n_x * (abs(A) + abs(vi)) ** 2
            assert abs(sc[2, i] - q2) <= 1e-13 * scale, (exact, i)
            if accumulate:
                assert abs(sc[3, i] - q3) <= 1e-13 * scale * (abs(A) + abs(vi)), (exact, i)


def test_two_pass_drag_falls_back_on_foreign_tables():
    """Tables that are not FloeChain's symmetric cell tables: no closed form (M_FAST = 0),
    every floe by the cell loop."""
    from floewave import _kernels as K
    cfg = ModelConfig()
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    cxi = chain.cxi.copy()
    cxi[0] += 1e-6
    mom = K.drag_tables(cxi, chain.sxi, chain.P)
    assert mom[K.M_FAST] == 0.0
    n = 20
    sc = K.new_scratch(n)
    idx = np.zeros(n, np.int64)
    m = K.drag_pass(np.ones(n), np.zeros(n), 1.0, 0.0, np.full(n, 0.01), np.full(n, 5.0),
                    chain.P, cxi, chain.sxi, mom, True, sc, idx)
    assert m == n
    q2, q3 = K.drag_sums(0.01 * chain.P.u_amp, 1.0, 0.0, 5.0, cxi, chain.sxi)
    assert sc[2, 0] == q2 and sc[3, 0] == q3


@pytest.mark.parametrize("exact", [False, True])
@pytest.mark.parametrize("accumulate", [False, True])
def test_prefix_sums_of_every_floe_equal_the_indexed_path_bit_for_bit(exact, accumulate):
    """When every floe has a root (m = n, the common case of 1.5 m and 3 m floes)
    prefix_sums copies the floes without the index; with one floe more that has none (so
    idx is not the identity) the same floes take the indexed gather: the same bits, and
    the per-floe sums to 1e-13 of the floe's scale."""
    from floewave import _kernels as K
    from floewave._exact import drag_sums_exact
    cfg = ModelConfig(L_x=3.0, T=1.2)              # kL = 8.4 > 2 pi: |v| < |A| has roots
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    P = chain.P._replace(u_amp=1.0)
    mom = K.exact_tables(P.geom) if exact else K.drag_tables(chain.cxi, chain.sxi, P)
    rng = np.random.default_rng(11)
    n = 37
    th = rng.uniform(-np.pi, np.pi, n + 1)
    a = rng.uniform(0.5, 1.0, n + 1)
    v = a * rng.uniform(-0.95, 0.95, n + 1)
    v[0] = 5.0                                    # floe 0: no root (|v| > A)
    out = []
    for lo in (1, 0):                              # floes 1..n alone, then all n + 1
        ck, sk = np.cos(th[lo:]), np.sin(th[lo:])
        nn = n + 1 - lo
        sc = K.new_scratch(nn)
        idx = np.zeros(nn, np.int64)
        if exact:
            m = K.exact_pass(ck, sk, 1.0, 0.0, a[lo:], v[lo:], P, mom, accumulate, sc, idx)
        else:
            m = K.drag_pass(ck, sk, 1.0, 0.0, a[lo:], v[lo:], P, chain.cxi, chain.sxi, mom,
                            accumulate, sc, idx)
        assert m == n
        assert (idx[m - 1] == m - 1) == (lo == 1)   # dense the first time, indexed next
        out.append(sc[2:4, -n - K.LANES:-K.LANES].copy())
    assert out[0][0].tobytes() == out[1][0].tobytes()
    if accumulate:
        assert out[0][1].tobytes() == out[1][1].tobytes()
    for i in range(1, n + 1):
        if exact:
            q2, q3 = drag_sums_exact(a[i], np.cos(th[i]), np.sin(th[i]), v[i], P.geom)
        else:
            q2, q3 = K.drag_sums(a[i], np.cos(th[i]), np.sin(th[i]), v[i], chain.cxi,
                                 chain.sxi)
        scale = cfg.n_x * (a[i] + abs(v[i])) ** 2
        assert abs(out[1][0, i - 1] - q2) <= 1e-13 * scale
        if accumulate:
            assert abs(out[1][1, i - 1] - q3) <= 1e-13 * scale * (a[i] + abs(v[i]))


@pytest.mark.parametrize("L_x", [0.5, 3.0])
@pytest.mark.parametrize("m", [1, 13, 17, 40])
def test_cell_sums_are_per_floe_sums_bit_for_bit(L_x, m):
    """cell_sums (vectorised across floes, lanes padded) gives exactly drag_sums /
    floe by floe: the summation order over the cells is the source's."""
    from floewave import _kernels as K
    cfg = ModelConfig(L_x=L_x)
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    rng = np.random.default_rng(m)
    n = 40
    th, a, v = _random_floes(rng, n, 1.0)
    idx = rng.permutation(n)[:m].astype(np.int64)
    for accumulate in (False, True):
        sc = K.new_scratch(n)
        sc[K.SC_C, :n] = np.cos(th)
        sc[K.SC_S, :n] = np.sin(th)
        sc[K.SC_GATHER:] = np.nan          # padding lanes must not leak into results
        K.cell_sums(sc, np.concatenate([idx, np.zeros(n - m, np.int64)]), m, a, 0.05,
                    v * 0.05, chain.cxi, chain.sxi, accumulate)
        for i in idx:
            A = a[i] * 0.05
            q2, q3 = K.drag_sums(A, sc[K.SC_C, i], sc[K.SC_S, i], v[i] * 0.05,
                                 chain.cxi, chain.sxi)
            if accumulate:
                assert sc[K.SC_S3, i] == q3
            assert sc[K.SC_S2, i] == q2


def test_scratch_too_small_is_refused():
    """The padded scratch is checked, not silently overrun."""
    from floewave import _kernels as K
    cfg = ModelConfig()
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = np.full(cfg.n_floes, cfg.a0)
    chain.work = np.zeros((K.N_WORK, cfg.n_floes))          # no padding lanes
    with pytest.raises(ValueError, match="scratch too small"):
        chain.run(a, 10)


def test_inline_angle_is_atan2_on_the_unit_circle():
    """The vectorisable atan2 of the prefix-sum drag: within 4e-16 rad of math.atan2 on
    200,001 points of the unit circle, including the axes and the reduction boundaries
    (2 ulp of pi)."""
    from floewave._prefix import angle_unit
    phi = np.concatenate([np.linspace(-np.pi, np.pi, 200_001),
                          np.array([0.0, np.pi / 2, -np.pi / 2, np.pi / 4, 3 * np.pi / 4])])
    worst = 0.0
    for f in phi:
        x, y = np.cos(f), np.sin(f)
        worst = max(worst, abs(angle_unit(x, y) - np.arctan2(y, x)))
    assert worst <= 8.9e-16


@pytest.mark.parametrize("opts", [
    dict(),
    dict(drag_integration="exact", contact="linear", damping="exact"),
    dict(L_x=3.0, T=1.1, clip_attraction=True, integrator="half_step"),
])
def test_replica_r_is_the_same_whatever_r_runs_with(opts):
    """The ensemble kernel advances R chains in one loop; each replica's state is, bit for
    bit, that of the same chain run alone (nothing couples replicas), through spin-up and
    averaging steps and a change of amplitudes."""
    from floewave import _kernels as K
    from floewave.ensemble import initial_positions
    cfg = ModelConfig(replicas=3, **opts)
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg))
    a = cfg.a0 * np.linspace(1.0, 0.5, cfg.n_floes)
    a3 = np.stack([a, 0.9 * a, 1.1 * a])
    ens = FloeChain(cfg, k, x0)
    st = np.zeros((K.N_STATS, 3, cfg.n_floes))
    ens.run(a3, 1500)
    ens.run(a3, 700, st)
    ens.run(0.95 * a3, 300)
    for r in range(3):
        one = FloeChain(cfg, k, x0[r])
        s1 = np.zeros((K.N_STATS, cfg.n_floes))
        one.run(a3[r], 1500)
        one.run(a3[r], 700, s1)
        one.run(0.95 * a3[r], 300)
        assert np.array_equal(one.x, ens.x[r]) and np.array_equal(one.u, ens.u[r])
        assert np.array_equal(s1, st[:, r, :])
    assert np.any(np.diff(ens.x, axis=1) - cfg.L_x < 0), "no contact exercised"
    assert not np.array_equal(ens.x[0], ens.x[1])


def test_prefix_sums_at_the_root_count_boundary():
    """A floe whose cell span 2h lies a few ulp below a multiple of 2 pi, with a root at its
    end (the review's case: the root count and the enumeration once disagreed there by one
    root, an error of 2 F(n)): equal to the cell loop, over 40 lengths around the boundary."""
    from floewave import _kernels as K
    k, n_x, A, v, th = 1.0, 200, 1.1254979767515874, 0.38230289469490575, 1.9173670619666847
    L0 = 6.314759102693051
    for ulps in range(-20, 20):
        L = L0 + ulps * np.spacing(L0)
        xi = (np.arange(n_x) + 0.5) * (L / n_x) - L / 2.0
        cxi, sxi = np.cos(k * xi), np.sin(k * xi)
        P = ModelConfig(L_x=1.5)
        P = FloeChain(P, 1.0).P._replace(k=k, L_x=L, u_amp=1.0)
        mom = K.drag_tables(cxi, sxi, P)
        assert mom[K.M_FAST] == 1.0
        sc = K.new_scratch(1)
        idx = np.zeros(1, np.int64)
        K.drag_pass(np.array([np.cos(th)]), np.array([np.sin(th)]), 1.0, 0.0, np.array([A]),
                    np.array([v]), P, cxi, sxi, mom, True, sc, idx)
        q2, q3 = K.drag_sums(A, np.cos(th), np.sin(th), v, cxi, sxi)
        scale = n_x * (A + v) ** 2
        assert abs(sc[K.SC_S2, 0] - q2) <= 1e-12 * scale, ulps
        assert abs(sc[K.SC_S3, 0] - q3) <= 1e-12 * scale * (A + v), ulps
