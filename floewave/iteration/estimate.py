"""The point's estimate from the averaged windows of R replicas (docs/model.md §4
"Ensembles", §6): :func:`estimate_point`, with the error bars of :mod:`floewave.errorbars`.

Error bars (:func:`estimate_point`): every reported quantity is a function of the R
replicas' records (the dissipation per averaging iteration, the time-mean gaps and
positions, ...). Its standard error is the delete-one jackknife over replicas,
``sqrt((R - 1) / R * sum_r (theta_(-r) - mean_r theta_(-r))^2)`` (Efron & Stein 1981;
for a mean it is exactly the standard error of the mean). ``W_c`` is a property of one
averaging window (the paper's: where the window's mean gaps drop below 1e-4 m): it is found
in every window of every replica, averaged over each replica's windows, then over the
replicas that have a compact zone, with the standard error of that mean.
``benchmarks/honesty.py`` checks these error bars against independent ensembles
(docs/convergence.md "Ensembles and error bars").
"""
from __future__ import annotations

import math
import warnings
from collections import Counter
from dataclasses import dataclass

import numpy as np

from .._march import march_coefficients, march_rows, mean_coefficients
from ..collision_stats import point_statistics
from ..config import ModelConfig
from ..errorbars import jackknife_se, max_stderr, stderr
from ..results import LAYOUTS, fit_exponential, fit_inverse, fit_zone, zone_fits
from .result import ESTIMATED, Estimate
from .window import FIELDS

__all__ = ["Records", "estimate_point", "windows_estimate", "targets_met", "SE_FLOOR",
           "samples_records", "precise_enough"]

#: the smallest standard error of a reported, as a fraction of a0: below it two runs of a
#: non-chaotic point (replicas agreeing to rounding) differ by more than their jackknife
#: says (measured: 1e-9 a0 apart with standard errors of 1e-11 to 1e-10 a0)
SE_FLOOR = 1e-6


@dataclass
class Records:
    """What the averaging window kept of every replica.

    S : (J, R, N_f) dissipation per averaging iteration and replica [W m^-2]
    a_new : (J, R, N_f) the marched amplitudes per iteration (rows equal under ``mean``)
    profiles : name -> (R, N_f) time mean over the J iterations of each Window field
    W_c, compact_end : (J, R) the compact zone of each iteration's window and replica
        (:func:`floewave.collision_stats.zone_of` of that window's mean positions and
        gaps; NaN: none)
    layouts : J lists of R layouts of those zones
    C : (J, R, N_f) dissipation coefficients S / a^3 of each window (the stationary
        protocol; ``a`` is then the march of their mean, not a mean of ``a_new``)
    """

    S: np.ndarray
    a_new: np.ndarray
    profiles: dict[str, np.ndarray]
    W_c: np.ndarray
    compact_end: np.ndarray
    layouts: list[list[str]]
    C: np.ndarray | None = None


def _majority(layouts: list[str]) -> str:
    """The most common layout; ties go to the earlier entry of :data:`LAYOUTS`."""
    counts = Counter(layouts)
    return max(LAYOUTS, key=lambda name: (counts[name], -LAYOUTS.index(name)))


def estimate_point(cfg: ModelConfig, rec: Records, c_g: float, k: float) -> Estimate:
    """The point's estimates and their jackknife standard errors from the replicas.

    Returns the :class:`~floewave.iteration.result.Estimate` with the profiles (``a``,
    ``a_stderr`` and every Window field that is an output, as the replica mean), ``W_c``,
    ``W_c_stderr``, ``W_c_n``, ``compact_zone``, ``compact_end``, ``ice_extent``, the
    per-replica ``W_c_replicas`` / ``compact_end_replicas``,
    the other W_c rules (:func:`floewave.collision_stats.gap_rule_widths`: the rule on
    each replica's time-mean gaps) and the collision statistics
    (:func:`floewave.collision_stats.collision_statistics`) with their ``*_stderr``, the
    fits ``alpha_*`` with ``alpha_*_resid`` and ``alpha_*_stderr`` and ``a_end`` with
    ``a_end_stderr``. ``W_c_n`` is the number of replicas whose W_c entered the mean (0
    when the point's layout is ``none``: W_c is then NaN whatever some windows saw).
    Leave-one-out estimates recompute everything, the layout included; a leave-one-out
    value that is NaN (e.g. the layout flips to ``none``) makes that standard error NaN:
    the estimator is not stable enough for an error bar. With R = 1 every standard error
    is NaN (the caller supplies the single trajectory's iteration standard error of ``a``).
    """
    R = rec.S.shape[1]
    prof = rec.profiles
    # W_c as the paper defines it is a property of one nT-period window (the mean gaps over
    # that window): found per window and replica, averaged over a replica's windows (so its
    # expectation does not depend on how many iterations were averaged), then over replicas
    def layout_of(sub: np.ndarray) -> str:
        return _majority([row[r] for row in rec.layouts for r in np.flatnonzero(sub)])

    layout = layout_of(np.ones(R, dtype=bool))
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)          # all-NaN columns
        W_r = np.nanmean(rec.W_c, axis=0)
        end_r = np.nanmean(rec.compact_end, axis=0)
    has = np.isfinite(W_r)

    def estimate(sub: np.ndarray) -> dict:
        if rec.C is not None:         # the march of the mean coefficient (stationary.py)
            a = march_coefficients(cfg, mean_coefficients(rec.C[:, sub, :], (0, 1)),
                                   c_g, k)
        elif cfg.coupling == "mean":
            a_j = march_rows(cfg, rec.S[:, sub, :].mean(axis=1), c_g, k)   # (J, N_f)
            a = a_j.mean(axis=0)
        else:
            a = rec.a_new[:, sub, :].mean(axis=(0, 1))
        x = prof["x_mean"][sub].mean(axis=0)
        ice = float(x[-1] + 0.5 * cfg.L_x)
        s = sub & has
        lay = layout_of(sub)          # the whole estimator, the layout included
        if lay == "none" or not s.any():
            W_c = end = math.nan
        else:
            W_c, end = float(W_r[s].mean()), float(end_r[s].mean())
        zone = fit_zone(x, cfg.L_x, lay, W_c, end, ice)
        al, rl = fit_inverse(x, a, cfg.a0)
        ae, re_, ai, ri = zone_fits(x, a, cfg.a0, zone, min_floes=cfg.fit_min_floes,
                                    min_length=cfg.fit_min_length)
        if lay != layout:             # another layout: not the same zone fits (no SE)
            ae = re_ = ai = ri = math.nan
        ax, rx = fit_exponential(x, a, cfg.a0)
        return {"a": a, "x": x, "ice": ice, "W_c": W_c, "end": end,
                "alpha_all": (al, rl), "alpha_edge": (ae, re_), "alpha_inner": (ai, ri),
                "alpha_exp": (ax, rx)}

    full = estimate(np.ones(R, dtype=bool))
    out: dict = {name: prof[name].mean(axis=0) for name in prof}
    out["S_sd"] = -cfg.rho_w * cfg.C_sd * out["s3_mean"]          # eq. 19 of the mean
    out.update(x_mean_replicas=prof["x_mean"], gap_mean_replicas=prof["gap_mean"],
               S_sd_replicas=rec.S.mean(axis=0))
    out.update(a=full["a"], x_mean=full["x"], ice_extent=full["ice"], compact_zone=layout,
               W_c=full["W_c"], compact_end=full["end"],
               W_c_n=int(has.sum()) if layout != "none" else 0,
               W_c_replicas=W_r, compact_end_replicas=end_r, a_end=float(full["a"][-1]))
    fits = ("alpha_all", "alpha_edge", "alpha_inner", "alpha_exp")
    for name in fits:
        out[name], out[name + "_resid"] = full[name]
    m = int(has.sum())
    if layout != "none" and m >= 2:
        out["W_c_stderr"] = float(W_r[has].std(ddof=1) / math.sqrt(m))
    else:
        out["W_c_stderr"] = math.nan
    if R < 2:
        out["a_stderr"] = np.full(len(full["a"]), np.nan)
        for name in fits:
            out[name + "_stderr"] = math.nan
        out["a_end_stderr"] = math.nan
    else:
        loo = []
        for r in range(R):
            sub = np.ones(R, dtype=bool)
            sub[r] = False
            loo.append(estimate(sub))
        out["a_stderr"] = jackknife_se(np.array([e["a"] for e in loo]))
        out["a_end_stderr"] = float(out["a_stderr"][-1])
        for name in fits:
            out[name + "_stderr"] = float(jackknife_se(np.array([e[name][0] for e in loo])))
    # the same rule on each replica's gaps time-averaged over the whole averaging, and the
    # ice-wide collision statistics (floewave.collision_stats); no effect on the above
    out.update(point_statistics(cfg, prof))
    return _typed(out)


def _typed(out: dict) -> Estimate:
    """The :class:`Estimate` of ``out`` (its fields by name; the Window means that are no
    output, ``s3_mean``, stay behind)."""
    return Estimate(**{o.name: out[o.name] for o in ESTIMATED})


def _with_convergence(cfg: ModelConfig, est: Estimate, a_new: np.ndarray,
                      a_old: np.ndarray) -> Estimate:
    """An ensemble's SE(a) with the change of the replica-mean forcing in the last update,
    |mean_r (a_new - a)|, in quadrature (signed changes of single replicas cancel: it is how
    far the pooled estimate was still moving, which the jackknife alone does not see) and
    at least :data:`SE_FLOOR` a0."""
    if cfg.n_chains < 2:
        return est
    conv = np.abs(np.mean(a_new - a_old, axis=0))
    se = np.sqrt(np.asarray(est.a_stderr, dtype=float) ** 2 + conv**2)
    est.a_stderr = np.maximum(se, SE_FLOOR * cfg.a0)
    est.a_end_stderr = float(est.a_stderr[-1])
    return est


def windows_estimate(cfg: ModelConfig, wins, d: int, c_g: float, k: float,
                     a_new: np.ndarray) -> Estimate:
    """The stationary protocol's estimate of its windows after d
    (:class:`floewave.iteration.windows.Windows`) that last marched ``a_new``:
    :func:`estimate_point` of their records; with R = 1 ``a_stderr`` the
    autocorrelation-corrected standard error of the profiles the windows imply, else
    with the last update's change in quadrature (:func:`_with_convergence`)."""
    est = estimate_point(cfg, wins.records(d), c_g, k)
    if cfg.n_chains == 1:
        # one trajectory: the windows' implied profiles, autocorrelation-corrected
        per = [implied[0] for implied in wins.implied[d:]]
        est.a_stderr = (stderr(per) if len(per) > 1
                        else np.full(cfg.n_floes, np.nan))
        est.a_end_stderr = float(est.a_stderr[-1])
    return _with_convergence(cfg, est, a_new, wins.A[-1])


def targets_met(cfg: ModelConfig, est: Estimate) -> bool:
    """Does the stationary protocol's estimate meet the error-bar targets: max_i SE(a_i) <=
    ``target_stderr`` a0 and, with a compact zone in at least two replicas, SE(W_c) <=
    ``target_W_c_stderr`` (a target <= 0 is no condition)."""
    if cfg.target_stderr > 0:
        se = np.asarray(est.a_stderr, dtype=float)
        if not np.all(np.isfinite(se)) or float(np.max(se)) > cfg.target_stderr * cfg.a0:
            return False
    se_w = est.W_c_stderr
    if cfg.target_W_c_stderr > 0 and est.compact_zone != "none" and est.W_c_n >= 2:
        return bool(np.isfinite(se_w) and se_w <= cfg.target_W_c_stderr)
    return True


def samples_records(kept: list[tuple]) -> Records:
    """The noise-floor protocol's samples, (S, a_new, windows, zones) per averaging
    iteration, as :class:`Records`."""
    S = np.array([s[0] for s in kept])
    a_new = np.array([s[1] for s in kept])
    profiles = {}
    for name in FIELDS:
        total = 0.0
        for sample in kept:
            total = total + np.array([getattr(w, name) for w in sample[2]])
        profiles[name] = total / len(kept)
    zones = [sample[3] for sample in kept]
    return Records(S, a_new, profiles,
                   np.array([[z.W_c for z in row] for row in zones]),
                   np.array([[z.compact_end for z in row] for row in zones]),
                   [[z.layout for z in row] for row in zones])


def precise_enough(cfg: ModelConfig, samples: list, c_g: float,
                   k: float) -> tuple[bool, Estimate | None]:
    """May the noise-floor protocol's averaging stop? max_i SE(a_i) <= ``target_stderr`` a0
    (the iteration standard error for one trajectory, the jackknife over replicas for an
    ensemble) and, for an ensemble with a compact zone in at least two replicas, SE(W_c) <=
    ``target_W_c_stderr``. A target <= 0 is no condition. Also returns the ensemble's
    estimate when it was computed (the point's, if the averaging stops here)."""
    if cfg.n_chains == 1:
        return (cfg.target_stderr <= 0
                or max_stderr([s[1][0] for s in samples]) <= cfg.target_stderr * cfg.a0), None
    if cfg.target_stderr <= 0 and cfg.target_W_c_stderr <= 0:
        return True, None
    est = estimate_point(cfg, samples_records(samples), c_g, k)
    if cfg.target_stderr > 0 and float(np.max(est.a_stderr)) > cfg.target_stderr * cfg.a0:
        return False, est
    se_w = est.W_c_stderr
    return (cfg.target_W_c_stderr <= 0 or not math.isfinite(se_w)
            or se_w <= cfg.target_W_c_stderr), est
