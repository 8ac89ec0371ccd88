"""The forces of eq. 8 as the time loop computes them (floewave._force_terms): each term
against its formula, and their sum against the numpy twin's (floewave._reference)."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from floewave import ModelConfig, solve_dispersion
from floewave import _force_terms as T
from floewave import _kernels as K
from floewave import _reference as ref
from floewave._contact import contact_law
from floewave.forces import wave_force
from floewave.model import FloeChain


def _chain(**kw):
    cfg = ModelConfig(**kw)
    k, _ = solve_dispersion(cfg)
    return cfg, k, FloeChain(cfg, k)


def test_wave_force_is_the_froude_krylov_formula():
    cfg, k, chain = _chain()
    for x, t in ((0.3, 0.0), (2.7, 0.41), (11.0, 1.3)):
        s = math.sin(k * x - cfg.omega * t)
        assert T.wave_force(cfg.a0, s, chain.P) == wave_force(cfg, k, cfg.a0, x, t)


def test_skin_drag_and_edge_spring_are_their_formulas():
    cfg, _, chain = _chain()
    dx = cfg.L_x / cfg.n_x
    assert T.skin_drag(0.37, chain.P) == pytest.approx(cfg.rho_w * cfg.C_sd * cfg.L_y * dx
                                                       * 0.37, rel=1e-15)
    assert T.edge_spring(1.25, 1.0, chain.P) == -cfg.k_s * 0.25


def test_contact_force_is_the_law_while_touching_and_zero_apart():
    _, _, chain = _chain()
    for contact in (K.CONTACT_HERTZ_DISK, K.CONTACT_LINEAR):
        for damping in (K.DAMPING_LIGGGHTS, K.DAMPING_EXACT):
            for clip in (0, 1):
                args = (chain.P, contact, damping, clip)
                assert T.contact_force(1e-4, -0.1, *args) == 0.0
                assert T.contact_force(0.0, -0.1, *args) == 0.0
                f = T.contact_force(-1e-4, -0.1, *args)
                assert f == contact_law(1e-4, -0.1, *args) and f > 0.0


@pytest.mark.parametrize("kw", [dict(), dict(contact="linear", damping="exact",
                                             clip_attraction=True)])
def test_eq8_forces_is_the_twins_sum(kw):
    """One chain at a state with overlapping pairs: eq8_forces (the drag sums from the
    kernel's pass) equals the twin's sum of the same terms to rounding, and flags the
    touching pairs."""
    cfg, k, chain = _chain(**kw)
    n = cfg.n_floes
    rng = np.random.default_rng(5)
    x = chain.x0 + rng.normal(0, 2e-3, n)
    v = rng.normal(0, 0.05, n)
    a = cfg.a0 * np.linspace(1.0, 0.6, n)
    wt = 0.7
    sc = K.new_scratch(n)
    idx = np.zeros(n, np.int64)
    T.skin_drag_sums(np.cos(k * x), np.sin(k * x), math.cos(wt), math.sin(wt), a, v, chain.P,
                     chain.cxi, chain.sxi, chain.mom, False, sc, idx, K.DRAG_QUADRATURE)
    F, Fc = np.zeros(n), np.zeros(n)
    in_contact = np.zeros(n, np.int8)
    o = chain.opts
    T.eq8_forces(F, Fc, x, v, a, chain.x0, sc, in_contact, np.zeros((K.N_STATS, 0)), n,
                 chain.P, o.contact, o.damping, o.clip, False, 1, True)
    want = ref.forces(x, v, a, chain.x0, wt, chain.P, o, chain.cxi, chain.sxi)
    gaps = np.diff(x) - cfg.L_x
    assert np.any(gaps < 0)
    np.testing.assert_array_equal(in_contact[:-1], (gaps < 0).astype(np.int8))
    np.testing.assert_allclose(F, want, rtol=1e-12, atol=1e-9 * np.max(np.abs(want)))


LOADS = """
import json, numpy as np
from floewave import ModelConfig, solve_dispersion
from floewave import _kernels as K
from floewave.model import FloeChain
cfg = ModelConfig(T=1.2)
k, _ = solve_dispersion(cfg)
ch = FloeChain(cfg, k)
a = np.full(cfg.n_floes, cfg.a0)
ch.run(a, 8)
ch.run(a, 8, np.zeros((K.N_STATS, cfg.n_floes)))
print(json.dumps([[sum(d.stats.cache_hits.values()), sum(d.stats.cache_misses.values())]
                  for d in (ch._spin, ch._average)]))
"""


@pytest.mark.slow  # two fresh interpreters, the first compiling with a cold cache
def test_a_new_process_loads_the_built_loops_from_the_cache(tmp_path):
    """The built time loop (a closure over numbers, calling the numba-inlined eq8_forces)
    is compiled by the first process and loaded, not compiled, by the next."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def run():
        out = subprocess.run([sys.executable, "-c", LOADS], env=env, check=True,
                             capture_output=True, text=True).stdout
        return json.loads(out.splitlines()[-1])

    assert run() == [[0, 1], [0, 1]]
    assert run() == [[1, 0], [1, 0]]
