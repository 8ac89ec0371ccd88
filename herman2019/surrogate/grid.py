"""The grid's nodes as arrays, and multilinear weights on them.

The paper's grid is a full tensor product over six continuous parameters per dispersion
relation. Each axis is interpolated in its own coordinate (:data:`LOG_AXES` in log, the
others linear); :func:`cell_weights` gives, for query points, the 2^6 corners of the cell
that holds each point and their multilinear weights, so that a value, a variance
(weights squared) or a masked mean (a quantity defined at some nodes only) can all be
read from one set of weights. Agrees with ``scipy.interpolate.RegularGridInterpolator``
(``method="linear"``) where every node is defined (tested).
"""
from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["AXES", "LOG_AXES", "DISPERSIONS", "OutsideBox", "coordinate", "cell_weights",
           "check_box", "axis_weights", "window_weights"]

#: The six continuous axes of the paper's grid, in the table's order.
AXES = ("L_x", "T", "a0", "C_sd", "eps", "d_f")
#: Axes interpolated in log(value): their levels are spaced by factors (C_sd 0.005-0.2,
#: d_f 5-50 mm) or the physics scales with them (floe length, amplitude).
LOG_AXES = frozenset({"L_x", "a0", "C_sd", "d_f"})
#: The dispersion relations, one surrogate each.
DISPERSIONS = ("ep", "ow", "ml")

_CORNERS = np.array(list(itertools.product((0, 1), repeat=len(AXES))), dtype=np.int64)


class OutsideBox(ValueError):
    """A query outside the grid's box (or an unknown dispersion relation)."""


def coordinate(axis: str, values) -> np.ndarray:
    """The interpolation coordinate of ``values`` on ``axis`` (log or identity)."""
    v = np.asarray(values, dtype=float)
    return np.log(v) if axis in LOG_AXES else v


def check_box(levels: Mapping[str, np.ndarray], query: Mapping[str, np.ndarray],
              tol: float = 1e-9) -> None:
    """OutsideBox naming the first parameter outside the grid's range (relative ``tol``
    beyond an end is taken as the end), or not a finite number."""
    for axis in AXES:
        lv, q = levels[axis], np.asarray(query[axis], dtype=float)
        lo, hi = float(lv[0]), float(lv[-1])
        bad = ~np.isfinite(q) | (q < lo * (1 - tol)) | (q > hi * (1 + tol))
        if np.any(bad):
            first = float(np.asarray(q)[bad].ravel()[0])
            raise OutsideBox(f"{axis} = {first:g} is outside the grid's box"
                             f" [{lo:g}, {hi:g}]: the surrogate does not extrapolate")


def cell_weights(levels: Mapping[str, np.ndarray], query: Mapping[str, np.ndarray]
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For ``n`` query points (arrays of one shape, flattened): the flat node index of each
    of the 64 corners of the cell holding each point, shape (n, 64); their multilinear
    weights, (n, 64), summing to 1; each point's position inside its cell along each axis,
    t in [0, 1], (n, 6); and the cell's width along each axis in its coordinate, (n, 6).
    Node order is C order over :data:`AXES`."""
    shape = [len(levels[a]) for a in AXES]
    strides = np.cumprod([1] + shape[::-1][:-1])[::-1]
    n = np.asarray(query[AXES[0]], dtype=float).size
    lo_index = np.empty((n, len(AXES)), dtype=np.int64)
    t = np.empty((n, len(AXES)))
    h = np.empty((n, len(AXES)))
    for k, axis in enumerate(AXES):
        u = coordinate(axis, levels[axis])
        q = coordinate(axis, np.asarray(query[axis], dtype=float).ravel())
        q = np.clip(q, u[0], u[-1])
        j = np.clip(np.searchsorted(u, q, side="right") - 1, 0, len(u) - 2)
        lo_index[:, k] = j
        h[:, k] = u[j + 1] - u[j]
        t[:, k] = (q - u[j]) / h[:, k]
    idx = (lo_index[:, None, :] + _CORNERS[None, :, :]) @ strides        # (n, 64)
    w = np.prod(np.where(_CORNERS[None, :, :] == 1, t[:, None, :], 1.0 - t[:, None, :]),
                axis=2)
    return idx, w, t, h


def axis_weights(u: np.ndarray, x: np.ndarray, quadratic: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Along one axis of node coordinates ``u`` at points ``x`` (clipped to the range):
    the first node of each point's window, (n,), and the window's weights, (n, m). Linear
    (m = 2: the cell's two nodes) or, with ``quadratic`` and three levels or more, the
    mean of the quadratics through the cell's two nodes and each neighbour (one at an end
    cell; with three levels the quadratic through all three), m = min(levels, 4)
    (Lagrange weights, which may be negative); at a node, the node."""
    n_lv = len(u)
    x = np.clip(x, u[0], u[-1])
    j = np.clip(np.searchsorted(u, x, side="right") - 1, 0, n_lv - 2)     # the cell
    if not quadratic or n_lv < 3:
        t = (x - u[j]) / (u[j + 1] - u[j])
        return j, np.stack([1.0 - t, t], axis=1)
    m = min(n_lv, 4)
    start = np.clip(j - 1, 0, n_lv - m)
    lag = np.zeros((x.size, m))
    count = np.zeros(x.size)
    for first in (j - 1, j):             # the quadratic through nodes first .. first + 2
        ok = (first >= 0) & (first + 2 <= n_lv - 1)
        f = np.clip(first, 0, n_lv - 3)
        for a in range(3):
            wa = np.prod([(x - u[f + b]) / (u[f + a] - u[f + b]) for b in range(3) if b != a],
                         axis=0)
            col = f + a - start                                # its place in the window
            for c in range(m):
                lag[:, c] += np.where(ok & (col == c), wa, 0.0)
        count += ok
    return start, lag / count[:, None]


def window_weights(levels: Mapping[str, np.ndarray], query: Mapping[str, np.ndarray],
                   quadratic: Sequence[str] = ()) -> tuple[np.ndarray, np.ndarray]:
    """The tensor product of :func:`axis_weights` over :data:`AXES`, quadratic along the
    axes of ``quadratic`` and linear along the others: for ``n`` query points the flat
    node index of each corner of their windows and its weight, both (n, prod m), the
    weights summing to 1. With ``quadratic`` empty, :func:`cell_weights`' corners (in
    another order); at a node, the node."""
    shape = [len(levels[a]) for a in AXES]
    strides = np.cumprod([1] + shape[::-1][:-1])[::-1]
    n = np.asarray(query[AXES[0]], dtype=float).size
    idx = np.zeros((n, 1), dtype=np.int64)
    w = np.ones((n, 1))
    for k, axis in enumerate(AXES):
        u = coordinate(axis, levels[axis])
        x = coordinate(axis, np.asarray(query[axis], dtype=float).ravel())
        start, wa = axis_weights(u, x, axis in quadratic)
        offs = (start[:, None] + np.arange(wa.shape[1])[None, :]) * strides[k]   # (n, m)
        idx = (idx[:, :, None] + offs[:, None, :]).reshape(n, -1)
        w = (w[:, :, None] * wa[:, None, :]).reshape(n, -1)
    return idx, w


def node_levels(table, axes: Sequence[str] = AXES) -> dict[str, np.ndarray]:
    """Each axis's sorted distinct values in ``table`` (a DataFrame)."""
    return {a: np.sort(table[a].unique().astype(float)) for a in axes}
