"""Ice-water drag (eq. 15) and dissipation (eqs. 19, 22): quadrature and exact modes."""
import math

import numpy as np
import pytest

from floewave import ModelConfig, run_point, solve_dispersion
from floewave import _kernels as K
from floewave._exact import exact_geometry
from floewave.model import FloeChain


def _state(cfg):
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = np.full(cfg.n_floes, cfg.a0)
    chain.run(a, 2000)
    return chain, a


@pytest.mark.parametrize("L_x", [0.5, 1.5, 3.0])
def test_exact_mode_is_the_dx_to_zero_limit_of_the_quadrature(L_x):
    """Same floe state: drag force and |u_rel|^3 sums of the quadrature converge to the
    exact mode's as dx -> 0 (midpoint rule: O(dx^2)), and agree to 1e-6 at dx = L_x/4000."""
    cfg = ModelConfig(L_x=L_x, drag_integration="exact")
    chain, a = _state(cfg)
    A = cfg.a0 * chain.P.u_amp
    th = chain.k * chain.x - 0.37
    errs = []
    for dx in (L_x / 50, L_x / 100, L_x / 200, L_x / 4000):
        q = ModelConfig(L_x=L_x, dx=dx)
        xi = (np.arange(q.n_x) + 0.5) * dx - L_x / 2
        cxi, sxi = np.cos(chain.k * xi), np.sin(chain.k * xi)
        Pe = chain.P._replace(geom=exact_geometry(chain.k * L_x, float(q.n_x)))
        err = 0.0
        for i in range(cfg.n_floes):
            c, s = math.cos(th[i]), math.sin(th[i])
            v = chain.u[i]
            q2, q3 = K.floe_drag(A, c, s, v, True, K.DRAG_QUADRATURE, chain.P, cxi, sxi)
            e2, e3 = K.floe_drag(A, c, s, v, True, K.DRAG_EXACT, Pe, cxi, sxi)
            scale = q.n_x * (A + abs(v)) ** 2
            err = max(err, abs(q2 - e2) / scale, abs(q3 - e3) / (scale * (A + abs(v))))
        errs.append(err)
    assert errs[-1] < 1e-6
    orders = np.log2(np.array(errs[:2]) / np.array(errs[1:3]))
    assert np.all(orders > 1.7), orders


@pytest.mark.parametrize("mode", ["quadrature", "exact"])
def test_fixed_floes_dissipation_is_eq22(mode):
    """u_i = 0: S_sd = -rho_w C_sd <|u_w0|^3> = -rho_w C_sd (4/3pi) (a omega / tanh kh)^3."""
    cfg = ModelConfig(confined=True, nT=1, max_iterations=1, noise_window=0,
                      drag_integration=mode, L_x=1.5, protocol="noise_floor")
    r = run_point(cfg)
    k, _ = solve_dispersion(cfg)
    expected = -cfg.rho_w * cfg.C_sd * 4 / (3 * math.pi) * (
        cfg.a0 * cfg.omega / math.tanh(k * cfg.h)) ** 3
    np.testing.assert_allclose(r.S_sd, expected, rtol=1e-6, atol=0)


def test_exact_mode_confined_profile_is_eq25():
    cfg = ModelConfig(confined=True, d_f=0.0, nT=1, delta=1e-9, noise_window=0,
                      max_iterations=200, drag_integration="exact", C_sd=0.2)
    r = run_point(cfg)
    exact = 1.0 / (r.alpha_c * r.x_mean + 1.0 / cfg.a0)
    assert np.max(np.abs(r.a / exact - 1)) <= 5e-3
    assert r.kernel_mode == "numba/exact/confined"


def test_exact_and_quadrature_dem_points_agree_within_errors():
    """A reduced DEM point in both modes: far-end amplitudes within 4 combined std errors."""
    opts = dict(L_x=1.5, n0=3, n0_warm=3, nT=2, noise_window=4, n_average=20, eps=0.4, relax=0.3,
                target_stderr=0.0, replicas=1, placement="uniform",
                max_iterations=80)
    rq = run_point(ModelConfig(**opts))
    re_ = run_point(ModelConfig(drag_integration="exact", **opts))
    assert rq.status == re_.status == "converged_noisy"
    se = np.sqrt(rq.a_stderr**2 + re_.a_stderr**2)
    assert np.all(np.abs(rq.a - re_.a) <= 4 * se + 1e-4 * rq.a0)
