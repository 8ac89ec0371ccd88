"""floewave.results: PointResult's fields and the attenuation and power-law fits."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from floewave.results import (
    PROFILE_FIELDS,
    REPLICA_FIELDS,
    SCALAR_FIELDS,
    PointResult,
    fit_exponential,
    fit_inverse,
    power_law,
    power_law_weighted,
)

X = np.linspace(0.25, 9.75, 20)


def point_result(n=4, **changes):
    values = {name: np.arange(1.0, n + 1) for name in PROFILE_FIELDS}
    for f in dataclasses.fields(PointResult):
        if f.name not in values and f.default is dataclasses.MISSING \
                and f.default_factory is dataclasses.MISSING:
            values[f.name] = {"int": 0, "str": "", "float": 0.0}[
                f.type if f.type in ("int", "str") else "float"]
    values.update(a0=2.0, n_floes=n, status="converged", **changes)
    return PointResult(**values)


def test_point_result_fields_are_the_declared_ones():
    names = {f.name for f in dataclasses.fields(PointResult)}
    declared = set(PROFILE_FIELDS) | set(SCALAR_FIELDS) | set(REPLICA_FIELDS)
    assert declared | {"a0", "residual_history"} == names
    assert not set(PROFILE_FIELDS) & set(SCALAR_FIELDS)


def test_to_dict_and_a_rel():
    r = point_result()
    d = r.to_dict()
    assert list(d) == [f.name for f in dataclasses.fields(PointResult)]
    assert d["a"] is r.a and d["replicas"] == 1 and math.isnan(d["W_c_stderr"])
    assert d["x_mean_replicas"].shape == (0, 0)
    np.testing.assert_allclose(r.a_rel, np.arange(1.0, 5.0) / 2.0)


def test_fit_inverse_recovers_the_law_and_needs_three_floes():
    a0, alpha = 0.02, 3.0
    a = 1.0 / (1.0 / a0 + alpha * X)
    slope, resid = fit_inverse(X, a, a0)
    assert slope == pytest.approx(alpha, rel=1e-9) and resid < 1e-12
    a_bad = a.copy()
    a_bad[3:] = 0.0  # only floes with a > 0 are fitted: three are enough
    assert fit_inverse(X, a_bad, a0)[0] == pytest.approx(alpha, rel=1e-9)
    a_bad[2] = -1.0
    assert all(math.isnan(v) for v in fit_inverse(X, a_bad, a0))
    noisy = a * (1 + 0.05 * np.sin(7 * X))
    assert fit_inverse(X, noisy, a0)[1] > 1e-4


def test_fit_exponential_recovers_the_rate():
    a0, rate = 0.02, 0.15
    a = a0 * np.exp(-rate * X)
    got, resid = fit_exponential(X, a, a0)
    assert got == pytest.approx(rate, rel=1e-9) and resid < 1e-12
    assert all(math.isnan(v) for v in fit_exponential(X[:2], a[:2], a0))


def test_power_law_exact_and_with_scatter():
    x = np.array([0.5, 1.0, 2.0, 4.0])
    m, c, m_se, rms = power_law(x, 3.0 * x ** 2)
    assert (m, c) == (pytest.approx(2.0), pytest.approx(3.0))
    assert m_se < 1e-9 and rms < 1e-12
    m, c, m_se, rms = power_law(x, 3.0 * x ** 2 * np.array([1.1, 0.9, 1.1, 0.9]))
    assert m_se > 0.01 and rms > 0.05 and m == pytest.approx(2.0, abs=0.2)
    assert math.isnan(power_law(x[:2], x[:2] ** 2)[2])  # 2 points: no standard error


def test_power_law_weighted():
    x = np.array([0.5, 1.0, 2.0, 4.0])
    y = 3.0 * x ** 2
    m, c, m_se, chi2 = power_law_weighted(x, y, 0.01 * y)
    assert (m, c) == (pytest.approx(2.0), pytest.approx(3.0)) and chi2 < 1e-12
    # chi^2 < 1: the error bars alone give the standard error
    sxx = float(((np.log(x) - np.log(x).mean()) ** 2).sum()) / 0.01 ** 2
    assert m_se == pytest.approx(math.sqrt(1.0 / sxx))
    # scatter beyond the error bars: chi^2 > 1 widens the standard error
    scattered = y * np.array([1.1, 0.9, 1.1, 0.9])
    m2, _, se2, chi2 = power_law_weighted(x, scattered, 0.01 * scattered)
    assert chi2 > 1 and se2 == pytest.approx(math.sqrt(chi2) * m_se, rel=1e-6)
    assert all(math.isnan(v) for v in power_law_weighted(x[:1], y[:1], y[:1]))
    m, c, se, chi2 = power_law_weighted(x[:2], y[:2], 0.01 * y[:2])
    assert m == pytest.approx(2.0) and math.isnan(se) and math.isnan(chi2)
    assert all(math.isnan(v) for v in power_law_weighted([1.0, 1.0], [2.0, 3.0], [0.1, 0.1]))
