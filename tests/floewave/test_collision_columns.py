"""W_c of the time-mean gaps and the ice-wide collision statistics (floewave.collision_stats,
issue 23): hand-built replica records with known answers, and a small real point."""
from __future__ import annotations

import math

import numpy as np
import pytest

from floewave import ModelConfig
from floewave.collision_stats import (
    GAP_AND_COLLISION_FIELDS,
    collision_statistics,
    gap_zone_width,
)
from floewave.iteration.estimate import Records, estimate_point

#: 12 floes of 0.5 m (11 pairs); the compact-zone rule: 3 pairs spanning >= 1.5 m, no bridge
CFG = ModelConfig(L_x=0.5, L_y=10.0, L_sheet=6.0, T=1.5, nT=2, C_sd=0.05, rho_w=1000.0,
                  compact_min_pairs=3, compact_min_length=1.5, compact_bridge=0)
N = 12
X = 0.25 + 0.5 * np.arange(N)          # touching floes: the right end of floe i at 0.5 (i + 1)
OPEN, SHUT = 2e-3, 1e-5


def gaps(first_compact: int) -> np.ndarray:
    """Per-pair gaps, compact from pair ``first_compact`` on, with the trailing NaN."""
    g = np.full(N, np.nan)
    g[:N - 1] = OPEN
    g[first_compact:N - 1] = SHUT
    return g


def test_w_c_gap_of_time_mean_gaps_differs_from_the_per_window_mean():
    """Two windows of one replica: compact from pair 3 in one, from pair 7 in the other.
    Per window W_c = 2.0 and 4.0 m (mean 3.0); the time-mean gaps of pairs 3..6 are
    (OPEN + SHUT) / 2 = 1e-3 m > 1e-4 m, so the averaged gaps are compact from pair 7 only:
    W_c_gap = 4.0 m, 1 m above the per-window mean."""
    from floewave.collision_stats import zone_of
    w1, w2 = gaps(3), gaps(7)
    per_window = [zone_of(CFG, X, g).W_c for g in (w1, w2)]
    assert per_window == [2.0, 4.0]
    W, se, per_replica = gap_zone_width(CFG, X[None], ((w1 + w2) / 2)[None])
    assert W == 4.0 and per_replica.tolist() == [4.0]
    assert math.isnan(se)                              # one replica with a compact zone


def test_w_c_gap_mean_and_se_over_replicas_with_a_compact_zone():
    x = np.tile(X, (3, 1))
    g = np.array([gaps(3), gaps(5), np.full(N, OPEN)])  # W_c 2.0, 3.0 and none
    W, se, per = gap_zone_width(CFG, x, g)
    assert np.isnan(per[2]) and per[:2].tolist() == [2.0, 3.0]
    assert W == pytest.approx(2.5)
    assert se == pytest.approx(np.std([2.0, 3.0], ddof=1) / math.sqrt(2))   # = 0.5


def _profiles(cf, coll, s3):
    return {"contact_fraction": np.asarray(cf, float), "collisions": np.asarray(coll, float),
            "s3_mean": np.asarray(s3, float)}


def test_collision_statistics_hand_computed():
    """Two replicas of 3 floes (2 pairs), nT = 2 periods of T = 1.5 s (3 s windows).
    Replica 0: contact 0.2, 0.4; onsets 6, 2 per window; <|u|^3> 1e-4 on every floe.
    Replica 1: contact 0.1, 0.3; onsets 3, 1; <|u|^3> 2e-4."""
    nan = np.nan
    prof = _profiles([[0.2, 0.4, nan], [0.1, 0.3, nan]],
                     [[6, 2, nan], [3, 1, nan]],
                     [[1e-4] * 3, [2e-4] * 3])
    out = collision_statistics(CFG, prof)
    # contact fraction: replica means 0.3, 0.2 -> 0.25, SE of the mean 0.05
    assert out["contact_fraction_mean"] == pytest.approx(0.25)
    assert out["contact_fraction_mean_stderr"] == pytest.approx(0.05)
    # rate per pair per period: (6 + 2) / 2 / 2 = 2.0 and (3 + 1) / 2 / 2 = 1.0
    assert out["collision_rate"] == pytest.approx(1.5)
    assert out["collision_rate_stderr"] == pytest.approx(0.5)
    # power [W]: rho_w C_sd <|u|^3> L_x L_y per floe x 3 floes = 1000 * 0.05 * 1e-4 * 5 * 3
    P = np.array([0.075, 0.15])
    # collisions per second over the ice: 8 / 3 s and 4 / 3 s
    F = np.array([8 / 3, 4 / 3])
    assert out["dissipation_per_collision"] == pytest.approx(P.sum() / F.sum())  # 0.05625 J
    loo = np.array([P[1] / F[1], P[0] / F[0]])
    assert out["dissipation_per_collision_stderr"] == pytest.approx(
        math.sqrt(0.5 * ((loo - loo.mean()) ** 2).sum()))
    # one replica: the values, NaN standard errors
    one = collision_statistics(CFG, {k: v[:1] for k, v in prof.items()})
    assert one["collision_rate"] == pytest.approx(2.0)
    assert one["dissipation_per_collision"] == pytest.approx(0.075 / (8 / 3))
    assert all(math.isnan(one[k]) for k in one if k.endswith("_stderr"))


def test_no_collision_and_confined_give_nan():
    prof = _profiles([[0.0, 0.0, np.nan]] * 2, [[0, 0, np.nan]] * 2, [[1e-4] * 3] * 2)
    out = collision_statistics(CFG, prof)
    assert out["collision_rate"] == 0.0 and math.isnan(out["dissipation_per_collision"])
    fixed = collision_statistics(CFG.replace(confined=True), prof)
    assert all(math.isnan(v) for v in fixed.values())


def test_estimate_point_keeps_w_c_and_adds_w_c_gap():
    """Through estimate_point: W_c is the per-window mean (3.0 m), W_c_gap the time-mean
    gaps' (4.0 m); the collision columns come from the same records."""
    J, R = 2, 1
    g = np.array([[gaps(3)], [gaps(7)]])                         # (J, R, N)
    prof = {"x_mean": X[None], "gap_mean": g.mean(axis=0), "s3_mean": np.full((R, N), 1e-4),
            "contact_fraction": np.full((R, N), 0.5), "collisions": np.full((R, N), 4.0),
            "F_w_mean": np.ones((R, N)), "F_c_mean": np.ones((R, N)),
            "F_d_mean": np.ones((R, N))}
    rec = Records(S=np.full((J, R, N), -5e-3), a_new=np.full((J, R, N), 0.01), profiles=prof,
                  W_c=np.array([[2.0], [4.0]]), compact_end=np.array([[6.0], [6.0]]),
                  layouts=[["edge"], ["edge"]])
    est = estimate_point(CFG, rec, c_g=1.0, k=2.0)
    assert est.W_c == 3.0 and est.W_c_gap == 4.0
    assert est.collision_rate == pytest.approx(4.0 / 2)
    assert set(GAP_AND_COLLISION_FIELDS) <= set(est.outputs())


def test_columns_finite_on_a_small_real_point():
    """A small ensemble point (3 replicas of 18 floes): every new column is finite and in
    range; W_c is what it was (the same rule per window)."""
    from floewave import run_point
    cfg = ModelConfig(L_sheet=9.0, L_x=0.5, T=1.2, a0=0.02, n0=2, nT=1, max_iterations=3,
                      noise_window=2, n_average=2, replicas=3, placement="random", seed=4)
    res = run_point(cfg)
    for name in ("contact_fraction_mean", "collision_rate", "dissipation_per_collision"):
        assert math.isfinite(getattr(res, name)), name
        assert math.isfinite(getattr(res, name + "_stderr")), name
    assert 0.0 <= res.contact_fraction_mean <= 1.0
    assert res.collision_rate > 0 and res.dissipation_per_collision > 0
    # the stored mean profiles agree with the columns
    assert res.contact_fraction_mean == pytest.approx(np.nanmean(res.contact_fraction[:-1]))
    assert res.collision_rate == pytest.approx(np.nanmean(res.collisions[:-1]) / cfg.nT)
    W, _, _ = gap_zone_width(cfg, res.x_mean_replicas, res.gap_mean_replicas)
    assert (W == res.W_c_gap) or (math.isnan(W) and math.isnan(res.W_c_gap))
