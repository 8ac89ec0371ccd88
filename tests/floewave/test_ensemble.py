"""Ensembles (issue *ensemble*): arrangements, seeds, estimators and their standard errors.

The error bars' honesty against independent ensembles is measured by
``benchmarks/honesty.py`` (a benchmark: it takes minutes); here are the exact properties
the estimators must have and a short ensemble run end to end.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from floewave import ModelConfig, run_point
from floewave._march import march_amplitude, march_rows
from floewave.collision_stats import zone_of
from floewave.config import ConfigError
from floewave.ensemble import initial_positions
from floewave.errorbars import jackknife_se
from floewave.iteration.estimate import Records, estimate_point

SHORT = dict(L_x=1.5, T=1.2, a0=0.02, eps=0.8, dispersion="ep", n0=2, nT=1,
             max_iterations=4, noise_window=2, n_average=2, n0_warm=0, replicas=1,
             placement="uniform")


@pytest.mark.parametrize("d_f", [0.005, 0.05])
def test_random_placement_keeps_the_mean_gap_and_never_overlaps(d_f):
    cfg = ModelConfig(replicas=6, placement="random", d_f=d_f, seed=3)
    x = initial_positions(cfg)
    n = cfg.n_floes
    assert x.shape == (6, n)
    gaps = np.diff(x, axis=1) - cfg.L_x
    assert (gaps >= 0).all()
    np.testing.assert_allclose(gaps.mean(axis=1), d_f, rtol=1e-12)
    # the ice extent is the uniform arrangement's (the gaps sum to (N_f - 1) d_f)
    np.testing.assert_allclose(x[:, -1], cfg.L_x / 2 + (n - 1) * (cfg.L_x + d_f), rtol=1e-13)
    assert (x[:, 0] == cfg.L_x / 2).all()
    # the replicas differ, and their gaps are spread (exponential: sd about the mean)
    assert len({row.tobytes() for row in x}) == 6
    assert 0.6 < gaps.std() / d_f < 1.4


def test_replica_r_starts_the_same_whatever_R_and_the_seed_changes_it():
    base = dict(placement="random", seed=11)
    x4 = initial_positions(ModelConfig(replicas=4, **base))
    x9 = initial_positions(ModelConfig(replicas=9, **base))
    assert np.array_equal(x4, x9[:4])
    other = initial_positions(ModelConfig(replicas=4, placement="random", seed=12))
    assert not np.array_equal(other[1], x4[1])
    # and the arrangement follows the physics of the point, not only the seed
    y4 = initial_positions(ModelConfig(replicas=4, eps=0.4, **base))
    assert not np.array_equal(y4[1], x4[1])
    # bit for bit again from scratch
    assert np.array_equal(initial_positions(ModelConfig(replicas=4, **base)), x4)


def test_uniform_placement_is_the_papers_arrangement_perturbed_at_the_rounding_level():
    cfg = ModelConfig(replicas=4, placement="uniform", seed=1)
    x = initial_positions(cfg)
    uniform = cfg.L_x / 2 + np.arange(cfg.n_floes) * (cfg.L_x + cfg.d_f)
    assert np.array_equal(x[0], uniform)
    dev = np.abs(x[1:] - uniform).max()
    assert 0 < dev < 1e-6 * cfg.n_floes * cfg.d_f * 2
    # one replica: exactly the paper's model
    assert np.array_equal(initial_positions(ModelConfig(replicas=1, placement="uniform"))[0],
                          uniform)


def test_ensemble_fields_are_validated():
    for bad in (dict(replicas=0), dict(seed=-1), dict(placement="grid"),
                dict(coupling="avg"), dict(replicas=2.5)):
        with pytest.raises(ConfigError):
            ModelConfig(**bad)


def test_march_rows_is_eq20_row_by_row():
    """Every row is eq. 20 (and 21 with overwash) written out as a plain loop (to rounding:
    the loop here squares with ``**``), and the one-profile march is its row."""
    import math as m
    rng = np.random.default_rng(0)
    g, c_g, k = 9.81, 0.9, 3.0
    for overwash in (False, True):
        cfg = ModelConfig(overwash=overwash, a0=0.025)
        S = -rng.random((5, cfg.n_floes)) * 2e-4
        rows = march_rows(cfg, S, c_g, k)
        fac = cfg.L_x / (cfg.rho_w * g * c_g)
        for i in range(5):
            a = [m.sqrt(max(cfg.a0**2 + fac * S[i, 0], 0.0))]
            for j in range(1, cfg.n_floes):
                a2 = a[-1] ** 2 + fac * (S[i, j - 1] + S[i, j])
                if overwash:
                    a2 -= 3 * m.sqrt(g) * (cfg.c_ow * max(k * a[-1] - cfg.s_min, 0)) ** 2.5 / c_g
                a.append(m.sqrt(max(a2, 0.0)))
            np.testing.assert_allclose(rows[i], a, rtol=1e-14)
            assert np.array_equal(rows[i], march_amplitude(cfg, S[i], c_g, k))


def test_jackknife_of_a_mean_is_the_standard_error_of_the_mean():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(7, 3))
    loo = np.array([np.delete(v, r, axis=0).mean(axis=0) for r in range(7)])
    np.testing.assert_allclose(jackknife_se(loo), v.std(axis=0, ddof=1) / math.sqrt(7),
                               rtol=1e-12)
    assert np.isnan(jackknife_se(loo[:1])).all()


def _records(cfg, R, J, rng, none=()):
    """Hand-built records: in window j, replica r is compact from pair 10 + 2 r + j on
    (replicas in ``none``: collisional everywhere)."""
    n = cfg.n_floes
    xw = (cfg.L_x / 2 + np.arange(n) * (cfg.L_x + 1e-3)
          + rng.normal(0, 1e-4, (J, R, n)))
    gw = np.full((J, R, n), 1e-3)
    for j in range(J):
        for r in range(R):
            if r not in none:
                gw[j, r, 10 + 2 * r + j:] = 1e-5
    gw[..., -1] = np.nan
    zones = [[zone_of(cfg, xw[j, r], gw[j, r]) for r in range(R)] for j in range(J)]
    prof = {name: rng.random((R, n)) for name in ("s3_mean", "contact_fraction",
                                                    "collisions", "F_w_mean", "F_c_mean",
                                                    "F_d_mean")}
    prof.update(x_mean=xw.mean(axis=0), gap_mean=gw.mean(axis=0))
    S = -rng.random((J, R, n)) * 1e-4
    return Records(S, np.zeros((J, R, n)), prof,
                   np.array([[z.W_c for z in row] for row in zones]),
                   np.array([[z.compact_end for z in row] for row in zones]),
                   [[z.layout for z in row] for row in zones]), xw


def test_estimates_and_standard_errors_from_replica_records():
    cfg = ModelConfig(L_x=0.5, replicas=5, coupling="mean")
    rng = np.random.default_rng(2)
    rec, xw = _records(cfg, 5, 3, rng)
    est = estimate_point(cfg, rec, 0.9, 3.0)
    # W_c: the mean of the per-replica W_c, with the standard error of that mean
    W = est.W_c_replicas
    assert np.isfinite(W).all() and est.W_c_n == 5
    assert est.compact_zone == "edge"
    assert est.W_c == pytest.approx(W.mean(), rel=1e-12)
    assert est.W_c_stderr == pytest.approx(W.std(ddof=1) / math.sqrt(5), rel=1e-12)
    # a replica's W_c: the mean over its windows of the window's W_c, the right end of
    # floe 10 + 2 r + j in window j
    for r in range(5):
        want = np.mean([xw[j, r, 10 + 2 * r + j] + cfg.L_x / 2 for j in range(3)])
        assert W[r] == pytest.approx(want, rel=1e-12)
    # a: the average over iterations of the march of the replica-mean dissipation
    a = np.mean([march_amplitude(cfg, rec.S[j].mean(axis=0), 0.9, 3.0) for j in range(3)],
                axis=0)
    np.testing.assert_allclose(est.a, a, rtol=1e-13)
    assert np.isfinite(est.a_stderr).all() and (est.a_stderr > 0).all()
    for name in ("alpha_all", "alpha_exp", "alpha_edge", "alpha_inner"):
        assert np.isfinite(getattr(est, name)) and getattr(est, name + "_stderr") > 0, name
    assert est.a_end_stderr == est.a_stderr[-1]
    # profiles: replica means
    np.testing.assert_allclose(est.F_w_mean, rec.profiles["F_w_mean"].mean(axis=0))


def test_independent_coupling_standard_error_of_a_is_that_of_the_replica_mean():
    cfg = ModelConfig(L_x=0.5, replicas=4, coupling="independent")
    rng = np.random.default_rng(3)
    rec, _ = _records(cfg, 4, 2, rng)
    rec.a_new[...] = rng.random(rec.a_new.shape) * 0.01
    est = estimate_point(cfg, rec, 0.9, 3.0)
    per = rec.a_new.mean(axis=0)                    # each replica's average
    np.testing.assert_allclose(est.a, per.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(est.a_stderr, per.std(axis=0, ddof=1) / 2, rtol=1e-10)


def test_replicas_without_a_compact_zone_do_not_enter_W_c():
    cfg = ModelConfig(L_x=0.5, replicas=5)
    rec, _ = _records(cfg, 5, 2, np.random.default_rng(4), none=(3,))
    est = estimate_point(cfg, rec, 0.9, 3.0)
    W = est.W_c_replicas
    assert np.isnan(W[3]) and est.W_c_n == 4
    assert est.W_c == pytest.approx(np.nanmean(W), rel=1e-12)
    # most replicas without a zone: the point has none
    rec, _ = _records(cfg, 5, 2, np.random.default_rng(4), none=(0, 1, 2))
    est = estimate_point(cfg, rec, 0.9, 3.0)
    assert est.compact_zone == "none" and math.isnan(est.W_c)
    assert math.isnan(est.alpha_inner) and est.W_c_n == 0


def test_one_replica_mean_and_independent_coupling_agree_bit_for_bit():
    a = run_point(ModelConfig(**SHORT, coupling="mean"))
    b = run_point(ModelConfig(**SHORT, coupling="independent"))
    for name in ("a", "a_stderr", "x_mean", "gap_mean", "S_sd", "residual_history"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.replicas == 1 and math.isnan(a.W_c_stderr) and math.isnan(a.alpha_all_stderr)


def test_short_ensemble_end_to_end():
    cfg = ModelConfig(**{**SHORT, "replicas": 3, "placement": "random", "seed": 5})
    r = run_point(cfg)
    one = run_point(ModelConfig(**SHORT))
    assert r.replicas == 3
    assert r.floe_steps == 3 * one.floe_steps * r.iterations // one.iterations
    assert r.W_c_replicas.shape == (3,) and r.compact_end_replicas.shape == (3,)
    for name in ("x_mean_replicas", "gap_mean_replicas", "S_sd_replicas"):
        assert getattr(r, name).shape == (3, cfg.n_floes), name
    # the profiles are replica means
    np.testing.assert_allclose(r.S_sd, r.S_sd_replicas.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(r.gap_mean[:-1], r.gap_mean_replicas.mean(axis=0)[:-1],
                               rtol=1e-12)
    assert np.isfinite(r.a_stderr).all() and (r.a_stderr > 0).any()
    assert np.isfinite(r.alpha_all_stderr) and r.alpha_all_stderr > 0
    # the replicas ran different trajectories
    assert not np.array_equal(r.x_mean_replicas[0], r.x_mean_replicas[1])
    # reproducible
    again = run_point(cfg)
    assert np.array_equal(again.a, r.a) and np.array_equal(again.a_stderr, r.a_stderr)


@pytest.mark.parametrize("changes", [dict(d_f=0.0), dict(L_sheet=3.0, L_x=1.5)])
def test_replicas_that_could_not_differ_run_as_one_chain(changes):
    """d_f = 0 (every arrangement touching) or two floes (the one gap is d_f): identical
    replicas would report a zero error bar; one chain runs, with the single trajectory's
    iteration standard error."""
    cfg = ModelConfig(**{**SHORT, "replicas": 4, "placement": "random", **changes})
    assert cfg.n_chains == 1
    r = run_point(cfg)
    assert r.replicas == 1 and r.floe_steps == cfg.floe_steps_of(r.iterations)
    assert math.isnan(r.alpha_all_stderr) and not np.all(r.a_stderr == 0)


def test_a_layout_that_flips_without_one_replica_has_no_zone_error_bars():
    """R = 2, one replica compact, one not: the layout is a tie (edge); leaving out the
    compact replica gives none, so the zone fits have no jackknife error bar (NaN)."""
    cfg = ModelConfig(L_x=0.5, replicas=2, coupling="mean")
    rec, _ = _records(cfg, 2, 2, np.random.default_rng(5), none=(1,))
    est = estimate_point(cfg, rec, 0.9, 3.0)
    assert est.compact_zone == "edge" and est.W_c_n == 1
    assert math.isnan(est.alpha_edge_stderr) and math.isnan(est.alpha_inner_stderr)
    assert np.isfinite(est.alpha_all_stderr)


def test_confined_runs_one_chain_whatever_R():
    cfg = ModelConfig(L_x=1.5, confined=True, d_f=0.0, replicas=4, placement="random")
    r = run_point(cfg)
    assert r.replicas == 1
    assert r.floe_steps == cfg.replace(replicas=1).floe_steps_of(r.iterations)


def test_independent_replica_r_gives_the_same_numbers_whatever_R():
    """With coupling "independent" each replica iterates its own a(x) from its own
    arrangement (seeded without R) in the one ensemble kernel: the first two replicas of an
    ensemble of 3 are bit for bit those of an ensemble of 2 (same iteration count here:
    max_iterations reached before any noise floor). Under coupling "mean" a replica's
    amplitudes are the replica mean, which depends on R by design."""
    base = dict(L_x=1.5, T=1.2, a0=0.02, d_f=0.01, coupling="independent", n0=2, nT=1,
                max_iterations=3, noise_window=10, delta=1e-12)
    two = run_point(ModelConfig(replicas=2, **base))
    three = run_point(ModelConfig(replicas=3, **base))
    assert two.iterations == three.iterations == 3
    for name in ("S_sd_replicas", "x_mean_replicas", "gap_mean_replicas"):
        assert np.array_equal(getattr(two, name), getattr(three, name)[:2], equal_nan=True), name
    assert not np.array_equal(three.S_sd_replicas[0], three.S_sd_replicas[1])
