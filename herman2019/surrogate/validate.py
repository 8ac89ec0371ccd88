"""Off-grid points run with the model, to fit the surrogate's interpolation-error scale
(the *calibration* sets) and to check it (the *validation* sets, never fitted on: which
sets play which role, :data:`ROLES`).

**The points** (:func:`draw_points`): uniform inside the grid's box in each axis's
interpolation coordinate (log for L_x, a0, C_sd, d_f: the coordinate the grid's levels
and the surrogate use, so every cell of the grid is drawn about equally often), rounded
where the model needs it (T to 4 ms: T/dt an integer multiple of ``drag_every`` = 4
steps; L_x to 1 cm, a multiple of dx) and elsewhere to 6 significant digits, the
dispersion relation uniform over the three. The ``axes`` sets (:func:`draw_axis_points`)
move one axis alone, the others at
grid nodes. Each is run at the model's defaults (the released ones: ``configs/
herman2019.toml``'s ``[base]``) and ``seed`` 0, as the grid's points were, by
:func:`herman2019.calibration.run_sample` (resumable; one row per point).

**The statistic** (:func:`compare`): per quantity, in log (so relative),
z = (log q_surrogate - log q_model) / sqrt(se_surrogate^2 + se_model^2), with the
model point's calibrated SE (its factor read between the calibrated levels); W_c where the
model point has a compact zone and the surrogate's cell has one at a corner.
:func:`fit_scale` fits the interpolation error's scales and combination on the
calibration sets. :func:`error_table` gives, on a validation set, RMS z, the median and
90th percentile of |q_surrogate / q_model - 1|, median |z|, the shares beyond |z| 2 and 4;
:func:`reliability` and :func:`brier` check p_zone against the points' outcomes.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from herman2019.surrogate.grid import AXES, DISPERSIONS, coordinate
from herman2019.surrogate.model import QUANTITIES, Surrogate, combine

__all__ = ["SETS", "draw_points", "model_table", "compare", "fit_scale", "error_table",
           "reliability", "brier", "by_region"]

#: The off-grid sets: name -> (kind, size, draw seed). ``random``: that many points uniform
#: in the box (:func:`draw_points`); ``axes``: that many grid nodes per axis with the axis
#: alone moved off its levels (:func:`draw_axis_points`). Their draw seeds differ (no
#: point is shared: tested). The calibration sets fit the error model, the validation
#: sets check it.
SETS = {"calibration": ("random", 300, 4801), "calibration_axes": ("axes", 24, 4803),
        "validation": ("random", 300, 4802), "validation_axes": ("axes", 24, 4804),
        "blind": ("random", 300, 4805), "blind_axes": ("axes", 24, 4806)}
#: The sets of each role, by the name of their random set (each with its axes set:
#: :func:`set_names`), in the order they were drawn. The first validation sets
#: ("validation", "validation_axes...") were looked at point by point: their worst residuals
#: showed the error model's missing term (a corner without a value, 2026-12-07), so they
#: joined the calibration, and the check is on sets drawn after that change and looked at
#: only by the check itself ("blind").
ROLES = {"calibration": ("calibration", "validation"), "validation": ("blind",)}
#: Every set's random name, in the order drawn (an axes set draws none of the nodes of
#: the axes sets before it).
DRAWN = ("calibration", "validation", "blind")
#: Off-node values per axis for the ``axes`` sets (on the model's lattices; those on a
#: grid's nodes are left out).
AXIS_VALUES = {"L_x": (0.6, 0.75, 1.0, 1.25, 2.0, 2.5, 2.75),
               "T": (1.152, 1.252, 1.3, 1.452, 1.7, 1.9),
               "a0": (0.0135, 0.0175, 0.0225),
               "C_sd": (0.0075, 0.025, 0.075, 0.125, 0.175),
               "eps": (0.3, 0.5, 0.7),
               "d_f": (0.007, 0.014, 0.035)}
#: More floe lengths for the ``_axes_lx<n>`` sets of a grid with more levels of L_x (with
#: L_x 0.75, 1.0, 1.25, 2.0, 2.5 among them, each of its intervals keeps a value or more).
MORE_LX = (0.87, 1.12, 1.37, 1.73, 2.24)
#: The lattices the model's T and L_x live on: T/dt a multiple of drag_every (0.001 s x
#: 4), L_x/dx an integer (dx 0.01 m).
T_STEP, L_STEP = 0.004, 0.01


def draw_points(levels: Mapping[str, np.ndarray], n: int, seed: int) -> pd.DataFrame:
    """``n`` points uniform in the box (module docstring), with ``group`` = "offgrid"."""
    rng = np.random.default_rng(seed)
    cols = {}
    for a in AXES:
        lo, hi = coordinate(a, [levels[a][0], levels[a][-1]])
        u = rng.uniform(lo, hi, n)
        cols[a] = np.exp(u) if a in ("L_x", "a0", "C_sd", "d_f") else u
    cols["T"] = np.round(np.round(cols["T"] / T_STEP) * T_STEP, 3)
    cols["L_x"] = np.round(np.round(cols["L_x"] / L_STEP) * L_STEP, 2)
    for a in ("a0", "C_sd", "eps", "d_f"):      # 6 significant digits: a config
        cols[a] = np.array([float(f"{v:.6g}") for v in cols[a]])   # a reader can retype
    cols["dispersion"] = rng.choice(np.array(DISPERSIONS), n)
    out = pd.DataFrame(cols)[[*AXES, "dispersion"]]
    out["group"] = "offgrid"
    return out


def draw_axis_points(levels: Mapping[str, np.ndarray], n: int, seed: int,
                     values: Mapping[str, Sequence[float]] | None = None,
                     exclude: frozenset = frozenset()) -> pd.DataFrame:
    """For each axis, ``n`` grid nodes of the other five axes and the dispersion relation
    drawn at random, each with the axis at every one of its ``values`` (default
    :data:`AXIS_VALUES`) off the grid's levels: points where the surrogate interpolates
    along that axis alone (``group`` = "axis:<name>"). A node already drawn for the axis,
    or in ``exclude`` (pairs (axis, node) of :func:`axis_nodes`: another set's), is drawn
    again."""
    rng = np.random.default_rng(seed)
    values = AXIS_VALUES if values is None else values
    rows = []
    for axis in AXES:
        taken = set()
        for _ in range(n):
            while True:
                base = {a: float(rng.choice(levels[a])) for a in AXES if a != axis}
                d = str(rng.choice(np.array(DISPERSIONS)))
                key = (axis, _node_key(base, d))
                if key not in taken and key not in exclude:
                    break
            taken.add(key)
            rows += [{**base, axis: v, "dispersion": d, "group": f"axis:{axis}"}
                     for v in values[axis]
                     if not np.any(np.isclose(v, levels[axis]))]   # off the nodes only
    return pd.DataFrame(rows)[[*AXES, "dispersion", "group"]]


def _node_key(base: Mapping[str, float], d: str) -> tuple:
    return (*(repr(float(base[a])) for a in AXES if a in base), d)


def axis_nodes(points: pd.DataFrame) -> frozenset:
    """The (axis, node) pairs of an ``axes`` set's points (:func:`draw_axis_points`)."""
    out = set()
    for row in points.itertuples(index=False):
        axis = str(row.group).removeprefix("axis:")
        base = {a: float(getattr(row, a)) for a in AXES if a != axis}
        out.add((axis, _node_key(base, str(row.dispersion))))
    return frozenset(out)


def set_names(levels: Mapping[str, np.ndarray], role: str) -> tuple[str, ...]:
    """The sets of ``role`` ("calibration" or "validation", :data:`ROLES`) for a grid of
    these levels: per name of :data:`ROLES`, the random set and the axes one of the
    paper's grid (three levels of L_x) or, for a grid with more floe lengths, its own
    (``<name>_axes_lx<n>``: its base nodes are drawn from other levels, and its L_x values
    must lie off them)."""
    n = len(levels["L_x"])
    return tuple(s for name in ROLES[role]
                 for s in (name, f"{name}_axes" if n == 3 else f"{name}_axes_lx{n}"))


def set_spec(name: str) -> tuple[str, int, int]:
    """(kind, size, draw seed) of the set ``name``: :data:`SETS`, or an ``_axes_lx<n>``
    set (24 nodes per axis, the seed of its role's axes set + 100 n)."""
    if name in SETS:
        return SETS[name]
    base, _, n = name.rpartition("_lx")
    kind, size, seed = SETS[base]
    return kind, size, seed + 100 * int(n)


def draw_set(name: str, levels: Mapping[str, np.ndarray]) -> pd.DataFrame:
    """The points of the set ``name`` (:func:`set_spec`). An ``_axes_lx<n>`` set moves L_x
    over :data:`MORE_LX` too; an ``axes`` set draws none of the nodes of the axes sets
    drawn before it (:data:`DRAWN`: so that no point is fitted and checked at once)."""
    kind, n, seed = set_spec(name)
    if kind == "random":
        return draw_points(levels, n, seed)
    values = dict(AXIS_VALUES)
    if "_lx" in name:
        values["L_x"] = tuple(sorted(set(AXIS_VALUES["L_x"]) | set(MORE_LX)))
    exclude = frozenset()
    first, _, tail = name.partition("_axes")
    for before in DRAWN[:DRAWN.index(first)]:
        exclude |= axis_nodes(draw_set(f"{before}_axes{tail}", levels))
    return draw_axis_points(levels, n, seed, values, exclude)


def model_table(runs: pd.DataFrame) -> pd.DataFrame:
    """The runs' rows with ``a_end_rel`` and every quantity's calibrated SE ``q_se`` (off
    the grid's levels of L_x, C_sd, d_f the factor read between the calibrated levels
    around the point: :func:`herman2019.factors.factors_between`)."""
    from herman2019.factors import calibrated_factors, factors_between
    fac = calibrated_factors()
    out = runs.copy()
    out["a_end_rel"] = out["a_end"] / out["a0"]
    out["a_end_rel_stderr"] = out["a_end_stderr"] / out["a0"]
    for q in QUANTITIES:
        base = "a_end" if q == "a_end_rel" else q
        f = factors_between(out, fac, base)
        out[q + "_se"] = out[q + "_stderr"].to_numpy(float) * np.nan_to_num(f, nan=1.0)
    done = out["status"].astype(str).isin(["converged", "converged_noisy", "not_converged"])
    out["zone"] = np.where(done, (out["layout"].astype(str) != "none").astype(float), np.nan)
    return out


def compare(sur: Surrogate, model: pd.DataFrame) -> pd.DataFrame:
    """The surrogate beside the model at the model table's points: per quantity the
    surrogate's value and SE (``q_sur``, ``q_sur_se``; its parts ``q_se_noise``,
    ``q_se_interp``), the model's (``q``, ``q_se``), and ``q_z`` (module docstring)."""
    pred = sur.predict(model["dispersion"].astype(str).to_numpy(), detail=True,
                       **{a: model[a].to_numpy(float) for a in AXES})
    out = model.reset_index(drop=True).copy()
    out["p_zone"] = pred["p_zone"].to_numpy()
    for q in QUANTITIES:
        out[q + "_sur"] = pred[q].to_numpy()
        out[q + "_sur_se"] = pred[q + "_se"].to_numpy()
        out[q + "_se_noise"] = pred[q + "_se_noise"].to_numpy()
        out[q + "_se_interp"] = pred[q + "_se_interp"].to_numpy()
        out[q + "_z"] = _z(out, q)
    return out


def _z(cmp: pd.DataFrame, q: str) -> np.ndarray:
    """z of ``q``: the log residual over the surrogate's and the model point's SEs."""
    x, y = cmp[q + "_sur"].to_numpy(float), cmp[q].to_numpy(float)
    noise, interp = cmp[q + "_se_noise"].to_numpy(float), cmp[q + "_se_interp"].to_numpy(float)
    rel_model = cmp[q + "_se"].to_numpy(float) / y
    with np.errstate(invalid="ignore", divide="ignore"):
        z = (np.log(x) - np.log(y)) / np.sqrt(noise**2 + interp**2
                                                + rel_model**2)
    ok = np.isfinite(z) & (y > 0)
    if q == "W_c":
        ok &= cmp["zone"].to_numpy() > 0
    return np.where(ok, z, np.nan)


#: The fit's pull of each term's log-scale towards their mean (a term with few points
#: that see it takes about the others' scale).
RIDGE = 1.0
#: The fit's starts for the flat terms' log-scales (the others start at 0); the start of
#: least negative log-likelihood wins. From 0 alone (a flat error of 100 %) the optimiser
#: drove every flat term of alpha_all to its lower bound, where the likelihood is flat in
#: them, and stopped there; from 1 % it found scales of 2-4 % and a likelihood higher by
#: far (the outliers along one axis where the nodes show no curvature: 2026-12-07).
FLAT_STARTS = (0.0, float(np.log(0.01)))
#: The largest power p of the terms' combination (sum v^(p/2))^(2/p): about the largest.
MAX_POWER = 64.0


def power(theta: float) -> float:
    """The combination's power p = 2 + exp(theta) (>= 2: at least as concentrated as a
    sum of independent variances), at most MAX_POWER."""
    return float(min(2.0 + np.exp(theta), MAX_POWER))


def fit_scale(sur: Surrogate, calibration: pd.DataFrame) -> dict[str, float]:
    """Fit the interpolation error's model on the calibration sets: per quantity one
    scale per term of :meth:`Surrogate.term_names` (each axis, curvature and flat; each
    interval of the axes of ``meta["intervals"]`` apart; the missing corners') and the power
    p of their combination, by maximum likelihood of
    the log residuals as normal with variance noise + (sum (scale^2 term)^(p/2))^(2/p)
    (a ridge of :data:`RIDGE` on the log-scales, the curvature terms' about their mean,
    the flat terms' about theirs, ``missing`` alone; the better of the starts of
    :data:`FLAT_STARTS`), then one common factor so that the mean over the
    calibration sets' kinds (``group``: uniform in the box, one axis alone) of their mean
    z^2 is 1, each kind weighing the same whatever its size. Parameters that end on a
    bound of the fit are listed in ``sur.meta["at_bound"]``. Also p_zone's
    recalibration (:func:`fit_p_zone`). Sets ``sur.scale`` and ``sur.meta``; returns the
    scales."""
    from scipy.optimize import minimize
    sur.meta.pop("p_zone", None)
    pred = sur.predict(calibration["dispersion"].astype(str).to_numpy(), detail="terms",
                       **{a: calibration[a].to_numpy(float) for a in AXES})
    names = sur.term_names()
    flat = np.array([n.endswith(":flat") for n in names])
    miss = np.array([n == "missing" for n in names])
    groups = (~flat & ~miss, flat, miss)       # the ridge pulls each group to its mean
    kind_all = np.where(calibration["group"].astype(str).str.startswith("axis:"), "axes",
                        "random") if "group" in calibration else np.full(len(calibration),
                                                                         "random")
    bounds = [(-12.0, 6.0)] * len(names) + [(-6.0, float(np.log(MAX_POWER - 2)))]
    sur.meta["at_bound"] = []
    for q in QUANTITIES:
        y = calibration[q].to_numpy(float)
        x = pred[q].to_numpy(float)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.log(x) - np.log(y)
            noise = (pred[q + "_se_noise"].to_numpy(float) ** 2
                     + (calibration[q + "_se"].to_numpy(float) / y) ** 2)
        terms = np.stack([pred[f"{q}_term_{n}"].to_numpy(float) for n in names], axis=1)
        ok = np.isfinite(r) & np.isfinite(noise) & np.all(np.isfinite(terms), axis=1)
        if q == "W_c":
            ok &= calibration["zone"].to_numpy() > 0
        r, noise, terms, kind = r[ok], noise[ok], terms[ok], kind_all[ok]
        seen = terms.sum(axis=0) > 0

        def var(p, c=1.0, noise=noise, terms=terms):
            return noise + c * c * combine(terms * np.exp(2 * p[:-1]), power(p[-1]))

        def ridge(s, seen=seen):
            out = 0.0
            for group in groups:
                group = group & seen
                if group.any():
                    out += float(np.sum((s[group] - s[group].mean()) ** 2))
            return RIDGE * out

        def nll(p, r=r, var=var, ridge=ridge):
            v = var(p)
            return float(np.sum(np.log(v) + r * r / v)) + ridge(p[:-1])
        fits = [minimize(nll, np.append(np.where(flat, start, 0.0), 0.0), method="L-BFGS-B",
                         bounds=bounds) for start in FLAT_STARTS]
        p = min(fits, key=lambda f: f.fun).x
        # a term no calibration point sees takes its group's mean log-scale, or 0 (a
        # scale of the common factor) when none of the group is seen: for ``missing``
        # (alpha_all: no node lacks a value; a_end_rel: one node of ow) a corner without
        # a value then costs up to its weight in relative error, on purpose (nothing
        # measured the reading there; an error bar of 0 would claim it exact)
        for group in groups:
            fill = p[:-1][seen & group]
            p[:-1][~seen & group] = fill.mean() if fill.size else 0.0
        sur.meta["at_bound"] += [f"{q}:{n}" for n, v, (lo, hi)
                                 in zip((*names, "p"), p, bounds, strict=True)
                                 if (v <= lo + 1e-6 or v >= hi - 1e-6)
                                 and (n == "p" or seen[names.index(n)])]
        s2 = np.exp(2 * p[:-1])
        kinds = [k for k in ("random", "axes") if (kind == k).any()]

        def excess(c, p=p, r=r, kind=kind, kinds=kinds, var=var):
            v = var(p, c)
            return float(np.mean([np.mean(r[kind == k] ** 2 / v[kind == k])
                                  for k in kinds])) - 1
        if excess(0.0) <= 0:
            c = 0.0
        else:
            hi = 1.0
            while excess(hi) > 0 and hi < 1e6:
                hi *= 2
            c = brentq(excess, 0.0, hi, xtol=1e-8) if excess(hi) <= 0 else hi
        sur.meta.setdefault("combine", {})[q] = power(p[-1])
        sur.scale.pop(q, None)
        for n, sj in zip(names, np.sqrt(s2), strict=True):
            sur.scale[f"{q}:{n}"] = float(c * sj)
    sur.meta["p_zone"] = fit_p_zone(pred["p_zone"].to_numpy(float),
                                    calibration["zone"].to_numpy(float))
    return dict(sur.scale)


def fit_p_zone(p: np.ndarray, zone: np.ndarray) -> list[float]:
    """(a, b) of p' = 1 / (1 + exp(-(a + b logit p))) by maximum likelihood on the points
    with 0 < p < 1 (a cell whose corners all agree keeps its 0 or 1)."""
    from scipy.optimize import minimize
    m = (p > 0) & (p < 1) & np.isfinite(zone)
    if m.sum() < 10:
        return [0.0, 1.0]
    lg, o = np.log(p[m] / (1 - p[m])), zone[m]

    def nll(ab):
        z = ab[0] + ab[1] * lg
        return float(np.sum(np.logaddexp(0, z) - o * z))
    return [float(v) for v in minimize(nll, np.array([0.0, 1.0]), method="Nelder-Mead").x]


def error_table(cmp: pd.DataFrame, quantities: Sequence[str] = QUANTITIES) -> pd.DataFrame:
    """Per quantity on ``cmp`` (:func:`compare`): points, RMS z with its 95 % interval (as
    if z were normal), median and 90th percentile of the relative error, its median
    stated SE, median |z| (0.67 for a normal z), the share beyond |z| 2 (4.6 %) and the
    points beyond |z| 4."""
    from scipy.stats import chi2
    rows = []
    for q in quantities:
        z = cmp[q + "_z"].to_numpy(float)
        ok = np.isfinite(z)
        n = int(ok.sum())
        rel = np.abs(cmp[q + "_sur"].to_numpy(float)[ok] / cmp[q].to_numpy(float)[ok] - 1)
        se_rel = cmp[q + "_sur_se"].to_numpy(float)[ok] / cmp[q + "_sur"].to_numpy(float)[ok]
        ss = float(np.sum(z[ok] ** 2))
        rows.append({"quantity": q, "points": n,
                     "rms_z": np.sqrt(ss / n) if n else np.nan,
                     "rms_z_lo": np.sqrt(ss / chi2.ppf(0.975, n)) if n else np.nan,
                     "rms_z_hi": np.sqrt(ss / chi2.ppf(0.025, n)) if n else np.nan,
                     "median_rel_error": float(np.median(rel)) if n else np.nan,
                     "p90_rel_error": float(np.quantile(rel, 0.9)) if n else np.nan,
                     "median_rel_se": float(np.median(se_rel)) if n else np.nan,
                     "median_abs_z": float(np.median(np.abs(z[ok]))) if n else np.nan,
                     "beyond_2": float(np.mean(np.abs(z[ok]) > 2)) if n else np.nan,
                     "beyond_4": int(np.sum(np.abs(z[ok]) > 4))})
    return pd.DataFrame(rows)


def by_region(cmp: pd.DataFrame, q: str = "alpha_all", bins: int = 3) -> pd.DataFrame:
    """Where in the box the surrogate is worst: per axis, the validation points split into
    ``bins`` equal parts of the axis's coordinate, and per dispersion relation; in each,
    points, RMS z and median relative error of ``q``."""
    rows = []
    z = cmp[q + "_z"].to_numpy(float)
    rel = np.abs(cmp[q + "_sur"].to_numpy(float) / cmp[q].to_numpy(float) - 1)
    ok = np.isfinite(z)
    for a in AXES:
        u = coordinate(a, cmp[a].to_numpy(float))
        edges = np.linspace(u.min(), u.max(), bins + 1)
        part = np.clip(np.searchsorted(edges, u, side="right") - 1, 0, bins - 1)
        for b in range(bins):
            lo, hi = edges[b], edges[b + 1]
            if a in ("L_x", "a0", "C_sd", "d_f"):
                lo, hi = np.exp(lo), np.exp(hi)
            m = ok & (part == b)
            rows.append({"region": f"{a} {lo:.4g}-{hi:.4g}", "points": int(m.sum()),
                         "rms_z": float(np.sqrt(np.mean(z[m] ** 2))) if m.any() else np.nan,
                         "median_rel_error": float(np.median(rel[m])) if m.any() else np.nan})
    for d in DISPERSIONS:
        m = ok & (cmp["dispersion"].astype(str).to_numpy() == d)
        rows.append({"region": f"dispersion {d}", "points": int(m.sum()),
                     "rms_z": float(np.sqrt(np.mean(z[m] ** 2))) if m.any() else np.nan,
                     "median_rel_error": float(np.median(rel[m])) if m.any() else np.nan})
    return pd.DataFrame(rows)


def reliability(cmp: pd.DataFrame, edges: Sequence[float] = (0, 1e-9, 0.1, 0.3, 0.5, 0.7,
                                                              0.9, 1 - 1e-9, 1.0)
                ) -> pd.DataFrame:
    """p_zone against the outcome: per bin of p_zone, points, mean p_zone, the share of
    points with a compact zone and its binomial SE."""
    p, o = cmp["p_zone"].to_numpy(float), cmp["zone"].to_numpy(float)
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        m = (p >= lo) & ((p < hi) if hi < 1.0 else (p <= hi))
        n = int(m.sum())
        share = float(o[m].mean()) if n else np.nan
        rows.append({"p_zone": f"[{lo:.2g}, {hi:.2g}" + ("]" if hi >= 1.0 else ")"),
                     "points": n, "mean_p": float(p[m].mean()) if n else np.nan,
                     "observed": share,
                     "observed_se": float(np.sqrt(share * (1 - share) / n)) if n else np.nan})
    return pd.DataFrame(rows)


def brier(cmp: pd.DataFrame, base_rate: float) -> dict[str, float]:
    """Brier score of p_zone, of the constant ``base_rate`` (the grid's share of points
    with a compact zone), and the skill 1 - ratio."""
    p, o = cmp["p_zone"].to_numpy(float), cmp["zone"].to_numpy(float)
    b = float(np.mean((p - o) ** 2))
    b0 = float(np.mean((base_rate - o) ** 2))
    return {"brier": b, "brier_constant": b0, "skill": 1 - b / b0 if b0 > 0 else np.nan}
