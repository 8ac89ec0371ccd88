"""Confined ice (docs/model.md §5, paper §3): the iteration reproduces eqs. 22-25."""
import math

import numpy as np
import pytest

from floewave import ModelConfig, alpha_confined, run_point, solve_dispersion


@pytest.mark.parametrize("disp", ["ep", "ml", "ow"])
@pytest.mark.parametrize("C_sd", [0.05, 0.2])
def test_confined_profile_matches_eq25(disp, C_sd):
    """a(x) = 1 / (alpha_c x + 1/a0) with alpha_c from eq. 24, to <= 0.5% at every floe."""
    cfg = ModelConfig(dispersion=disp, C_sd=C_sd, confined=True, d_f=0.0, nT=1, delta=1e-9,
                      noise_window=0, max_iterations=200)
    r = run_point(cfg)
    assert r.status == "converged"
    alpha_c = alpha_confined(cfg)
    assert r.alpha_c == alpha_c
    exact = 1.0 / (alpha_c * r.x_mean + 1.0 / cfg.a0)
    assert np.max(np.abs(r.a / exact - 1)) <= 5e-3
    # the attenuation is visible (the test can fail): a_end well below a0
    assert r.a[-1] < 0.99 * cfg.a0
    # and the 1/a fit recovers alpha_c (eq. 25 is linear in 1/a)
    assert r.alpha_all == pytest.approx(alpha_c, rel=5e-3)
    assert r.alpha_all_resid < r.alpha_exp_resid


def test_confined_S_sd_is_eq22():
    """Fixed floes: S_sd,i = -rho_w C_sd (4 / 3 pi) (a_i omega / tanh kh)^3 (eqs. 19, 22)."""
    cfg = ModelConfig(confined=True, d_f=0.0, nT=1, max_iterations=1, noise_window=0,
                      protocol="noise_floor")
    r = run_point(cfg)
    k, _ = solve_dispersion(cfg)
    # after one iteration the window ran with a = a0 on every floe
    expected = -cfg.rho_w * cfg.C_sd * 4 / (3 * math.pi) * (cfg.a0 * cfg.omega
                                                             / math.tanh(k * cfg.h)) ** 3
    assert np.allclose(r.S_sd, expected, rtol=1e-6, atol=0)


def test_confined_rate_scales_with_frequency_like_omega4_for_ow_deep_water():
    """eq. 27 in deep water: alpha_c,ow ~ omega^4 (paper §3)."""
    a1 = alpha_confined(ModelConfig(dispersion="ow", h=1000.0, T=1.0))
    a2 = alpha_confined(ModelConfig(dispersion="ow", h=1000.0, T=2.0))
    assert a1 / a2 == pytest.approx(16.0, rel=1e-9)
