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
  :func:`floewave.march_coefficients`) from the mean of the other replicas' coefficients
  S_sd,r / a^3. On the Fig. 2 points this re-march reproduces the stored a(x) within
  0.004-0.7 % of a0 and its jackknife SE of a_end is 0.50-1.68 times the stored one
  (``a_stderr``, made from the windows' own amplitudes): an approximation, stated in the
  table.
- :func:`rate_reach` / :func:`reach_estimate`: where the *local* rate reaches the compact
  zone's. The local rate is the least-squares slope of 1/a - 1/a0 over the floes within
  :data:`REACH_HALF` (1 m) of each floe; x_r is the first floe from which it stays at or
  below :data:`REACH_FACTOR` (1.25, the "close to" of the ratio claims) times alpha_inner
  for :data:`REACH_HOLD` (3 m, the compact-zone rule's minimum length). A two-line knot
  sits in the middle of a gradual bend; x_r is where the bend ends. SE: the same
  re-marched jackknife (alpha_inner held at the stored value), at least the floe grid's
  rounding error (spacing / sqrt(12)): x_r moves in steps of one floe.
- :func:`threshold_crossing`: the first pair whose mean gap is below the compact-zone
  threshold (the paper's dots in Figs. 2, 3a), for points where the zone rule found no zone.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from floewave import march_coefficients
from floewave.errorbars import jackknife_se
from herman2019.points import config_of

__all__ = ["two_segment_break", "break_estimate", "threshold_crossing", "loo_amplitudes",
           "rate_reach", "reach_estimate", "REACH_HALF", "REACH_FACTOR", "REACH_HOLD"]

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


REACH_HALF = 1.0
REACH_FACTOR = 1.25
REACH_HOLD = 3.0


def rate_reach(x: np.ndarray, a: np.ndarray, a0: float, alpha_inner: float) -> float:
    """x_r: the first floe centre from which the local slope of 1/a - 1/a0 stays at or below
    REACH_FACTOR alpha_inner for REACH_HOLD metres (NaN if none or alpha_inner is NaN)."""
    x = np.asarray(x, dtype=float)
    a = np.asarray(a, dtype=float)
    if not (math.isfinite(alpha_inner) and alpha_inner > 0):
        return math.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(a > 0, 1.0 / a - 1.0 / a0, np.nan)
    near = np.abs(x[:, None] - x[None, :]) <= REACH_HALF           # (floe, window member)
    cnt = near.sum(1)
    xm = np.where(near, x, 0.0).sum(1) / cnt
    ym = np.where(near, y, 0.0).sum(1) / cnt
    dx = np.where(near, x[None, :] - xm[:, None], 0.0)
    dy = np.where(near, y[None, :] - ym[:, None], 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (dx * dy).sum(1) / (dx * dx).sum(1)
    ok = np.isfinite(slope) & (slope <= REACH_FACTOR * alpha_inner) & (cnt >= 3)
    for i in range(len(x)):
        span = (x >= x[i]) & (x <= x[i] + REACH_HOLD)
        if x[-1] - x[i] >= REACH_HOLD and ok[span].all():
            return float(x[i])
    return math.nan


def loo_amplitudes(row: Mapping[str, Any], profile: Mapping[str, Any]) -> list[np.ndarray]:
    """Each replica left out in turn: a(x) re-marched from the other replicas' stored
    dissipation coefficients (the module docstring); [] without S_sd_replicas. Computed
    once per point and passed to :func:`break_estimate` and :func:`reach_estimate`."""
    a = np.asarray(profile["a"], dtype=float)
    S = profile["S_sd_replicas"] if "S_sd_replicas" in profile else None
    if S is None:
        return []
    S = np.asarray(S, dtype=float)
    if S.ndim != 2 or S.shape[0] < 2:
        return []
    with np.errstate(divide="ignore", invalid="ignore"):
        C = np.where(a > 0, S / a ** 3, np.nan)
    cfg = config_of(row)
    out = []
    for r in range(S.shape[0]):
        c = np.nanmean(np.delete(C, r, axis=0), axis=0)
        c = np.where(np.isfinite(c), c, 0.0)
        out.append(march_coefficients(cfg, c, float(row["c_g"]), float(row["k"])))
    return out


def reach_estimate(row: Mapping[str, Any], profile: Mapping[str, Any],
                   loo_a: list[np.ndarray] | None = None) -> tuple[float, float]:
    """(x_r, its jackknife SE) of a stored point (:func:`rate_reach` of the stored a(x)
    with the stored alpha_inner); ``loo_a``: :func:`loo_amplitudes` if already made."""
    a0, ai = float(row["a0"]), float(row.get("alpha_inner", math.nan))
    x = np.asarray(profile["x_mean"], dtype=float)
    xr = rate_reach(x, np.asarray(profile["a"], dtype=float), a0, ai)
    if not math.isfinite(xr):
        return xr, math.nan
    if loo_a is None:
        loo_a = loo_amplitudes(row, profile)
    loo = [rate_reach(x, a_r, a0, ai) for a_r in loo_a]
    if not loo:
        return xr, math.nan
    # x_r moves in steps of one floe: at least the rounding error of that grid
    grid = float(np.median(np.diff(x))) / math.sqrt(12.0)
    return xr, max(float(jackknife_se(np.array(loo))), grid)


def break_estimate(row: Mapping[str, Any], profile: Mapping[str, Any],
                   loo_a: list[np.ndarray] | None = None) -> tuple[float, float, float, float]:
    """(x_b, its jackknife SE, slope before, slope after) of a stored point
    (:func:`two_segment_break` of the stored a(x) up to ``compact_end``; SE as the module
    docstring says, NaN without ``S_sd_replicas`` or with one replica); ``loo_a``:
    :func:`loo_amplitudes` if already made."""
    a0 = float(row["a0"])
    end = float(row.get("compact_end", math.nan))
    x_max = end if math.isfinite(end) else math.inf
    x = np.asarray(profile["x_mean"], dtype=float)
    a = np.asarray(profile["a"], dtype=float)
    cfg = config_of(row)
    xb, s1, s2 = two_segment_break(x, a, a0, min_floes=cfg.fit_min_floes, x_max=x_max)
    if not math.isfinite(xb):
        return xb, math.nan, s1, s2
    if loo_a is None:
        loo_a = loo_amplitudes(row, profile)
    loo = [two_segment_break(x, a_r, a0, min_floes=cfg.fit_min_floes, x_max=x_max)[0]
           for a_r in loo_a]
    return xb, float(jackknife_se(np.array(loo))) if loo else math.nan, s1, s2


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
