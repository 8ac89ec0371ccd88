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
