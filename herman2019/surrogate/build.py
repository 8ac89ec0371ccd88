"""Build the surrogate's node arrays from the grid's table.

Per dispersion relation the table must be the full tensor product of the six axes (each
combination once). Per quantity q of :data:`.model.QUANTITIES` and node:

- ``y_q`` = log(q) (NaN where the point has no value: no compact zone for W_c, a failed
  point, a value <= 0), ``s_q`` = SE(q)/q, its error in log (the calibrated SE,
  ``q_stderr_cal``, where the table is of the calibration's model version, else the
  stated one);
- ``k_q_<axis>``: the squared curvature of y along the axis, from the leave-one-out
  residual at each interior node i (neighbours at distances h_l, h_r in the axis's
  coordinate): r = y_i - (h_r y_(i-1) + h_l y_(i+1)) / (h_l + h_r), the error a
  multilinear interpolant makes there, (1/2) y'' h_l h_r; with the residual's own noise
  taken out, kappa^2 = max(r^2 - var(r), 0) / (h_l h_r)^2 (the square of y''/2). An end
  node takes its neighbour's. Between nodes the interpolation error along the axis is
  then about (y''/2) t(1 - t) h^2 (:mod:`.model`);
- ``zone``: 1 where the point has a compact zone, else 0 (NaN without a result).
"""
from __future__ import annotations

import json
import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from herman2019.surrogate.grid import AXES, DISPERSIONS, coordinate, node_levels
from herman2019.surrogate.model import QUANTITIES, Surrogate

__all__ = ["FIELD_NAMES", "build", "loo_kappa2", "se_columns"]

#: The node fields, in the arrays' column order.
FIELD_NAMES = ("zone",) + tuple(f"{p}_{q}" for q in QUANTITIES for p in ("y", "s")) + \
    tuple(f"k_{q}_{a}" for q in QUANTITIES for a in AXES)
#: The axes along which each quantity is read quadratically (:func:`.grid.window_weights`;
#: linearly along the others), chosen by measured error on the calibration set
#: (``benchmarks/surrogate_methods.py --quadratic``).
#: With the eight floe lengths, median |error| on the calibration set's 300 points (all
#: linear -> these axes quadratic): alpha_all 4.60 -> 2.71 %, alpha_edge 5.64 -> 5.33 %,
#: a_end_rel 1.11 -> 0.43 %; W_c 7.73 % (no axis helps it).
QUADRATIC = {"alpha_all": ("L_x", "T", "d_f"), "alpha_edge": ("L_x",), "a_end_rel": ("C_sd",),
             "W_c": ()}
#: The axes whose intervals each have their own interpolation-error terms (each of the
#: others shares one scale over its intervals): L_x, whose eight levels are far from evenly
#: spread in its coordinate, and d_f, whose widest interval (0.02-0.05, 0.92 in log against
#: 0.69) the first surrogate's error bar covered worst along d_f alone (RMS z of
#: alpha_edge 1.94 at d_f 0.035 against 0.62 at 0.007 on calibration_axes_lx8).
INTERVALS = ("L_x", "d_f")
#: Statuses with results.
DONE = ("converged", "converged_noisy", "not_converged")


def se_columns(table: pd.DataFrame) -> tuple[pd.DataFrame, str]:
    """``table`` with the standard errors the surrogate carries (``q_se_use``), and which:
    the calibrated ones (``herman2019.factors.calibrated``) when the table records its
    model version (``provenance``) and it is the calibration's, else the stated ones."""
    from herman2019.factors import calibrated
    stated = table.assign(**{f"{q}_se_use": table[f"{q}_stderr"] for q in QUANTITIES})
    if "provenance" not in table:
        return stated, "stated"
    try:
        cal = calibrated(table, between=True)
    except ValueError:
        return stated, "stated"
    return cal.assign(**{f"{q}_se_use": cal[f"{q}_stderr_cal"] for q in QUANTITIES}), \
        "calibrated"


def loo_kappa2(y: np.ndarray, s: np.ndarray, u: np.ndarray, axis: int) -> np.ndarray:
    """kappa^2 (module docstring) of log-values ``y`` with errors ``s`` along ``axis``
    (node coordinates ``u``), the same shape as ``y``; NaN where a node or a neighbour has
    no value."""
    y, s = np.moveaxis(y, axis, -1), np.moveaxis(s, axis, -1)
    n = y.shape[-1]
    out = np.full(y.shape, np.nan)
    for i in range(1, n - 1):
        hl, hr = u[i] - u[i - 1], u[i + 1] - u[i]
        wl, wr = hr / (hl + hr), hl / (hl + hr)
        r = y[..., i] - (wl * y[..., i - 1] + wr * y[..., i + 1])
        var = s[..., i] ** 2 + (wl * s[..., i - 1]) ** 2 + (wr * s[..., i + 1]) ** 2
        out[..., i] = np.maximum(r * r - var, 0.0) / (hl * hr) ** 2
    if n > 2:
        out[..., 0], out[..., -1] = out[..., 1], out[..., -2]
    else:       # two nodes: no curvature can be seen; the scale fit carries it
        out[...] = 0.0
    return np.moveaxis(out, -1, axis)


def build(table: pd.DataFrame, source: str = "", commit: str = "",
          lx_order: dict[str, int] | None = None,
          quadratic: dict[str, Sequence[str]] | None = None) -> Surrogate:
    """The surrogate of ``table`` (``sweep.load`` of a full grid), interpolation-error
    scale 1 (fit it with :func:`.validate.fit_scale`), read quadratically along the axes
    of ``quadratic`` per quantity (default :data:`QUADRATIC`; ``lx_order`` q: 2 says
    along L_x alone, 1 linear). ValueError when a dispersion relation's rows are not the
    full tensor product of the axes."""
    table, which = se_columns(table)
    levels = node_levels(table)
    shape = tuple(len(levels[a]) for a in AXES)
    n_nodes = math.prod(shape)
    fields = {}
    versions = sorted({str(json.loads(p).get("model_version")) for p in table["provenance"]}
                      ) if "provenance" in table else []
    for d in DISPERSIONS:
        part = table[table["dispersion"].astype(str) == d]
        if part.empty:
            continue
        keys = part[list(AXES)].drop_duplicates()
        if len(part) != n_nodes or len(keys) != n_nodes:
            raise ValueError(f"dispersion {d}: {len(part)} rows, {len(keys)} distinct"
                             f" points; the grid {' x '.join(map(str, shape))} has"
                             f" {n_nodes}: the surrogate needs the whole tensor product")
        part = part.sort_values(list(AXES))
        done = part["status"].astype(str).isin(DONE).to_numpy()
        cols = {"zone": np.where(done, (part["compact_zone"].astype(str) != "none")
                                 .to_numpy(float), np.nan)}
        for q in QUANTITIES:
            v = part[q].to_numpy(float)
            se = part[f"{q}_se_use"].to_numpy(float)
            ok = done & np.isfinite(v) & (v > 0) & np.isfinite(se)
            with np.errstate(invalid="ignore", divide="ignore"):
                y = np.where(ok, np.log(np.where(ok, v, 1.0)), np.nan)
                s = np.where(ok, se / v, np.nan)
            cols[f"y_{q}"], cols[f"s_{q}"] = y, s
            Y, S = y.reshape(shape), s.reshape(shape)
            for k, a in enumerate(AXES):
                cols[f"k_{q}_{a}"] = loo_kappa2(Y, S, coordinate(a, levels[a]), k).ravel()
        fields[d] = np.stack([cols[name] for name in FIELD_NAMES], axis=1)
    meta = {"source": source, "commit": commit, "model_version": versions,
            "standard_errors": which, "points": int(sum(len(f) for f in fields.values())),
            }
    quad = {q: tuple(v) for q, v in (QUADRATIC if quadratic is None else quadratic).items()}
    if lx_order is not None:
        quad = {q: ("L_x",) if lx_order.get(q, 1) == 2 else () for q in QUANTITIES}
    # (a quadratic needs three levels)
    meta["intervals"] = [a for a in AXES if a in INTERVALS]
    meta["quadratic"] = {q: [a for a in AXES if a in quad.get(q, ()) and len(levels[a]) >= 3]
                         for q in QUANTITIES}
    return Surrogate(levels, fields, FIELD_NAMES, {q: 1.0 for q in QUANTITIES}, meta)
