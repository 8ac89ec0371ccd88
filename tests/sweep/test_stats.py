"""sweep.collision_stats / alpha_omega on a hand-built store whose answers are known.

The store is computed by ``sweep.testing:power_point`` (rates set by formula, see its
docstring), so every statistic below has an exact expected value.
"""
import math

import numpy as np
import pandas as pd
import pytest

from sweep import alpha_omega, collision_stats, derived, load
from sweep.testing import POWER_M

TOML = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.0]
T = [1.0, 1.5, 2.0]
eps = [0.2, 0.8]
d_f = [0.005, 0.02]
dispersion = ["ep", "ml"]
"""


@pytest.fixture(scope="module")
def table(power_store):
    return load(power_store(TOML))


def test_derived_columns_per_point(table):
    d = derived(table)
    assert len(d) == 48
    np.testing.assert_allclose(d["L_sheet"], 6.0)
    np.testing.assert_allclose(d["omega"], 2 * np.pi / d["T"])
    # W_c = 10 eps L_x where that lies inside the 6 m sheet, else no compact zone (NaN)
    none = (d["eps"] == 0.8) & (d["L_x"] == 1.0)
    assert (d["no_compact_zone"] == none).all()
    assert (d["compact_zone"] == np.where(none, "none", "edge")).all()
    np.testing.assert_allclose(d["W_c_rel"], np.where(none, np.nan, 10 * d["eps"] * d["L_x"]
                                                      / 6.0))
    np.testing.assert_allclose(d["inner_over_c"], np.where(none, np.nan, 1 + d["eps"]),
                               rtol=1e-12)
    np.testing.assert_allclose(d["edge_over_inner"],
                               np.where(none, np.nan, 2 + 100 * d["d_f"]), rtol=1e-12)
    assert (d["prefers_n2"] == (d["eps"] < 0.5)).all()
    # an explicit sheet length overrides config_json
    np.testing.assert_allclose(derived(table, L_sheet=12.0)["W_c_rel"], d["W_c_rel"] / 2)


def test_collision_stats_by_eps(table):
    s = collision_stats(table, by="eps").set_index("eps")
    assert list(s.index) == [0.2, 0.8]
    for col in ("n_points", "n_not_converged", "n_edge", "n_no_compact", "n_W_c", "W_c_mean",
                "W_c_std", "W_c_rel_mean", "frac_no_compact_zone", "inner_over_c_mean",
                "inner_over_c_median",
                "edge_over_inner_mean", "frac_prefers_n2", "fit_ratio_median"):
        assert col in s.columns, col
    assert s.loc[0.2, "n_points"] == 24 and s.loc[0.8, "n_points"] == 24
    assert s.loc[0.2, "n_not_converged"] == 0 and s.loc[0.8, "n_not_converged"] == 24
    assert s.loc[0.2, "W_c_mean"] == pytest.approx(1.5)       # mean of 2 * 0.5, 2 * 1.0
    # eps 0.8: W_c 4 m (L_x 0.5); at L_x 1.0 no compact zone: no W_c, counted apart
    assert s.loc[0.8, "W_c_mean"] == pytest.approx(4.0)
    assert s.loc[0.8, "n_W_c"] == 12 and s.loc[0.2, "n_W_c"] == 24
    assert s.loc[0.8, "n_no_compact"] == 12 and s.loc[0.8, "n_edge"] == 12
    assert s.loc[0.8, "W_c_rel_mean"] == pytest.approx(4.0 / 6.0)
    assert s.loc[0.8, "frac_no_compact_zone"] == pytest.approx(0.5)
    assert s.loc[0.8, "n_inner_over_c"] == 12
    # only the paper's layout: the same here (every point with a zone is "edge")
    e = collision_stats(table, by="eps", layouts=["edge"]).set_index("eps")
    assert e.loc[0.8, "n_points"] == 12 and e.loc[0.8, "W_c_mean"] == pytest.approx(4.0)
    assert s.loc[0.2, "inner_over_c_mean"] == pytest.approx(1.2)
    assert s.loc[0.8, "inner_over_c_median"] == pytest.approx(1.8)
    assert s.loc[0.2, "edge_over_inner_mean"] == pytest.approx(3.25)   # (2.5 + 4) / 2
    assert s.loc[0.2, "frac_prefers_n2"] == 1.0 and s.loc[0.8, "frac_prefers_n2"] == 0.0
    assert s.loc[0.2, "fit_ratio_median"] == pytest.approx(1.2)
    assert s.loc[0.8, "fit_ratio_median"] == pytest.approx(0.5)


def test_collision_stats_grouped_by_two_and_by_none(table):
    s = collision_stats(table, by=["L_x", "dispersion"])
    assert len(s) == 4 and set(s["n_points"]) == {12}
    one = s[(s["L_x"] == 1.0) & (s["dispersion"] == "ml")].iloc[0]
    assert one["W_c_mean"] == pytest.approx(2.0)       # eps 0.8 has no compact zone there
    assert one["n_W_c"] == 6 and one["n_no_compact"] == 6
    total = collision_stats(table)
    assert len(total) == 1 and total["n_points"].iloc[0] == 48
    assert "eps" not in total.columns
    with pytest.raises(KeyError, match="nope"):
        collision_stats(table, by="nope")


def test_failed_and_invalid_points_are_left_out(table):
    bad = table.iloc[:2].copy()
    bad["status"] = ["failed", "invalid"]
    bad[["W_c", "alpha_inner", "alpha_c"]] = np.nan
    mixed = pd.concat([table, bad], ignore_index=True)
    assert collision_stats(mixed)["n_points"].iloc[0] == 48
    assert len(derived(mixed)) == 48


def test_alpha_omega_recovers_the_exponents(table):
    r = alpha_omega(table)
    assert list(r.columns[:5]) == ["L_x", "a0", "C_sd", "eps", "d_f"]
    assert len(r) == 2 * 2 * 2 * 2                      # L_x x eps x d_f x dispersion
    none = (r["L_x"] == 1.0) & (r["eps"] == 0.8)        # no compact zone: no alpha_inner
    assert r.loc[none, "m"].isna().all() and (r.loc[none, "n_dropped_no_zone"] == 3).all()
    assert (r["n_dropped_nan"] == 0).all()
    assert (r.loc[none, "n_points"] == 0).all()
    r = r[~none]
    for disp, m in POWER_M.items():
        sub = r[r["dispersion"] == disp]
        if sub.empty:
            continue
        np.testing.assert_allclose(sub["m"], m, atol=1e-10)
        np.testing.assert_allclose(sub["m_c"], m, atol=1e-10)    # alpha_c = alpha / (1+eps)
        assert (sub["rms_log_resid"] < 1e-10).all()
        assert (sub["n_periods"] == 3).all() and (sub["n_dropped"] == 0).all()
        np.testing.assert_allclose(sub["c"], 0.05, rtol=1e-9)     # C_sd default 0.05
    assert r["omega_min"].iloc[0] == pytest.approx(math.pi)
    assert r["omega_max"].iloc[0] == pytest.approx(2 * math.pi)


def test_alpha_omega_coarser_groups_pool_points(table):
    r = alpha_omega(table, by="dispersion").set_index("dispersion")
    assert r.loc["ep", "n_points"] == 18 and r.loc["ep", "m"] == pytest.approx(2.0)
    assert r.loc["ep", "n_dropped_no_zone"] == 6
    assert r.loc["ml", "m"] == pytest.approx(6.0)
    # alpha_edge = (2 + 100 d_f) alpha_inner: pooled over d_f the exponent stays, the
    # scatter shows in the residual and the standard error
    e = alpha_omega(table, alpha="alpha_edge", by="dispersion").set_index("dispersion")
    assert e.loc["ep", "m"] == pytest.approx(2.0)
    assert e.loc["ep", "rms_log_resid"] > 0.1 and e.loc["ep", "m_stderr"] > 0


def test_alpha_omega_drops_nonpositive_rates_and_needs_enough_periods(table):
    t = table.copy()
    first_ep = t.index[t["dispersion"] == "ep"]
    t.loc[first_ep, "alpha_inner"] = np.where(t.loc[first_ep, "T"] == 2.0, -1.0,
                                              t.loc[first_ep, "alpha_inner"])
    r = alpha_omega(t, by="dispersion").set_index("dispersion")
    assert r.loc["ep", "n_dropped_nonpositive"] == 8 and r.loc["ep", "n_periods"] == 2
    assert r.loc["ep", "n_dropped_no_zone"] == 4 and r.loc["ep", "n_dropped"] == 12
    assert math.isnan(r.loc["ep", "m"])                          # 2 periods < 3
    assert math.isnan(r.loc["ep", "m_c"])                        # same points as m
    assert alpha_omega(t, by="dispersion", min_periods=2).set_index(
        "dispersion").loc["ep", "m"] == pytest.approx(2.0)
    with pytest.raises(ValueError, match="T is the fitted variable"):
        alpha_omega(t, by=["T"])
    with pytest.raises(KeyError, match="alpha_x"):
        alpha_omega(t, alpha="alpha_x")


def test_rows_of_old_stores(table):
    """Rows written before model version 3 (empty compact_zone, the first-pair W_c): W_c =
    L_sheet meant no compact pair (now "none": no W_c, no alpha_inner), any other W_c is
    "legacy" and counted apart."""
    old = table.copy()
    old["compact_zone"] = ""
    old["W_c"] = np.where(old["eps"] == 0.8, 6.0, 1.0)
    d = derived(old)
    none = d["eps"] == 0.8
    assert (d.loc[none, "compact_zone"] == "none").all()
    assert d.loc[none, "W_c"].isna().all() and d.loc[none, "inner_over_c"].isna().all()
    assert (d.loc[~none, "compact_zone"] == "legacy").all()
    s = collision_stats(old, by="eps").set_index("eps")
    assert s.loc[0.8, "n_no_compact"] == 24 and s.loc[0.8, "n_W_c"] == 0
    assert s.loc[0.2, "n_legacy"] == 24 and s.loc[0.2, "W_c_mean"] == pytest.approx(1.0)


# ---------------------------------------------------------------- standard errors (ensembles)
def test_power_law_weighted_recovers_the_law_and_an_honest_error():
    """The weighted log-log fit gives the exact law on exact data, and on data scattered
    by their stated standard errors its m_stderr matches the spread of m over 4000 draws
    (Monte Carlo: within 5 %)."""
    from floewave.results import power_law_weighted
    om = np.array([3.1, 3.9, 4.5, 5.2, 5.7, 6.3])
    se_rel = np.array([0.02, 0.05, 0.03, 0.1, 0.04, 0.06])
    y = 2.0 * om**3.5
    m, c, m_se, chi2 = power_law_weighted(om, y, se_rel * y)
    assert m == pytest.approx(3.5, rel=1e-12) and c == pytest.approx(2.0, rel=1e-10)
    assert chi2 == pytest.approx(0.0, abs=1e-18)
    w = se_rel**-2                          # weights of ln y: 1 / (SE of ln y)^2
    lx = np.log(om)
    expected = 1.0 / math.sqrt(float((w * (lx - np.average(lx, weights=w)) ** 2).sum()))
    rng = np.random.default_rng(7)
    ms = []
    for _ in range(4000):
        yy = y * np.exp(rng.normal(0.0, se_rel))
        ms.append(power_law_weighted(om, yy, se_rel * yy)[0])
    assert np.std(ms) == pytest.approx(expected, rel=0.05)
    # the reported error is never below the error bars' own (chi^2 inflation only raises it)
    for _ in range(20):
        yy = y * np.exp(rng.normal(0.0, se_rel))
        assert power_law_weighted(om, yy, se_rel * yy)[2] >= expected * (1 - 1e-12)


def _with_se(table, se):
    t = table.copy()
    t["W_c_stderr"] = se
    t["alpha_inner_stderr"] = 0.05 * t["alpha_inner"].abs()
    return t


def test_collision_stats_propagate_the_points_standard_errors(table):
    t = _with_se(table, 0.5)
    s = collision_stats(t, by="eps").set_index("eps")
    d = derived(t)
    for eps in (0.2, 0.8):
        g = d[d["eps"] == eps]
        n = int(g["W_c"].notna().sum())
        assert s.loc[eps, "W_c_mean_stderr"] == pytest.approx(0.5 * math.sqrt(n) / n)
        assert s.loc[eps, "W_c_rel_mean_stderr"] == pytest.approx(0.5 / 6.0 / math.sqrt(n))
        inner = g["inner_over_c_stderr"][g["inner_over_c"].notna()]
        assert s.loc[eps, "inner_over_c_mean_stderr"] == pytest.approx(
            math.sqrt((inner**2).sum()) / len(inner))
    # one point of a group without an error bar: that group's mean has none
    t.loc[t.index[0], "W_c_stderr"] = np.nan
    s2 = collision_stats(t, by="eps").set_index("eps")
    eps0 = t.loc[t.index[0], "eps"]
    if not math.isnan(t.loc[t.index[0], "W_c"]) and t.loc[t.index[0], "compact_zone"] != "none":
        assert math.isnan(s2.loc[eps0, "W_c_mean_stderr"])
    # single trajectories (no standard-error columns): NaN, never zero
    s3 = collision_stats(table, by="eps")
    assert s3["W_c_mean_stderr"].isna().all()


def test_alpha_omega_weighted_when_every_point_has_an_error_bar(table):
    t = _with_se(table, 0.5)
    w = alpha_omega(t)
    ok = w["n_periods"] >= 3
    assert w.loc[ok, "weighted"].all()
    # exact power law with proportional errors: the weighted fit finds the same m exactly
    np.testing.assert_allclose(w.loc[ok, "m"], alpha_omega(table).loc[ok, "m"], rtol=1e-9)
    assert not alpha_omega(table)["weighted"].any()


def test_converged_only_leaves_out_the_not_converged_points(table):
    """Issue *first hour* 6: not-converged points enter by default (counted in
    n_not_converged); ``converged_only`` is the filter."""
    s = collision_stats(table, by="eps", converged_only=True).set_index("eps")
    assert list(s.index) == [0.2]  # every eps 0.8 point is not_converged (power_point)
    assert s.loc[0.2, "n_points"] == 24 and s.loc[0.2, "n_not_converged"] == 0
