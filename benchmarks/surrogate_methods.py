"""Which interpolation for the surrogate: measured on off-grid points run with the model.

    python benchmarks/surrogate_methods.py [--grid TABLE ...]   # default: the surrogate's four
    python benchmarks/surrogate_methods.py --quadratic 3        # the surrogate's quadratic axes
        [--runs results/surrogate/calibration/runs.csv.gz]

Interpolates alpha_all, alpha_edge and a_end/a0 (defined at every node) of the grid's
table at the points of ``--runs`` (the surrogate's calibration set by default: the choice
is made there, not on the validation set) with scipy's tensor-grid interpolators, and
prints per method the median and 90th percentile of |q_interp / q_model - 1|:

- ``linear, log q, log axes``: the surrogate's choice (L_x, a0, C_sd, d_f on log axes);
- ``linear, q, linear axes``: the plain reading of the table;
- ``linear, log q, linear axes``;
- ``linear x quadratic L_x``: linear over the other five axes, along L_x the quadratic
  through its three levels (more levels: the mean of the quadratics through the cell and
  each neighbour, :func:`join_lx`);
- ``pchip`` and ``cubic`` (``RegularGridInterpolator``, log q, log axes): they need four
  nodes per axis and the paper's grid has three of L_x, so each is applied over the other
  five axes at each level of L_x, then joined along L_x by the quadratic (and, as a
  check, linearly);
- with four or more levels of L_x (``--grid`` with the grid's extensions): ``pchip`` along
  L_x too.

The model values are one 8-replica ensemble each (stochastic): the medians include their
noise (median stated SE printed), so a method can only be told from another where they
differ by more than that.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import RegularGridInterpolator

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

AXES = ("L_x", "T", "a0", "C_sd", "eps", "d_f")
LOG = {"L_x", "a0", "C_sd", "d_f"}
QS = ("alpha_all", "alpha_edge", "a_end_rel")


def coord(a, v, log_axes):
    v = np.asarray(v, float)
    return np.log(v) if a in log_axes else v


def grid_arrays(table, disp, q, levels):
    part = table[table["dispersion"].astype(str) == disp].sort_values(list(AXES))
    return part[q].to_numpy(float).reshape([len(levels[a]) for a in AXES])


def interp(method, values, levels, pts, log_q, log_axes, join="quadratic"):
    """Values at ``pts`` (dict of arrays)."""
    y = np.log(values) if log_q else values
    if method == "linear" and join == "linear":
        f = RegularGridInterpolator([coord(a, levels[a], log_axes) for a in AXES], y)
        out = f(np.stack([coord(a, pts[a], log_axes) for a in AXES], axis=1))
    else:       # over the five other axes at each L_x level, then along L_x
        rest = AXES[1:]
        xs = np.stack([coord(a, pts[a], log_axes) for a in rest], axis=1)
        at = np.stack([RegularGridInterpolator(
            [coord(a, levels[a], log_axes) for a in rest], y[i], method=method)(xs)
            for i in range(len(levels["L_x"]))], axis=1)            # (n, L_x levels)
        u = coord("L_x", levels["L_x"], log_axes)
        x = coord("L_x", pts["L_x"], log_axes)
        out = join_lx(join, at, u, x)
    return np.exp(out) if log_q else out


def join_lx(join, at, u, x):
    """Along L_x, from the values ``at`` (n, levels) at its levels ``u``: ``linear``, the
    line through the cell's two; ``quadratic``, the mean of the quadratics through the
    cell's two nodes and each neighbour (one at an end cell; with three levels, the
    quadratic through all three: the surrogate's quadratic reading); ``pchip``, scipy's
    monotone cubic."""
    rows = np.arange(len(x))
    if join == "pchip":
        from scipy.interpolate import PchipInterpolator
        return np.array([PchipInterpolator(u, at[i])(x[i]) for i in rows])
    from herman2019.surrogate.grid import axis_weights  # the surrogate's own reading
    start, w = axis_weights(u, x, join == "quadratic")
    return sum(w[:, c] * at[rows, start + c] for c in range(w.shape[1]))


#: An axis is read quadratically only if that lowers the median error by this share.
MIN_GAIN = 0.05


def quadratic_axes(table, runs, k_max, grids) -> int:
    """Along which axes to read each quantity quadratically: the surrogate built from the
    table (``herman2019.surrogate.build``, its own reading: multilinear in log q on log
    axes, quadratic along the axes chosen), at the runs' points; from none, the axis whose
    quadratic reading lowers the median |q_sur / q_model - 1| most is added while that
    lowers it by :data:`MIN_GAIN` of itself or more, up to ``k_max`` axes (each costs the
    prediction a factor of up to 2 in corners)."""
    from herman2019.surrogate.build import build
    from herman2019.surrogate.model import QUANTITIES, Surrogate
    from herman2019.surrogate.validate import model_table
    sur = build(table)
    model = model_table(runs)
    print(f"{len(runs)} off-grid points; grid {' + '.join(grids)}"
          f" ({len(sur.levels['L_x'])} levels of L_x); median (90th pct) |rel. error|")

    def errors(q, axes):
        s = Surrogate(sur.levels, sur.fields, sur.names, dict(sur.scale),
                      {**sur.meta, "quadratic": {q: list(axes)}})
        p = s.predict(model["dispersion"].astype(str).to_numpy(),
                      **{a: model[a].to_numpy(float) for a in AXES})
        rel = np.abs(p[q].to_numpy(float) / model[q].to_numpy(float) - 1)
        if q == "W_c":
            rel = rel[model["zone"].to_numpy() > 0]
        rel = rel[np.isfinite(rel)]
        return float(np.median(rel)), float(np.quantile(rel, 0.9))
    for q in QUANTITIES:
        chosen: list[str] = []
        med, p90 = errors(q, chosen)
        line = [f"linear {100 * med:.2f}% ({100 * p90:.1f}%)"]
        while len(chosen) < k_max:
            trial = {a: errors(q, [*chosen, a]) for a in AXES if a not in chosen}
            best = min(trial, key=lambda a: trial[a][0])
            if trial[best][0] > (1 - MIN_GAIN) * med:
                break
            chosen.append(best)
            med, p90 = trial[best]
            line.append(f"+{best} {100 * med:.2f}% ({100 * p90:.1f}%)")
        print(f"{q:10s} " + ", ".join(line))
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    from herman2019.surrogate.command import GRIDS
    ap.add_argument("--grid", nargs="+", default=[str(ROOT / "results" / g) for g in GRIDS],
                    help="the grid's tables, read together (default: the surrogate's, the"
                    " paper's grid and its extensions in floe length)")
    ap.add_argument("--runs", default=str(ROOT / "results" / "surrogate" / "calibration"
                                          / "runs.csv.gz"))
    ap.add_argument("--quadratic", type=int, default=0, metavar="K",
                    help="instead: per quantity, the surrogate itself read quadratically"
                    " along up to K axes, chosen greedily (quadratic_axes)")
    args = ap.parse_args()
    import sweep
    table = pd.concat([sweep.load(g) for g in args.grid], ignore_index=True)
    if args.quadratic:
        return quadratic_axes(table, pd.read_csv(args.runs), args.quadratic, args.grid)
    table["a_end_rel"] = table["a_end"] / table["a0"]
    runs = pd.read_csv(args.runs)
    runs["a_end_rel"] = runs["a_end"] / runs["a0"]
    runs["a_end_rel_stderr"] = runs["a_end_stderr"] / runs["a0"]
    levels = {a: np.sort(table[a].unique().astype(float)) for a in AXES}
    methods = [("linear, log q, log axes", "linear", True, LOG, "linear"),
               ("linear, q, linear axes", "linear", False, set(), "linear"),
               ("linear, log q, linear axes", "linear", True, set(), "linear"),
               ("linear x quadratic L_x, log q, log axes", "linear", True, LOG, "quadratic"),
               ("pchip x quadratic L_x, log q, log axes", "pchip", True, LOG, "quadratic"),
               ("pchip x linear L_x, log q, log axes", "pchip", True, LOG, "linear"),
               ("cubic x quadratic L_x, log q, log axes", "cubic", True, LOG, "quadratic")]
    if len(levels["L_x"]) >= 4:         # enough floe lengths for a cubic along L_x too
        methods += [("linear x pchip L_x, log q, log axes", "linear", True, LOG, "pchip"),
                    ("pchip (all axes), log q, log axes", "pchip", True, LOG, "pchip")]
    print(f"{len(runs)} off-grid points of {args.runs}; grid {' + '.join(args.grid)}"
          f" ({len(levels['L_x'])} levels of L_x)")
    print(f"{'method':42s} " + " ".join(f"{q + ' med':>15s} {'p90':>6s}" for q in QS))
    for name, method, log_q, log_axes, join in methods:
        cells = []
        for q in QS:
            rel = np.full(len(runs), np.nan)
            for d in runs["dispersion"].astype(str).unique():
                m = (runs["dispersion"].astype(str) == d).to_numpy()
                v = grid_arrays(table, d, q, levels)
                pts = {a: runs.loc[m, a].to_numpy(float) for a in AXES}
                if not np.all(np.isfinite(v) & (v > 0)):
                    v = np.where(np.isfinite(v) & (v > 0), v, np.nanmin(v[v > 0]))
                got = interp(method, v, levels, pts, log_q, log_axes, join)
                rel[m] = np.abs(got / runs.loc[m, q].to_numpy(float) - 1)
            ok = np.isfinite(rel)
            med, p90 = 100 * np.median(rel[ok]), 100 * np.quantile(rel[ok], 0.9)
            cells.append(f"{med:14.1f}% {p90:5.1f}%")
        print(f"{name:42s} " + " ".join(cells))
    se = " ".join(f"{q} {100 * np.nanmedian(runs[q + '_stderr'] / runs[q]):.1f} %"
                  for q in QS)
    print(f"median stated SE of the model points: {se}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
