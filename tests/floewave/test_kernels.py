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
])
def test_numba_kernel_equals_numpy_twin(opts):
    cfg = ModelConfig(**opts)
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = cfg.a0 * np.linspace(1.0, 0.6, cfg.n_floes)
    chain.run(a, 3000)                   # develop contacts first
    x, u, acc = chain.x.copy(), chain.u.copy(), chain.acc.copy()
    istep = chain.istep
    chain.run(a, 2000)
    ref.advance(x, u, acc, a, chain.x0, istep, 2000, chain.P, chain.cxi, chain.sxi)
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


@pytest.mark.parametrize("L_x", [0.5, 1.5, 3.0])
@pytest.mark.parametrize("accumulate", [False, True])
def test_two_pass_drag_equals_per_floe_sums(L_x, accumulate):
    """drag_pass (closed form for one-sign floes, cell loop for the rest) and
    drag_pass_exact (one-sign case, general evaluation for the rest) equal the per-floe
    drag_sums / drag_sums_exact to rounding, and the closed forms are exercised."""
    from floewave import _kernels as K
    from floewave._exact import drag_pass_exact, drag_sums_exact
    cfg = ModelConfig(L_x=L_x)
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
    for exact in (False, True):
        sc = K.new_scratch(n)
        idx = np.zeros(n, np.int64)
        if exact:
            m = drag_pass_exact(ck, sk, cwt, swt, a, P1.u_amp, v * 0.05, P.geom, accumulate,
                                sc, idx)
        else:
            m = K.drag_pass(ck, sk, cwt, swt, a, v * 0.05, P1, chain.cxi, chain.sxi, mom,
                            accumulate, sc, idx, False)
        if L_x == 0.5:
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
                    chain.P, cxi, chain.sxi, mom, True, sc, idx, False)
    assert m == n
    q2, q3 = K.drag_sums(0.01 * chain.P.u_amp, 1.0, 0.0, 5.0, cxi, chain.sxi)
    assert sc[2, 0] == q2 and sc[3, 0] == q3


@pytest.mark.parametrize("L_x", [0.5, 3.0])
@pytest.mark.parametrize("m", [1, 13, 17, 40])
def test_cell_sums_are_per_floe_sums_bit_for_bit(L_x, m):
    """cell_sums (vectorised across floes, lanes padded) gives exactly drag_sums /
    drag_force_sum floe by floe: the summation order over the cells is the source's."""
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
            if accumulate:
                q2, q3 = K.drag_sums(A, sc[K.SC_C, i], sc[K.SC_S, i], v[i] * 0.05,
                                     chain.cxi, chain.sxi)
                assert sc[K.SC_S3, i] == q3
            else:
                q2 = K.drag_force_sum(A, sc[K.SC_C, i], sc[K.SC_S, i], v[i] * 0.05,
                                      chain.cxi, chain.sxi)
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
