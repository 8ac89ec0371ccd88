"""Dispersion relations (eq. 6), group velocity (eq. 7) and alpha_c (eqs. 24, 27, 28)."""
import math

import pytest

from floewave import DispersionError, ModelConfig, alpha_confined, solve_dispersion
from floewave.config import G
from floewave.dispersion import (
    coefficients,
    dispersion_residual,
    omega_of_k,
    solve_dispersion_omega,
)

PERIODS = (1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0)


@pytest.mark.parametrize("disp", ["ep", "ml", "ow"])
@pytest.mark.parametrize("T", PERIODS)
def test_eq6_residual_and_group_velocity(disp, T):
    cfg = ModelConfig(T=T, dispersion=disp)
    k, cg = solve_dispersion(cfg)
    b1, b2 = coefficients(cfg)
    assert abs(dispersion_residual(k, cfg.omega, cfg.h, b1, b2)) <= 1e-10
    # eq. 7 against a central difference of omega(k) (step chosen for ~1e-10 truncation)
    dk = 1e-5 * k
    num = (omega_of_k(k + dk, cfg.h, b1, b2) - omega_of_k(k - dk, cfg.h, b1, b2)) / (2 * dk)
    assert cg == pytest.approx(num, rel=1e-6)


@pytest.mark.parametrize("disp", ["ep", "ml", "ow"])
def test_solving_at_an_omega_is_solving_its_configuration(disp):
    """solve_dispersion_omega(cfg, omega) (a curve of many frequencies, Fig. 1) is
    solve_dispersion of the configuration with that period, bit for bit; ml beyond its
    cutoff is refused by both."""
    for T in (*PERIODS, 0.4, 7.0):
        cfg = ModelConfig(T=T, dispersion=disp)
        assert solve_dispersion_omega(cfg.replace(T=99.0), cfg.omega) == solve_dispersion(cfg)
    if disp == "ml":
        cfg = ModelConfig(T=0.05, dispersion="ml")
        for solve in (lambda: solve_dispersion(cfg),
                      lambda: solve_dispersion_omega(cfg, cfg.omega)):
            with pytest.raises(DispersionError, match="cutoff"):
                solve()


def test_field_scale_example():
    cfg = ModelConfig(h=1000.0, rho_w=1025.0, rho_i=910.0, E=6e9, h_i=1.5, nu=0.3, T=10.0,
                      dispersion="ep", L_x=3.0, L_sheet=42.0)
    k, cg = solve_dispersion(cfg)
    b1, b2 = coefficients(cfg)
    assert abs(dispersion_residual(k, cfg.omega, cfg.h, b1, b2)) <= 1e-10
    assert cg > 0


def test_ep_tends_to_ml_as_E_vanishes():
    k_ml, cg_ml = solve_dispersion(ModelConfig(dispersion="ml"))
    errs = []
    for E in (3e3, 3e1, 3e-1):
        k, cg = solve_dispersion(ModelConfig(dispersion="ep", E=E))
        errs.append(abs(k / k_ml - 1))
        assert cg == pytest.approx(cg_ml, rel=1e-6 * E)
    # the difference is linear in E (beta2 ~ E): two decades of E, two decades of error
    assert errs[0] / errs[1] == pytest.approx(100, rel=0.01)
    assert errs[1] / errs[2] == pytest.approx(100, rel=0.01)
    assert errs[-1] < 1e-8


def test_ml_tends_to_ow_as_ice_thins():
    k_ow, cg_ow = solve_dispersion(ModelConfig(dispersion="ow"))
    for hi, tol in ((3e-3, 3e-2), (3e-5, 3e-4), (3e-7, 3e-6)):
        k, cg = solve_dispersion(ModelConfig(dispersion="ml", h_i=hi))
        assert k == pytest.approx(k_ow, rel=tol)
        assert cg == pytest.approx(cg_ow, rel=tol)


def test_ow_deep_water_limits():
    cfg = ModelConfig(dispersion="ow", h=1000.0, T=2.0)
    k, cg = solve_dispersion(cfg)
    assert k == pytest.approx(cfg.omega**2 / G, rel=1e-12)          # omega^2 = g k
    assert cg == pytest.approx(0.5 * G / cfg.omega, rel=1e-12)       # c_g = c / 2


def test_ow_shallow_water_limit():
    cfg = ModelConfig(dispersion="ow", h=0.002, T=20.0)
    k, cg = solve_dispersion(cfg)
    c0 = math.sqrt(G * cfg.h)
    kh = k * cfg.h
    # c = c0 (1 - (kh)^2 / 6 + ...), c_g = c0 (1 - (kh)^2 / 2 + ...)
    assert cfg.omega / k == pytest.approx(c0 * (1 - kh**2 / 6), rel=1e-9)
    assert cg == pytest.approx(c0 * (1 - kh**2 / 2), rel=1e-9)


def test_ml_cutoff_is_a_clear_error():
    # omega^2 < g rho_w / (rho_i h_i): with h_i = 0.5 m the cutoff period is ~1.36 s
    cfg = ModelConfig(dispersion="ml", h_i=0.5, T=1.2)
    with pytest.raises(DispersionError, match="mass-loading cutoff"):
        solve_dispersion(cfg)
    with pytest.raises(ValueError):
        cfg.check_physics()
    solve_dispersion(cfg.replace(T=1.5))  # below the cutoff frequency: fine


@pytest.mark.parametrize("T", PERIODS)
def test_alpha_c_special_cases(T):
    """eq. 24 equals eq. 27 for 'ow' and eq. 28 (A^2 alpha_ow) for 'ml'."""
    ow = ModelConfig(T=T, dispersion="ow", C_sd=0.05)
    k, _ = solve_dispersion(ow)
    kh = k * ow.h
    f = math.tanh(kh) ** -4 / (1 + 2 * kh / math.sinh(2 * kh))
    a_ow = 8 * ow.C_sd / (3 * math.pi * G**2) * f * ow.omega**4
    assert alpha_confined(ow) == pytest.approx(a_ow, rel=1e-12)
    ml = ow.replace(dispersion="ml")
    k_ml, _ = solve_dispersion(ml)
    A = 1 + ml.rho_i * ml.h_i / ml.rho_w * k_ml * math.tanh(k_ml * ml.h)
    kh = k_ml * ml.h
    f_ml = math.tanh(kh) ** -4 / (1 + 2 * kh / math.sinh(2 * kh))
    a_ml_eq28 = A**2 * 8 * ml.C_sd / (3 * math.pi * G**2) * f_ml * ml.omega**4
    assert alpha_confined(ml) == pytest.approx(a_ml_eq28, rel=1e-10)


def test_alpha_c_ordering_and_linearity_in_Csd():
    base = ModelConfig(T=1.2, C_sd=0.05)
    a = {d: alpha_confined(base.replace(dispersion=d)) for d in ("ep", "ml", "ow")}
    assert a["ml"] > a["ow"] > a["ep"]
    assert alpha_confined(base.replace(C_sd=0.1)) == pytest.approx(2 * alpha_confined(base))
