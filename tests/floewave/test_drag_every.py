"""``drag_every``: the drag and dissipation sums evaluated every K steps and held in between
(multiple time stepping, :mod:`floewave._kernels`)."""
import numpy as np
import pytest

from floewave import ModelConfig, solve_dispersion
from floewave import _kernels as K
from floewave.config import ConfigError, InvalidPointError
from floewave.ensemble import initial_positions
from floewave.model import FloeChain


def _spun(opts: dict):
    """A two-replica chain spun up for two periods, its k, x0 and amplitudes."""
    base = ModelConfig(replicas=2, **opts)
    k, _ = solve_dispersion(base)
    x0 = np.array(initial_positions(base))
    a = base.a0 * np.linspace(1.0, 0.6, base.n_floes)
    spun = FloeChain(base, k, x0)
    spun.run(a, 2 * base.n_t)
    return base, k, x0, a, spun


def _continue(base, k, x0, a, spun, drag_every: int, steps: int):
    """``steps`` more steps from the spun-up state with ``drag_every``: (x, u, S3 sums)."""
    ch = FloeChain(base.replace(drag_every=drag_every), k, x0)
    ch.x[:], ch.u[:], ch.in_contact[:] = spun.x, spun.u, spun.in_contact
    ch.istep = spun.istep
    st = np.zeros((K.N_STATS,) + x0.shape)
    ch.run(a, steps, st)
    return ch.x.copy(), ch.u.copy(), st[K.ST_S3]


@pytest.mark.parametrize("opts", [dict(L_x=1.5, L_sheet=3.0),
                                  dict(L_x=0.5, L_sheet=1.0, dispersion="ow")])
def test_held_drag_is_second_order_in_the_hold(opts):
    """The held drag is evaluated at the centre of the K steps it holds (midpoint rule), so
    over a stretch without contacts its error per unit time is O((K^2 - 1) dt^2): from one
    state, 400 steps with K = 2, 4, 8 against K = 1 differ in velocity in the ratios
    15 / 3 = 5 and 63 / 15 = 4.2 (observed 4.3-4.9 and 3.8-4.1). A zero-order hold at the
    first step (first order, ratios 3 and 2.3) fails this."""
    cfg = ModelConfig(d_f=0.5, C_sd=0.2, replicas=1, **opts)       # two floes, apart
    k, _ = solve_dispersion(cfg)
    a = np.full(cfg.n_floes, cfg.a0)
    spun = FloeChain(cfg, k)
    spun.run(a, cfg.n_t // 3)
    u = {}
    for K_ in (1, 2, 4, 8):
        ch = FloeChain(cfg.replace(drag_every=K_), k)
        ch.x[:], ch.u[:], ch.istep = spun.x, spun.u, spun.istep
        ch.run(a, 400)
        assert np.all(np.diff(ch.x) - cfg.L_x > 0), "a contact: not a smooth stretch"
        u[K_] = ch.u.copy()
    e = {K_: np.max(np.abs(u[K_] - u[1])) for K_ in (2, 4, 8)}
    assert 4.0 <= e[4] / e[2] <= 5.5
    assert 3.5 <= e[8] / e[4] <= 4.6
    assert e[4] < 2e-6          # velocities are ~0.05 m/s


def test_dissipation_sum_stands_for_the_steps_it_holds():
    """Each evaluation's |u_rel|^3 sum is added K times over (the window statistics are
    per-step sums): over one period the K = 4 sum is the K = 1 sum within 1 % (a sample
    of every 4th step along a slightly different trajectory; measured 0.35 %), not a
    quarter of it."""
    base, k, x0, a, spun = _spun(dict(L_x=1.5))
    s1 = _continue(base, k, x0, a, spun, 1, base.n_t)[2]
    s4 = _continue(base, k, x0, a, spun, 4, base.n_t)[2]
    assert np.all(s1 > 0)
    assert np.max(np.abs(s4 / s1 - 1.0)) < 1e-2


def test_drag_every_one_is_the_every_step_kernel():
    """K = 1 evaluates every step: a loop built for K = 1 and the default options agree
    bit for bit (the kernel's arithmetic for K = 1 is that of the paper's every-step drag)."""
    cfg = ModelConfig(replicas=2, drag_every=1)
    assert K.kernel_options(K.kernel_params(cfg, 1.0), True).drag_every == 1
    base, k, x0, a, spun = _spun(dict(drag_every=1))
    x1, u1, s1 = _continue(base, k, x0, a, spun, 1, 500)
    x1b, u1b, s1b = _continue(base, k, x0, a, spun, 1, 500)
    assert np.array_equal(x1, x1b) and np.array_equal(s1, s1b)


@pytest.mark.parametrize("steps", [(1500, 700, 300), (1502, 701, 299)])
def test_replica_invariance_with_a_held_drag(steps):
    """Replica r's numbers do not depend on the others with K = 4, also when only one
    replica's amplitudes change (the others keep their acceleration *and* their held drag)
    and when the change falls inside a hold (step counts not multiples of K)."""
    cfg = ModelConfig(replicas=3, drag_every=4)
    k, _ = solve_dispersion(cfg)
    x0 = np.array(initial_positions(cfg))
    a = cfg.a0 * np.linspace(1.0, 0.5, cfg.n_floes)
    a3 = np.stack([a, 0.9 * a, 1.1 * a])
    b3 = a3.copy()
    b3[1] *= 0.95                          # only replica 1 gets new amplitudes
    n1, n2, n3 = steps
    ens = FloeChain(cfg, k, x0)
    st = np.zeros((K.N_STATS, 3, cfg.n_floes))
    ens.run(a3, n1)
    ens.run(a3, n2, st)
    ens.run(b3, n3, st)
    for r in range(3):
        one = FloeChain(cfg, k, x0[r])
        s1 = np.zeros((K.N_STATS, cfg.n_floes))
        one.run(a3[r], n1)
        one.run(a3[r], n2, s1)
        one.run(b3[r], n3, s1)
        assert np.array_equal(one.x, ens.x[r]) and np.array_equal(one.u, ens.u[r])
        assert np.array_equal(s1, st[:, r, :])
    assert np.any(np.diff(ens.x, axis=1) - cfg.L_x < 0), "no contact exercised"


def test_drag_every_must_divide_the_steps_of_a_period():
    with pytest.raises(ConfigError, match="drag_every"):
        ModelConfig(drag_every=0)
    with pytest.raises(InvalidPointError, match="drag_every = 2, or a T that is a multiple"
                                                " of 0.003 s"):
        ModelConfig(T=1.1, dt=1e-3, drag_every=3).check_physics()    # 1100 steps
    with pytest.raises(InvalidPointError, match="set drag_every = 2"):
        ModelConfig(T=1.25, dt=1e-3).check_physics()                  # the default, 4
    ModelConfig(T=1.1, dt=1e-3, drag_every=4).check_physics()
    ModelConfig(T=1.25, dt=1e-3, drag_every=5).check_physics()
