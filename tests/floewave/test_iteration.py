"""The ``noise_floor`` attenuation iteration (docs/model.md §4) on a reduced full-DEM point (the
stationary protocol's own tests: tests/floewave/test_protocol.py)."""
import numpy as np
import pytest

from floewave import ModelConfig, run_point
from floewave._march import march_amplitude, noise_floor_reached, residual

# the earlier protocol with the model's numerics (dt 1e-3, the drag every 4 steps: 20 times
# faster than model version 5's dt 1e-4 with the drag every step, which these tests used)
REDUCED = dict(protocol="noise_floor", coupling="mean",
               replicas=1, placement="uniform", L_x=1.5, n0=3, n0_warm=3, nT=2, noise_window=4,
               max_iterations=80, relax=0.3,
               target_stderr=0.0, reuse_floor=False)


@pytest.fixture(scope="module")
def windows():
    """The same point averaged over 5 and over 30 iterations after the noise floor."""
    return {n: run_point(ModelConfig(eps=0.4, n_average=n, **REDUCED)) for n in (5, 30)}


def test_full_dem_point_converges_with_a_decreasing_profile(windows):
    r = windows[30]
    cfg = ModelConfig(eps=0.4, **REDUCED)
    assert r.status in ("converged", "converged_noisy")
    assert len(r.residual_history) == r.iterations and r.residual == r.residual_history[-1]
    # the status agrees with the history: no residual fell below delta before the last one,
    # and a noisy convergence first saw the floor (two noise windows), then averaged 30
    assert np.all(r.residual_history[:-1] >= cfg.delta)
    if r.status == "converged_noisy":
        assert r.iterations >= 2 * cfg.noise_window + 30
    assert np.all(r.a > 0) and np.all(r.a <= cfg.a0)
    assert np.all(np.diff(r.a) <= 0)
    assert r.a[-1] < 0.95 * cfg.a0          # the drag attenuates
    assert r.floe_steps == r.iterations * cfg.floe_steps_per_iteration()  # n0_warm == n0
    later = cfg.replace(n0_warm=1)
    assert later.floe_steps_of(5) == (cfg.n0 + cfg.nT + 4 * (1 + cfg.nT)) * cfg.n_t * 28
    assert r.x_mean.shape == r.a.shape == r.gap_mean.shape == (cfg.n_floes,)
    assert np.isnan(r.gap_mean[-1]) and np.all(np.isfinite(r.gap_mean[:-1]))
    assert np.all((r.contact_fraction[:-1] >= 0) & (r.contact_fraction[:-1] <= 1))
    assert np.all(r.collisions[:-1] >= 0)
    assert np.all(r.S_sd < 0)
    assert r.ice_extent == r.x_mean[-1] + 0.5 * cfg.L_x
    assert r.compact_zone in ("edge", "inverted", "patchy", "none")
    if r.compact_zone == "none":
        assert np.isnan(r.W_c) and np.isnan(r.compact_end) and np.isnan(r.alpha_inner)
    else:
        assert 0 < r.W_c < r.compact_end <= r.ice_extent


def test_standard_error_shrinks_with_the_averaging_window(windows):
    """Six times the samples: 1/sqrt(6) = 0.41 for independent samples; asserted < 0.75.
    (At eps = 0.8 this reduced point drifts slowly and the error shrinks much less.)"""
    short, long_ = windows[5], windows[30]
    assert short.status == long_.status == "converged_noisy"
    assert long_.noise > 0
    assert np.mean(long_.a_stderr) < 0.75 * np.mean(short.a_stderr)


def test_run_point_is_deterministic():
    cfg = ModelConfig(eps=0.6, L_x=3.0, n0=1, nT=1, max_iterations=3)
    r1, r2 = run_point(cfg), run_point(cfg)
    for name in ("a", "S_sd", "x_mean", "gap_mean", "F_c_mean", "residual_history"):
        np.testing.assert_array_equal(getattr(r1, name), getattr(r2, name))


def test_paper_plain_algorithm_available(monkeypatch):
    """relax = 1, no noise handling: the paper's iteration a <- a_new (each iteration's
    wave forcing is the amplitude the previous one marched); it stops at the first residual
    below delta or at max_iterations."""
    import floewave.iteration.noise_floor as M

    forcing, marched = [], []           # per iteration: a given to the window, a_new

    def window(cfg, chain, x0s, a, first):
        forcing.append(np.array(a))
        return run_window(cfg, chain, x0s, a, first)

    def march(*args):                   # coupling "independent": a profile per replica
        marched.append(np.array(march_rows(*args)))
        return marched[-1]

    run_window, march_rows = M.run_window, M.march_rows
    monkeypatch.setattr(M, "run_window", window)
    monkeypatch.setattr(M, "march_rows", march)
    cfg = ModelConfig(eps=0.6, L_x=3.0, n0=2, nT=1, relax=1.0, noise_window=0,
                      max_iterations=8, protocol="noise_floor")
    assert cfg.coupling == "independent" and cfg.n_chains > 1
    r = run_point(cfg)
    assert r.status in ("converged", "not_converged")
    hist = r.residual_history
    assert len(hist) == r.iterations == len(forcing) == len(marched) >= 2
    np.testing.assert_array_equal(forcing[0], cfg.a0)
    for it in range(1, r.iterations):   # relax = 1: not a blend of the old and new profiles
        np.testing.assert_array_equal(forcing[it], marched[it - 1])
        assert not np.array_equal(marched[it], marched[it - 1])
    assert list(hist) == [max(residual(f_r, m_r) for f_r, m_r in zip(f, m, strict=True))
                          for f, m in zip(forcing, marched, strict=True)]
    # the status agrees with the residual history: it stopped at the first residual below
    # delta (converged), else ran all 8 iterations with none below delta; never averaged
    assert np.all(hist[:-1] >= cfg.delta)
    if r.status == "converged":
        assert hist[-1] < cfg.delta
    else:
        assert r.iterations == 8 and hist[-1] >= cfg.delta


def test_march_is_eq20():
    cfg = ModelConfig(L_x=0.5)
    S = -np.linspace(1e-3, 2e-3, 5)
    a = march_amplitude(cfg, S, c_g=0.8, k=3.0)
    fac = cfg.L_x / (cfg.rho_w * 9.81 * 0.8)
    assert a[0] ** 2 == pytest.approx(cfg.a0**2 + fac * S[0])
    for i in range(1, 5):
        assert a[i] ** 2 == pytest.approx(a[i - 1] ** 2 + fac * (S[i - 1] + S[i]))
    # clipped at zero, never NaN
    assert np.all(march_amplitude(cfg, np.full(5, -1e3), 0.8, 3.0) == 0)


def test_overwash_removes_energy_eq21():
    cfg = ModelConfig(overwash=True, c_ow=0.05, s_min=0.0)
    S = np.zeros(4)
    a = march_amplitude(cfg, S, c_g=0.8, k=3.0)
    h_ow = 0.05 * 3.0 * cfg.a0
    assert a[1] ** 2 == pytest.approx(cfg.a0**2 - 3 * 9.81**0.5 * h_ow**2.5 / 0.8)
    assert np.all(np.diff(a) < 0)
    assert np.all(march_amplitude(cfg.replace(s_min=1.0), S, 0.8, 3.0) == cfg.a0)


def test_residual_and_noise_floor_detection():
    assert residual(np.array([1.0, 2.0, 0.0]), np.array([1.1, 1.0, 5.0])) == pytest.approx(0.5)
    decaying = list(0.5 * 0.7 ** np.arange(12))
    assert not noise_floor_reached(decaying, 4)
    noisy = decaying[:4] + [0.03, 0.01, 0.04, 0.02, 0.025, 0.03, 0.015, 0.02]
    assert noise_floor_reached(noisy, 4)
    assert not noise_floor_reached(noisy, 0)


def test_adaptive_window_meets_its_stderr_target():
    """target_stderr: averaging continues until max_i a_stderr_i <= target a0."""
    opts = {**REDUCED, "eps": 0.4, "n_average": 3}
    loose = run_point(ModelConfig(**{**opts, "target_stderr": 0.05}))
    tight = run_point(ModelConfig(**{**opts, "target_stderr": 0.002}))
    for r, target in ((loose, 0.05), (tight, 0.002)):
        assert r.status == "converged_noisy"
        assert np.max(r.a_stderr) <= target * r.a0
    assert tight.iterations > loose.iterations


def test_reuse_floor_starts_the_average_with_the_floor_window():
    """With reuse_floor the noise_window samples that revealed the floor count towards
    n_average: the same trajectory ends exactly noise_window iterations earlier."""
    opts = {**REDUCED, "eps": 0.4, "n_average": 10}
    plain = run_point(ModelConfig(**{**opts, "reuse_floor": False}))
    reuse = run_point(ModelConfig(**{**opts, "reuse_floor": True}))
    assert plain.status == reuse.status == "converged_noisy"
    assert reuse.iterations == plain.iterations - REDUCED["noise_window"]
    np.testing.assert_array_equal(reuse.residual_history,
                                  plain.residual_history[:reuse.iterations])
