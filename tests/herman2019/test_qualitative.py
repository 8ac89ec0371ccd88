"""Paper §4 qualitative results (docs/model.md §8) on small, reduced-numerics points.

Reduced: L_x = 1.5 m (28 floes; 0.5 m, 84 floes, for the floe-size and W_c checks), n0 = 3,
nT = 2 periods per iteration, ensembles of 4 replicas averaged over 6 iterations (8 for
0.5 m) at the noise floor. Each comparison is between values whose difference is many
(jackknife) standard errors wide (asserted).
"""
import pytest

from floewave import ModelConfig, run_point

REDUCED = dict(L_x=1.5, n0=3, n0_warm=3, nT=2, noise_window=4, n_average=6, max_iterations=60,
               relax=0.3, target_stderr=0.0, target_W_c_stderr=0.0, replicas=4)


@pytest.fixture(scope="module")
def points():
    out = {}
    for eps in (0.2, 0.8):
        for disp in ("ml", "ep"):
            out[eps, disp] = run_point(ModelConfig(eps=eps, dispersion=disp, **REDUCED))
        out[eps, "ml", 0.5] = run_point(ModelConfig(
            eps=eps, dispersion="ml", **{**REDUCED, "L_x": 0.5, "n_average": 8}))
    return out


def _clearly_less(r1, r2, n_sigma=3.0):
    """r1's far-end a is below r2's by more than n_sigma combined standard errors."""
    diff = r2.a[-1] - r1.a[-1]
    se = (r1.a_stderr[-1] ** 2 + r2.a_stderr[-1] ** 2) ** 0.5
    return diff > n_sigma * se


@pytest.mark.parametrize("disp", ["ml", "ep"])
def test_higher_restitution_attenuates_more(points, disp):
    assert _clearly_less(points[0.8, disp], points[0.2, disp])


@pytest.mark.parametrize("eps", [0.2, 0.8])
def test_elastic_plate_attenuates_less_than_mass_loading(points, eps):
    assert _clearly_less(points[eps, "ml"], points[eps, "ep"])


def test_higher_restitution_narrows_the_collisional_zone(points):
    """Paper Fig. 2: the zone of energetic collisions (W_c) shrinks as eps grows."""
    hi, lo = points[0.8, "ml", 0.5], points[0.2, "ml", 0.5]
    assert hi.W_c < 0.8 * lo.W_c
    assert lo.W_c - hi.W_c > 3.0 * (hi.W_c_stderr**2 + lo.W_c_stderr**2) ** 0.5


@pytest.mark.parametrize("eps", [0.2, 0.8])
def test_smaller_floes_attenuate_more(points, eps):
    """Paper §4: 0.5 m floes attenuate more than 1.5 m floes, all else equal."""
    assert _clearly_less(points[eps, "ml", 0.5], points[eps, "ml"])
