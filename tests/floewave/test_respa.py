"""Contacts on their own clock (``integrator = "respa"`` and ``"mts"``, floewave/_respa.py):
the kernel
against its numpy twin (which sub-steps every floe, so the kernel's choice of clusters must
not matter), a collision pushed on into a floe that was free (the outer step taken again),
the restitution table and an elastic collision's energy at every outer step, and replicas
that do not see each other."""
import numpy as np
import pytest

from floewave import ModelConfig, solve_dispersion
from floewave import _kernels as K
from floewave import _reference as ref
from floewave.ensemble import initial_positions
from floewave.model import FloeChain
from tests.floewave.helpers import collision_config, two_floe_collision

TABLE = (0.166, 0.368, 0.575, 0.786)   # docs/model.md §3, hertz_disk + liggghts


def _twin_state(chain):
    """The chain's state as the twin takes it over: x, u, slow acc, contact acc, flags."""
    n = chain.x0.size
    return (chain.x.ravel().copy(), chain.u.ravel().copy(), chain.acc.ravel().copy(),
            chain.work[K.W_AF, :n].copy(), chain.in_contact.ravel().copy())


TWINS = {"respa": ref.advance_respa, "mts": ref.advance_mts}
# M 4 and 20 are kernels of their own to compile (M is a constant of the compiled loop):
# the slow tier's; M 10 is their fast twin
SLOW = pytest.mark.slow


@pytest.mark.parametrize("integrator", list(TWINS))
@pytest.mark.parametrize("M,L_x", [(10, 0.5), pytest.param(4, 1.5, marks=SLOW),
                                   pytest.param(20, 3.0, marks=SLOW)])
def test_kernel_equals_numpy_twin_with_statistics(M, L_x, integrator):
    cfg = ModelConfig(L_x=L_x, integrator=integrator, drag_every=M, a0=0.02, C_sd=0.1)
    k, _ = solve_dispersion(cfg)
    chain = FloeChain(cfg, k)
    a = cfg.a0 * np.linspace(1.0, 0.6, cfg.n_floes)
    chain.run(a, 2400)                               # develop contacts first
    x, u, acc, af, ic = _twin_state(chain)
    istep = chain.istep
    n = 400
    st = np.zeros((K.N_STATS, cfg.n_floes))
    chain.run(a, n, st)
    st_ref = np.zeros_like(st)
    TWINS[integrator](x, u, acc, af, ic, a, chain.x0, istep, n, chain.P, chain.opts,
                      chain.cxi, chain.sxi, st_ref)
    assert np.any(st[K.ST_CONTACT] > 0), "no contact exercised"
    assert np.any(st[K.ST_CONTACT, :-1] == 0), "every pair sub-stepped: no free floe"
    np.testing.assert_allclose(chain.x, x, rtol=0, atol=1e-11)
    np.testing.assert_allclose(chain.u, u, rtol=0, atol=1e-9)
    assert np.array_equal(chain.in_contact, ic)
    np.testing.assert_array_equal(st[K.ST_CONTACT], st_ref[K.ST_CONTACT])
    np.testing.assert_array_equal(st[K.ST_COLL], st_ref[K.ST_COLL])
    for row, atol in ((K.ST_X, 1e-9), (K.ST_GAP, 1e-9)):
        np.testing.assert_allclose(st[row], st_ref[row], rtol=0, atol=atol)
    for row in (K.ST_FW, K.ST_FD, K.ST_FC, K.ST_S3):
        np.testing.assert_allclose(st[row], st_ref[row], rtol=1e-7,
                                   atol=1e-9 * np.abs(st_ref[row]).max())


@pytest.mark.parametrize("integrator", list(TWINS))
def test_a_collision_pushed_on_into_a_free_floe_is_taken_again(integrator):
    """Floe 1 hits floe 2 at rest, which is pushed into floe 3 within the same outer step:
    pair (2, 3) is free when the step starts (both at rest, its gap open; floe 3 is no
    edge floe, which are always sub-stepped), so the kernel must notice the gap closing
    and sub-step them together. Against the twin (every floe sub-stepped); a kernel that
    does not take the step again fails this (checked by disabling it)."""
    cfg = collision_config(L_sheet=2.5, integrator=integrator, drag_every=20, eps=0.8)
    chain = FloeChain(cfg, 1.0)
    a = np.zeros(5)
    L = cfg.L_x
    gaps = np.array([2e-4, 3e-4, 1e-2, 1e-2])
    chain.x0[:] = chain.x[:] = 0.25 + np.concatenate([[0.0], np.cumsum(L + gaps)])
    chain.u[:] = [0.3, 0.0, 0.0, 0.0, 0.0]
    chain.run(a, 0)                                   # the first evaluation
    x, u, acc, af, ic = _twin_state(chain)
    chain.run(a, 200)
    TWINS[integrator](x, u, acc, af, ic, a, chain.x0, 0, 200, chain.P, chain.opts,
                      chain.cxi, chain.sxi)
    assert chain.x[2] - chain.x0[2] > 1e-3, "the push did not reach floe 3"
    np.testing.assert_allclose(chain.x, x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(chain.u, u, rtol=0, atol=1e-10)


@pytest.mark.parametrize("integrator", list(TWINS))
@pytest.mark.parametrize("M", [pytest.param(4, marks=SLOW), 10, pytest.param(20, marks=SLOW)])
def test_restitution_table_at_every_outer_step(M, integrator):
    for eps, expected in zip((0.2, 0.4, 0.6, 0.8), TABLE, strict=True):
        cfg = collision_config(eps=eps, integrator=integrator, drag_every=M)
        e, _, _ = two_floe_collision(cfg, chunk=M)
        assert e == pytest.approx(expected, abs=0.01), (M, eps)


@pytest.mark.parametrize("integrator", list(TWINS))
@pytest.mark.parametrize("M", [pytest.param(4, marks=SLOW), 10])
def test_elastic_collision_energy_as_the_every_step_integrator(M, integrator):
    """eps = 1: the inner steps are the predictor integrator's, so KE after / before is
    that of the every-step loop (1 + 3.0e-4 at dt 1e-3) to rounding."""
    _, ke_step, _ = two_floe_collision(collision_config(eps=1.0), chunk=1)
    _, ke, _ = two_floe_collision(collision_config(eps=1.0, integrator=integrator,
                                                   drag_every=M), chunk=M)
    assert abs(ke_step - 1.0) < 1e-3
    assert ke == pytest.approx(ke_step, abs=1e-9)


@pytest.mark.parametrize("integrator", list(TWINS))
def test_replicas_do_not_see_each_other(integrator):
    cfg = ModelConfig(L_x=1.5, integrator=integrator, drag_every=10, replicas=3)
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg))
    a = cfg.a0 * np.linspace(1.0, 0.5, cfg.n_floes)
    a3 = np.stack([a, 0.9 * a, 1.1 * a])
    ens = FloeChain(cfg, k, x0)
    st = np.zeros((K.N_STATS, 3, cfg.n_floes))
    ens.run(a3, 1500)
    ens.run(a3, 700, st)
    ens.run(0.95 * a3 * np.array([[1.0], [0.0], [1.0]]) + a3 * np.array([[0], [1], [0]]), 300)
    for r in range(3):
        one = FloeChain(cfg, k, x0[r])
        s1 = np.zeros((K.N_STATS, cfg.n_floes))
        one.run(a3[r], 1500)
        one.run(a3[r], 700, s1)
        one.run(a3[r] if r == 1 else 0.95 * a3[r], 300)
        assert np.array_equal(one.x, ens.x[r]) and np.array_equal(one.u, ens.u[r])
        assert np.array_equal(s1, st[:, r, :])
    assert np.any(np.diff(ens.x, axis=1) - cfg.L_x < 0), "no contact exercised"


def test_steps_off_the_outer_clock_are_refused():
    cfg = ModelConfig(integrator="respa", drag_every=10)
    chain = FloeChain(cfg, solve_dispersion(cfg)[0])
    with pytest.raises(ValueError, match="multiples"):
        chain.run(np.full(cfg.n_floes, cfg.a0), 15)
