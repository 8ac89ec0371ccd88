"""A group-sequential rule for ``herman2019 check --settle``: looking again at a claim as
seeds are added, with the false-verdict rate of one look kept.

A claim's evidence is a set of z statistics (:mod:`herman2019.estimates`): each is read
against a critical value, +c for "holds", -c for "fails". Checked once, at c = 2, each
z carries a one-sided false-verdict rate of alpha = 1 - Phi(2) = 2.28 % (a "holds" where the
true effect is 0, or a "fails" where it is 0). Checked again after every added seed until
a verdict appears, at c = 2 each time, that rate grows with the number of looks (6.5 % in
4 looks at 1/8, 1/4, 1/2 and all of the data, by :func:`crossing_rate`). This module spends alpha over K planned looks instead
(Lan & DeMets 1983, the error-spending approach; Jennison & Turnbull 2000, ch. 7):

- the looks are at information fractions t_1 < ... < t_K = 1 (here the share of the
  planned seeds pooled: 4, 8, 16, 32, 64 seeds give 1/16, 1/8, 1/4, 1/2, 1);
- a spending function alpha(t) says how much of alpha may be used by t:
  :data:`POCOCK` ``alpha ln(1 + (e - 1) t)`` (Lan-DeMets' Pocock type: nearly constant
  boundaries, most of alpha early) or :data:`OBRIEN_FLEMING`
  ``2 - 2 Phi(z_(alpha/2) / sqrt t)`` (strict early, about 2 at the end);
- the boundary c_k is the value at which the probability, with no effect, of first
  crossing +c at look k (having stayed inside (-c_j, c_j) before) is alpha(t_k) -
  alpha(t_(k-1)). The z's at the looks are those of a Brownian motion observed at the
  fractions t_k: corr(Z_j, Z_k) = sqrt(t_j / t_k), and the crossing probabilities are
  computed by recursive numerical integration of the density of the continuing paths
  (Armitage, McPherson & Rowe 1969), on a grid of :data:`GRID` points.

So over all K looks the chance that a z with no effect ever crosses +c_k is alpha, and the
same for -c_k: the false-verdict rate of one z is the one-look rule's. Where the SE is
estimated with nu degrees of freedom, c_k is carried to Student-t at the same tail
probability (as :func:`herman2019.estimates.z_critical` does for one look). The tests
(``tests/sweep/test_settle.py``) measure the rate on simulated looks.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cache

import numpy as np

__all__ = ["ALPHA", "POCOCK", "OBRIEN_FLEMING", "GRID", "spent", "boundaries",
           "crossing_rate"]

#: The one-sided false-verdict rate of one z at the one-look rule's z_c = 2.
ALPHA = 0.5 * math.erfc(2.0 / math.sqrt(2.0))
POCOCK, OBRIEN_FLEMING = "pocock", "obrien-fleming"
#: Grid points over the continuation region in the recursive integration.
GRID = 801


def _phi(x: np.ndarray | float) -> np.ndarray | float:
    return np.exp(-0.5 * np.square(x)) / math.sqrt(2.0 * math.pi)


def _cdf(x: np.ndarray | float) -> np.ndarray | float:
    from scipy.special import ndtr

    return ndtr(x)


def spent(t: float, alpha: float = ALPHA, kind: str = POCOCK) -> float:
    """alpha(t): the false-verdict rate (one side) that may be used by information
    fraction ``t`` (0 at t = 0, ``alpha`` at t = 1)."""
    if not 0.0 <= t <= 1.0:
        raise ValueError(f"information fraction {t} not in [0, 1]")
    if t == 0.0:
        return 0.0
    if kind == POCOCK:
        return alpha * math.log1p((math.e - 1.0) * t)
    if kind == OBRIEN_FLEMING:
        from scipy.special import ndtri

        return float(2.0 - 2.0 * _cdf(ndtri(1.0 - alpha / 2.0) / math.sqrt(t)))
    raise ValueError(f"spending function {kind!r}: one of {POCOCK!r}, {OBRIEN_FLEMING!r}")


def _step(density: np.ndarray, grid: np.ndarray, dgrid: float, dt: float,
          upper: float) -> float:
    """The probability that paths with ``density`` on ``grid`` (the continuation region of
    the last look) end above ``upper`` after an increment of variance ``dt``."""
    tail = 1.0 - _cdf((upper - grid) / math.sqrt(dt))
    return float(np.sum(_trapz_w(len(grid)) * density * tail) * dgrid)


@cache
def _trapz_w(n: int) -> np.ndarray:
    w = np.ones(n)
    w[0] = w[-1] = 0.5
    return w


@cache
def _boundaries(fractions: tuple[float, ...], alpha: float, kind: str) -> tuple[float, ...]:
    from scipy.optimize import brentq
    from scipy.special import ndtri

    out: list[float] = []
    density = grid = None
    dgrid = 0.0
    prev_t, prev_spent = 0.0, 0.0
    for t in fractions:
        target = spent(t, alpha, kind) - prev_spent
        if density is None:                         # first look: Z_1 ~ N(0, 1)
            c = float(-ndtri(target))
        else:
            dt = t - prev_t
            lo_c, hi_c = 0.0, 12.0

            def excess(c_: float, dt: float = dt, t: float = t) -> float:
                return _step(density, grid, dgrid, dt, c_ * math.sqrt(t)) - target

            c = float(brentq(excess, lo_c, hi_c, xtol=1e-10)) if excess(hi_c) < 0 < excess(
                lo_c) else math.inf
        out.append(c)
        # the density of the score S = Z sqrt(t) of the paths still inside (-c, c)
        half = c * math.sqrt(t)
        if not math.isfinite(half):
            half = 12.0 * math.sqrt(t)
        new_grid = np.linspace(-half, half, GRID)
        if density is None:
            new_density = _phi(new_grid / math.sqrt(t)) / math.sqrt(t)
        else:
            dt = t - prev_t
            kern = _phi((new_grid[:, None] - grid[None, :]) / math.sqrt(dt)) / math.sqrt(dt)
            new_density = kern @ (_trapz_w(len(grid)) * density) * dgrid
        density, grid, dgrid = new_density, new_grid, new_grid[1] - new_grid[0]
        prev_t, prev_spent = t, spent(t, alpha, kind)
    return tuple(out)


def boundaries(fractions: Sequence[float], alpha: float = ALPHA, kind: str = POCOCK
               ) -> tuple[float, ...]:
    """The critical |z| at each look (the module docstring), for increasing information
    fractions ending at 1."""
    fr = tuple(float(f) for f in fractions)
    if not fr or any(b <= a for a, b in zip(fr[:-1], fr[1:], strict=True)) or fr[0] <= 0 \
            or not math.isclose(fr[-1], 1.0):
        raise ValueError(f"information fractions {fr}: increasing, in (0, 1], ending at 1")
    if not 0.0 < alpha < 0.5:
        raise ValueError(f"alpha {alpha}: in (0, 0.5)")
    return _boundaries(fr, float(alpha), kind)


def crossing_rate(fractions: Sequence[float], critical: Sequence[float]) -> float:
    """The probability, with no effect, that a z observed at these looks ever reaches
    +critical[k] (having stayed inside (-c, c) before): the one-sided false-verdict rate
    of the looks (by the same integration; with c = 2 at every look it is the rate of
    looking again at the one-look rule)."""
    fr = [float(f) for f in fractions]
    total = 1.0 - float(_cdf(critical[0]))
    half = critical[0] * math.sqrt(fr[0])
    grid = np.linspace(-half, half, GRID)
    density = _phi(grid / math.sqrt(fr[0])) / math.sqrt(fr[0])
    dgrid = grid[1] - grid[0]
    for k in range(1, len(fr)):
        dt = fr[k] - fr[k - 1]
        total += _step(density, grid, dgrid, dt, critical[k] * math.sqrt(fr[k]))
        half = critical[k] * math.sqrt(fr[k])
        new = np.linspace(-half, half, GRID)
        kern = _phi((new[:, None] - grid[None, :]) / math.sqrt(dt)) / math.sqrt(dt)
        density = kern @ (_trapz_w(len(grid)) * density) * dgrid
        grid, dgrid = new, new[1] - new[0]
    return total
