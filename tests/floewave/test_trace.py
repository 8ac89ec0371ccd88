"""floewave.trace: the opt-in time series of selected floes (the paper's Fig. 4)."""
import json
import math

import numpy as np
import pytest

from floewave import ModelConfig
from floewave import _kernels as K
from floewave._reference import forces as reference_forces
from floewave.chain import FloeChain
from floewave.cli import main
from floewave.forces import cell_offsets
from floewave.iteration.window import Window, dissipation
from floewave.trace import floes_at, instantaneous, trace_point

SMALL = dict(L_sheet=6.0, n0=1, nT=1, max_iterations=3)


def test_time_mean_of_the_trace_is_the_kernels_eq_19_average():
    """Sampled every step over one period, the mean instantaneous S_sd equals the kernel's
    own eq. 19 statistic of the same window to O(dt acc) (end-of-step vs predicted u), with
    the kernel's drag evaluated every step (drag_every = 1: the default's held drag samples
    eq. 19 every 4th step, tests/floewave/test_drag_every.py)."""
    cfg = ModelConfig(**SMALL, drag_every=1)
    from floewave import solve_dispersion

    k = solve_dispersion(cfg)[0]
    a = cfg.a0 * np.linspace(1.0, 0.6, cfg.n_floes)
    one, two = FloeChain(cfg, k), FloeChain(cfg, k)
    for chain in (one, two):
        chain.run(a, 2 * cfg.n_t)
    stats = K.new_stats(cfg.n_floes)
    one.run(a, cfg.n_t, stats)
    kernel = dissipation(cfg, Window(cfg, stats, cfg.n_t, one.x0).s3_mean)
    xi = cell_offsets(cfg)
    total = np.zeros(cfg.n_floes)
    for _ in range(cfg.n_t):
        two.run(a, 1)
        S, _ = instantaneous(two.x, two.u, a, 2 * math.pi / cfg.n_t * (two.istep % cfg.n_t),
                             two.P, cfg, xi)
        total += S
    np.testing.assert_allclose(total / cfg.n_t, kernel, rtol=cfg.dt / 1.0)   # O(dt), dt in s
    assert np.all(kernel < 0)


def test_contact_force_is_the_reference_steps_contact_term():
    """With no waves, drag or springs the reference step's total force is the contact
    force alone: F_c of the trace must equal it floe by floe."""
    cfg = ModelConfig(**SMALL, C_sd=0.0, k_s=0.0)
    chain = FloeChain(cfg, 2.0)
    rng = np.random.default_rng(3)
    x = chain.x0 + rng.normal(0, 2e-3, cfg.n_floes)  # some pairs overlap
    u = rng.normal(0, 0.05, cfg.n_floes)
    a = np.zeros(cfg.n_floes)
    _, F_c = instantaneous(x, u, a, 0.3, chain.P, cfg, cell_offsets(cfg))
    ref = reference_forces(x, u, a, chain.x0, 0.3, chain.P, chain.opts, chain.cxi,
                           chain.sxi)
    assert np.count_nonzero(F_c) > 0
    np.testing.assert_allclose(F_c, ref, rtol=1e-12, atol=1e-9)


def test_trace_point_records_the_chosen_floes():
    cfg = ModelConfig(**SMALL)
    from floewave import run_point

    r = run_point(cfg)
    tr = trace_point(cfg, r, distances=(0.0, 3.0, 100.0), every=20, periods=2, spin_up=1)
    assert tr.floes.tolist() == [0, int(np.argmin(np.abs(r.x_mean - 3.0))), cfg.n_floes - 1]
    assert tr.S_sd.shape == (2 * cfg.n_t // 20, 3) == tr.F_c.shape == tr.x.shape
    np.testing.assert_allclose(np.diff(tr.t), 20 * cfg.dt, rtol=1e-9)
    assert np.all(tr.S_sd <= 0) and np.all(np.isfinite(tr.u))
    json.dumps(tr.to_dict())
    assert floes_at(np.array([0.25, 0.75, 1.25]), [0.7]).tolist() == [1]


def test_floewave_run_trace_writes_json_and_fig4(run_main, tmp_path):
    pytest.importorskip("matplotlib")
    p = run_main(main, ["run", *[f"--set={k}={v}" for k, v in SMALL.items()], "--trace", "1,4",
                   "--trace-every", "50", "--json", "o.json", "--trace-plot", "fig4.png"],
            tmp_path)
    assert p.returncode == 0, p.stderr
    assert "trace: floes" in p.stdout
    data = json.loads((tmp_path / "o.json").read_text())
    assert len(data["trace"]["t"]) == ModelConfig().n_t // 50  # nT = 1 period of n_t steps
    assert data["trace"]["units"]["S_sd"] == "W m-2"
    assert (tmp_path / "fig4.png").stat().st_size > 5000


def test_trace_plot_without_trace_is_bad_input(run_main, tmp_path):
    p = run_main(main, ["run", "--trace-plot", "f.png"], tmp_path)
    assert p.returncode == 2 and "--trace-plot needs --trace" in p.stderr
