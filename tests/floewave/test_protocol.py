"""The stationary iteration protocol (floewave.iteration.stationary, floewave._march): the
self-consistent march against eq. 20, the confined limit, the stationarity tests on series
whose transient is known, and the time-step rule."""
import math

import numpy as np
import pytest

from floewave import ConfigError, InvalidPointError, ModelConfig, march_coefficients, run_point
from floewave._march import coefficients, march_amplitude, mean_coefficients
from floewave.iteration.stationary import confined_profile
from floewave.iteration.stationarity import halves_z, mser_truncation


def test_self_consistent_march_solves_eq20_with_its_own_dissipation():
    """a from c, then S = c a^3 marched by eq. 20 gives a back (to rounding)."""
    cfg = ModelConfig(L_x=0.5)
    rng = np.random.default_rng(3)
    c = -rng.uniform(0.5, 3.0, (3, cfg.n_floes)) * 1e2      # S / a^3 [W m^-5]
    a = march_coefficients(cfg, c, c_g=0.9, k=3.0)
    assert np.all(a > 0) and np.all(np.diff(a, axis=1) < 0)
    for r in range(3):
        again = march_amplitude(cfg, c[r] * a[r] ** 3, c_g=0.9, k=3.0)
        np.testing.assert_allclose(again, a[r], rtol=1e-12, atol=0)


def test_self_consistent_march_with_overwash_is_eq21():
    cfg = ModelConfig(L_x=0.5, overwash=True, c_ow=0.05, s_min=0.0)
    c = np.full(cfg.n_floes, -150.0)
    a = march_coefficients(cfg, c, c_g=0.9, k=3.0)
    np.testing.assert_allclose(march_amplitude(cfg, c * a**3, 0.9, 3.0), a, rtol=1e-12)


def test_a_wave_that_dies_out_is_zero_beyond_never_nan():
    """Cubic dissipation alone decays algebraically (as eq. 25 does); the wave dies only
    where a floe would take more than its own energy (q a > 1 upwave): 0 from there on."""
    cfg = ModelConfig(L_x=0.5)
    strong = march_coefficients(cfg, np.full(cfg.n_floes, -1e6), c_g=0.9, k=3.0)
    assert np.all(strong > 0) and np.all(np.diff(strong) < 0)
    c = np.full(cfg.n_floes, -100.0)
    c[0] = -1e9
    a = march_coefficients(cfg, c, c_g=0.9, k=3.0)
    assert np.all(np.isfinite(a)) and a[0] > 0 and np.all(a[1:] == 0.0)


def test_coefficients_skip_floes_without_a_wave():
    S = np.array([[-2.0, -1.0, 0.0, 0.0]])
    A = np.array([[1.0, 0.5, 0.0, 0.0]])
    c = coefficients(S, A)
    assert c[0, 0] == -2.0 and c[0, 1] == -8.0 and np.all(np.isnan(c[0, 2:]))
    # the mean ignores unmeasured windows; an unmeasured floe takes its upwave neighbour's
    C = np.array([[[-1.0, np.nan, np.nan]], [[-3.0, -4.0, np.nan]]])
    np.testing.assert_array_equal(mean_coefficients(C), [[-2.0, -4.0, -4.0]])


def test_confined_point_converges_in_one_update_to_the_discrete_eq20_profile():
    """Fixed floes: S = c a^3 exactly, so the first update is the fixed point; the second
    window confirms it (status converged). The profile is the noise_floor protocol's
    converged one (eq. 20, iterated to delta 1e-9) and close to eq. 25."""
    cfg = ModelConfig(confined=True, d_f=0.0, C_sd=0.2, L_x=1.5)
    r = run_point(cfg)
    assert r.status == "converged" and r.iterations == 2
    old = run_point(cfg.replace(protocol="noise_floor", relax=1.0, noise_window=0,
                                delta=1e-9, max_iterations=200))
    assert old.status == "converged"
    np.testing.assert_allclose(r.a, old.a, rtol=1e-8)
    eq25 = confined_profile(cfg, r.x_mean, r.alpha_c)
    assert np.max(np.abs(r.a / eq25 - 1)) <= 5e-3


def test_mser_finds_a_known_transient():
    rng = np.random.default_rng(11)
    y = np.concatenate([np.linspace(2.0, 1.0, 8), 1.0 + 0.05 * rng.standard_normal(24)])
    assert 6 <= mser_truncation(y, 5) <= 10
    flat = 1.0 + 0.05 * rng.standard_normal(30)
    assert mser_truncation(flat, 5) <= 8
    assert mser_truncation(np.ones(12), 5) == 0
    # a step to a constant tail: truncated at the step
    step = np.concatenate([np.full(20, 0.0), np.full(60, 0.0096153846153846)])
    assert mser_truncation(step, 8) == 20
    # a deterministic creep (non-chaotic point): MSER truncates at the end, whatever n
    creep = 0.97 + 1e-10 * 0.9 ** np.arange(60)
    assert mser_truncation(creep, 8) == 52


def test_a_non_chaotic_point_stops_after_its_minimum():
    """3 m floes, T 1.4 s, C_sd 0.01: the replicas agree to 1e-11 a0 and the amplitudes creep
    by 1e-10 a0; rounded to the resolution of a reported amplitude the series is stationary
    at once (unrounded, MSER kept truncating at the end: 100 windows, not_converged)."""
    from floewave import solve_dispersion
    from floewave.transient import transient_windows

    cfg = ModelConfig(L_x=3.0, T=1.4, a0=0.02, C_sd=0.01, eps=0.8, d_f=0.01, dispersion="ow")
    r = run_point(cfg)
    k, _ = solve_dispersion(cfg)
    assert r.status == "converged_noisy"
    assert r.iterations == transient_windows(cfg, k) + cfg.n_average


def test_halves_test_sees_a_drift_the_replicas_share():
    rng = np.random.default_rng(7)
    n, R = 16, 8
    noise = 0.01 * rng.standard_normal((n, R))
    drift = np.linspace(0.0, 0.03, n)[:, None]
    assert abs(halves_z(noise + drift, 1e-6)) > 2.5
    zs = [halves_z(0.01 * rng.standard_normal((n, R)), 1e-6) for _ in range(200)]
    assert np.mean(np.abs(zs) > 2.5) < 0.1          # t with 7 dof: ~4 % beyond 2.5
    # identical replicas (no chaos): the floor decides
    same = np.tile(np.linspace(0, 1e-6, n)[:, None], (1, R))
    assert abs(halves_z(same, 1e-3)) < 1e-2


def test_a_point_stopped_before_stationarity_is_not_converged_with_finite_estimates():
    cfg = ModelConfig(L_x=3.0, eps=0.6, max_iterations=6)
    r = run_point(cfg)
    assert r.status == "not_converged" and r.iterations == 6
    assert np.all(np.isfinite(r.a)) and np.all(np.isfinite(r.a_stderr))
    assert np.all(r.a > 0)


def test_stationary_point_meets_its_targets():
    cfg = ModelConfig(L_x=3.0, eps=0.6, T=1.4, C_sd=0.1, d_f=0.01)
    r = run_point(cfg)
    assert r.status == "converged_noisy"
    assert np.max(r.a_stderr) <= cfg.target_stderr * cfg.a0
    assert r.iterations >= cfg.transient_min + cfg.n_average
    assert r.floe_steps == cfg.floe_steps_of(r.iterations)


def test_fixed_transient_runs_exactly_its_windows():
    cfg = ModelConfig(L_x=3.0, stationarity="fixed", transient_min=3, n_average=4,
                      max_iterations=50, target_stderr=0.0, target_W_c_stderr=0.0)
    r = run_point(cfg)
    assert r.status == "converged_noisy" and r.iterations == 7


@pytest.mark.parametrize("contact,dt,ok", [("hertz_disk", 1e-3, True), ("linear", 1e-3, False),
                                           ("linear", 1e-4, True), ("hertz_disk", 1e-4, True)])
def test_the_time_step_must_resolve_a_binary_contact(contact, dt, ok):
    cfg = ModelConfig(contact=contact, dt=dt)
    steps = cfg.contact_steps()
    # the half period of the stiffest undamped contact, pi sqrt(m* / k), in steps
    y = cfg.E / (2 * (1 - cfg.nu**2))
    k = y * cfg.L_y * cfg.h_i / cfg.L_x if contact == "linear" else math.pi * y * cfg.h_i * 0.9117
    assert steps == pytest.approx(math.pi * math.sqrt((1 + cfg.C_m) * cfg.mass / 2 / k) / dt)
    if ok:
        cfg.check_physics()
    else:
        with pytest.raises(InvalidPointError, match="dt"):
            cfg.check_physics()
    ModelConfig(contact=contact, dt=dt, confined=True).check_physics()   # no contacts


def test_the_transient_spans_the_drag_relaxation_time():
    """tau_d = (1 + C_m) m / (rho_w C_sd L_y L_x u_w0): 1/C_sd, independent of L_x (mass
    and drag area both scale with it); the transient is transient_drag_times tau_d long,
    at least transient_min windows and at most half of max_iterations."""
    from floewave import solve_dispersion
    from floewave.iteration.stationary import drag_time, transient_windows

    cfg = ModelConfig(C_sd=0.005, T=1.1)
    k, _ = solve_dispersion(cfg)
    u = cfg.a0 * cfg.omega / math.tanh(k * cfg.h)
    tau = (1 + cfg.C_m) * cfg.mass / (cfg.rho_w * cfg.C_sd * cfg.L_y * cfg.L_x * u)
    assert drag_time(cfg, k) == pytest.approx(tau, rel=1e-12)
    assert drag_time(cfg.replace(L_x=3.0), k) == pytest.approx(tau, rel=1e-12)
    assert drag_time(cfg.replace(C_sd=0.01), k) == pytest.approx(tau / 2, rel=1e-12)
    n = transient_windows(cfg, k)
    assert n == math.ceil(cfg.transient_drag_times * tau / (cfg.nT * cfg.T)) > cfg.transient_min
    assert transient_windows(cfg.replace(C_sd=0.2), k) == cfg.transient_min
    assert transient_windows(cfg.replace(C_sd=0.0), k) == cfg.max_iterations // 2
    assert transient_windows(cfg.replace(transient_drag_times=0.0), k) == cfg.transient_min
    # 0 drag times is no bound even without drag (inf * 0 must not decide)
    assert transient_windows(cfg.replace(C_sd=0.0, transient_drag_times=0.0), k) == \
        cfg.transient_min


def test_the_march_root_is_exact_where_the_cubic_term_dominates():
    """a^2 + q a^3 = b with q sqrt(b) ~ 1e56: Newton from min(sqrt(b), cbrt(b/q)) converges
    (from sqrt(b) alone it ran out of its 100 steps with a 1e-8 relative residual)."""
    cfg = ModelConfig(L_x=0.5)
    fac = cfg.L_x / (cfg.rho_w * 9.81 * 0.9)
    for c0 in (-1e30, -1e50, -1e60):
        c = np.full(cfg.n_floes, -100.0)
        c[0] = c0
        a1 = march_coefficients(cfg, c, c_g=0.9, k=3.0)[0]
        q = -fac * c0
        assert a1 > 0
        assert abs(a1 * a1 + q * a1**3 - cfg.a0**2) <= 1e-12 * cfg.a0**2


def test_the_convergence_term_and_the_floor_of_an_ensembles_error_bar():
    """SE(a)^2 = jackknife^2 + |mean_r (a_new - a)|^2, at least SE_FLOOR a0; one chain
    keeps its own error bar."""
    from copy import copy
    from types import SimpleNamespace

    from floewave.iteration.estimate import SE_FLOOR, _with_convergence

    cfg = ModelConfig(L_x=3.0)
    n = cfg.n_floes
    est = SimpleNamespace(a_stderr=np.full(n, 3e-5), a_end_stderr=3e-5)   # an Estimate's two
    a_old = np.full((2, n), 0.01)
    a_new = a_old + np.array([[4e-5], [4e-5]])          # both replicas moved by +4e-5
    out = _with_convergence(cfg, copy(est), a_new, a_old)
    np.testing.assert_allclose(out.a_stderr, 5e-5, rtol=1e-12)        # 3-4-5
    assert out.a_end_stderr == pytest.approx(5e-5, rel=1e-12)
    opposite = a_old + np.array([[4e-5], [-4e-5]])       # signed changes cancel
    np.testing.assert_allclose(_with_convergence(cfg, copy(est), opposite, a_old).a_stderr,
                               3e-5, rtol=1e-12)
    tiny = SimpleNamespace(a_stderr=np.full(n, 1e-15), a_end_stderr=1e-15)
    floor = _with_convergence(cfg, tiny, a_old, a_old).a_stderr
    assert np.all(floor == SE_FLOOR * cfg.a0)
    one = ModelConfig(L_x=3.0, replicas=1)
    assert _with_convergence(one, copy(est), a_new, a_old).a_stderr is est.a_stderr


def test_mean_coupling_under_the_stationary_protocol_shares_one_profile():
    cfg = ModelConfig(L_x=3.0, replicas=3, coupling="mean", max_iterations=16)
    r = run_point(cfg)
    assert r.status in ("converged_noisy", "not_converged")
    assert np.all(np.isfinite(r.a)) and np.all(np.diff(r.a) <= 0)
    # the coupling decides the forcing, so the trajectories: the same replicas marching
    # their own a(x) dissipate differently
    ind = run_point(cfg.replace(coupling="independent"))
    assert r.S_sd_replicas.shape == ind.S_sd_replicas.shape == (3, cfg.n_floes)
    assert not np.array_equal(r.S_sd_replicas, ind.S_sd_replicas)


def test_max_average_must_be_at_least_n_average():
    with pytest.raises(ConfigError, match=r"max_average = 30 must be 0 or >= n_average \(40\)"):
        ModelConfig(n_average=40)
    assert ModelConfig(n_average=10, max_average=0).max_average == 0


def test_a_stationary_run_that_cannot_meet_its_targets_stops_at_max_average():
    """An unreachable target (SE(a) <= 1e-9 a0 at a chaotic point): with max_average the
    run stops once that many stationary windows are averaged, not_converged with the
    estimate and error bars of those windows, below max_iterations; without, it runs to
    max_iterations."""
    base = dict(L_x=3.0, eps=0.6, T=1.4, C_sd=0.2, d_f=0.01, nT=1, n0=1, transient_min=3,
                n_average=4, target_stderr=1e-9, target_W_c_stderr=0.0, max_iterations=40)
    cfg = ModelConfig(**base, max_average=6)
    bounded = run_point(cfg)
    assert bounded.status == "not_converged"
    assert 3 + 6 <= bounded.iterations < 40
    assert np.max(bounded.a_stderr) > 1e-9 * cfg.a0
    assert np.all(np.isfinite(bounded.a)) and np.all(np.isfinite(bounded.a_stderr))
    unbounded = run_point(ModelConfig(**base, max_average=0))
    assert unbounded.status == "not_converged" and unbounded.iterations == 40
    # a reachable target stops before the bound, converged_noisy
    easy = run_point(ModelConfig(**{**base, "target_stderr": 0.5}, max_average=6))
    assert easy.status == "converged_noisy" and easy.iterations < bounded.iterations

def test_past_the_transient_bound_the_update_pools_the_windows_after_it():
    """Model version 9: before n_average windows the update marches from the last window
    only until the transient's bound d_min has passed, then from the windows after it
    (version 8 used the last window until n_average: the first averaged windows ran at
    one window's noise)."""
    from floewave.iteration.stationarity import truncation
    cfg = ModelConfig(n_average=10)
    series = [np.zeros((3, 4)) for _ in range(9)]
    assert [truncation(cfg, series[:n], 6) for n in (1, 5, 6, 7, 9)] == [
        (0, False), (4, False), (5, False), (6, False), (6, False)]
    # a bound beyond n_average: the last window until then, as before
    assert truncation(cfg, series[:9], 20) == (8, False)
    fixed = ModelConfig(n_average=10, stationarity="fixed", transient_min=3)
    assert truncation(fixed, series[:8], 6) == (3, True)
