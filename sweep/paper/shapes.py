"""Shape measures of one point's profiles for the paper's §4.2 claims, with standard errors.

- :func:`two_segment_break`: where the attenuation rate changes. The confined-ice law
  (eq. 25) makes 1/a - 1/a0 linear in x with slope alpha; a zone of faster attenuation at
  the edge and a slower one downwave make it two lines. The break x_b is the knot of the
  continuous two-line least-squares fit through the origin (1/a = 1/a0 at x = 0, eq. 25's
  boundary condition), searched on a 0.05 m grid between the ``min_floes``-th floe from
  either end.
- :func:`break_estimate`: x_b with a delete-one jackknife SE over the replicas. The store
  keeps each replica's time-mean dissipation ``S_sd_replicas`` but not its amplitudes, so
  each leave-one-out a(x) is re-marched (eq. 20,
  :func:`floewave._march.march_coefficients`) from the mean of the other replicas' coefficients
  S_sd,r / a^3. On the Fig. 2 points this re-march reproduces the stored a(x) within
  0.05-0.7 % of a0 and its jackknife SE of a_end is 0.9-1.7 times the stored one
  (``a_stderr``, made from the windows' own amplitudes): an approximation, stated in the
  table.
- :func:`threshold_crossing`: the first pair whose mean gap is below the compact-zone
  threshold (the paper's dots in Figs. 2, 3a), for points where the zone rule found no zone.
"""
from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["two_segment_break", "break_estimate", "threshold_crossing", "jackknife"]

#: Grid step of the break search [m].
BREAK_STEP = 0.05


def two_segment_break(x: np.ndarray, a: np.ndarray, a0: float, *, min_floes: int = 5,
                      x_max: float = math.inf) -> tuple[float, float, float]:
    """(x_b, slope before, slope after) of the continuous two-line fit of 1/a - 1/a0
    against x through the origin (floes with x <= ``x_max``, a > 0); NaNs when fewer than
    2 ``min_floes`` floes are left."""
    x = np.asarray(x, dtype=float)
    a = np.asarray(a, dtype=float)
    ok = np.isfinite(x) & np.isfinite(a) & (a > 0) & (x <= x_max)
    x, y = x[ok], 1.0 / a[ok] - 1.0 / a0
    if len(x) < 2 * min_floes:
        return math.nan, math.nan, math.nan
    lo, hi = x[min_floes - 1], x[-min_floes]
    xb = np.arange(lo, hi + 0.5 * BREAK_STEP, BREAK_STEP)[:, None]
    # y = s1 min(x, xb) + s2 max(x - xb, 0): linear in (s1, s2); the 2 x 2 normal equations
    # solved for every candidate knot at once
    u, v = np.minimum(x, xb), np.maximum(x - xb, 0.0)
    suu, suv, svv = (u * u).sum(1), (u * v).sum(1), (v * v).sum(1)
    suy, svy = (u * y).sum(1), (v * y).sum(1)
    det = suu * svv - suv * suv
    with np.errstate(divide="ignore", invalid="ignore"):
        s1 = (svv * suy - suv * svy) / det
        s2 = (suu * svy - suv * suy) / det
    sse = ((s1[:, None] * u + s2[:, None] * v - y) ** 2).sum(1)
    sse = np.where(np.isfinite(sse), sse, np.inf)
    k = int(np.argmin(sse))
    return float(xb[k, 0]), float(s1[k]), float(s2[k])


def jackknife(values: np.ndarray) -> float:
    """Delete-one jackknife SE of leave-one-out values (NaN if any is NaN or fewer than 2)."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2 or not np.all(np.isfinite(v)):
        return math.nan
    d = v - v.mean()
    return float(math.sqrt((len(v) - 1) / len(v) * np.sum(d * d)))


def _cfg(row: Mapping[str, Any]) -> Any:
    from floewave.config import ModelConfig

    return ModelConfig.from_dict(json.loads(str(row["config_json"])))


def break_estimate(row: Mapping[str, Any], profile: Mapping[str, Any]
                   ) -> tuple[float, float, float, float]:
    """(x_b, its jackknife SE, slope before, slope after) of a stored point
    (:func:`two_segment_break` of the stored a(x) up to ``compact_end``; SE as the module
    docstring says, NaN without ``S_sd_replicas`` or with one replica)."""
    from floewave._march import march_coefficients

    a0 = float(row["a0"])
    end = float(row.get("compact_end", math.nan))
    x_max = end if math.isfinite(end) else math.inf
    x = np.asarray(profile["x_mean"], dtype=float)
    a = np.asarray(profile["a"], dtype=float)
    cfg = _cfg(row)
    xb, s1, s2 = two_segment_break(x, a, a0, min_floes=cfg.fit_min_floes, x_max=x_max)
    S = profile["S_sd_replicas"] if "S_sd_replicas" in profile else None
    if S is None or not math.isfinite(xb):
        return xb, math.nan, s1, s2
    S = np.asarray(S, dtype=float)
    if S.ndim != 2 or S.shape[0] < 2:
        return xb, math.nan, s1, s2
    with np.errstate(divide="ignore", invalid="ignore"):
        C = np.where(a > 0, S / a ** 3, np.nan)
    loo = []
    for r in range(S.shape[0]):
        c = np.nanmean(np.delete(C, r, axis=0), axis=0)
        c = np.where(np.isfinite(c), c, 0.0)
        a_r = march_coefficients(cfg, c, float(row["c_g"]), float(row["k"]))
        loo.append(two_segment_break(x, a_r, a0, min_floes=cfg.fit_min_floes,
                                     x_max=x_max)[0])
    return xb, jackknife(np.array(loo)), s1, s2


def threshold_crossing(x: np.ndarray, gap: np.ndarray, threshold: float) -> float:
    """The centre of the first pair (x_i + gap-side half) whose mean gap is below
    ``threshold``: the paper's dot; NaN if none."""
    x = np.asarray(x, dtype=float)
    g = np.asarray(gap, dtype=float)[: len(x) - 1]
    below = np.flatnonzero(np.isfinite(g) & (g < threshold))
    if not len(below):
        return math.nan
    i = int(below[0])
    return float(0.5 * (x[i] + x[i + 1]))
