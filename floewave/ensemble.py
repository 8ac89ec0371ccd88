"""Ensembles of floe chains (docs/model.md §4 "Ensembles"): initial arrangements, replica
seeds, and the estimators with their jackknife standard errors.

A point runs R = ``cfg.replicas`` chains. Replica r starts from its own arrangement
(:func:`initial_positions`), drawn from a seed that derives from the configuration
*without* ``replicas``, from ``cfg.seed`` and from r (:func:`replica_seed_sequence`):
the same configuration gives the same arrangements bit for bit, and replica r starts
the same whatever R.

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

import hashlib
import json
import math
import warnings
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._march import march_coefficients
from .collision_stats import collision_statistics, gap_rule_widths, zone_of
from .config import G, ModelConfig
from .results import (
    LAYOUTS,
    Zones,
    fit_exponential,
    fit_inverse,
    jackknife_se,
    zone_fits,
)

__all__ = ["initial_positions", "replica_seed_sequence", "march_rows", "Records", "Iteration",
           "estimate_point", "jackknife_se", "zone_of", "fit_zone", "coefficients",
           "mean_coefficients", "effective_sample_size", "stderr", "residual"]


def replica_seed_sequence(cfg: ModelConfig) -> np.random.SeedSequence:
    """The parent seed sequence of a point's replicas: entropy = SHA-256 of the canonical
    JSON of every field but ``replicas`` (so replica r does not depend on R), then
    ``cfg.seed``. Replica r uses ``.spawn`` child r (spawn keys are (r,))."""
    d = cfg.to_dict()
    d.pop("replicas")
    text = json.dumps(d, sort_keys=True, separators=(",", ":"))
    digest = hashlib.sha256(text.encode("ascii")).digest()
    words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 32, 4)]
    return np.random.SeedSequence([*words, cfg.seed & 0xFFFFFFFF, cfg.seed >> 32])


def initial_positions(cfg: ModelConfig) -> np.ndarray:
    """(R, N_f) initial floe centres [m], the ice edge at x = 0, the first floe's left end
    at 0, gaps g_i between floes i and i + 1 (x_{i+1} = x_i + L_x + g_i).

    ``random``: g_i = (N_f - 1) d_f e_i / sum_j e_j with e_i i.i.d. standard exponential
    (the replica's PCG64 stream by inversion, -log1p(-u)): uniform on the simplex, so every
    gap is >= 0 (no overlap), their mean is d_f and the ice extent is the uniform
    arrangement's.
    ``uniform`` (the paper's): g_i = d_f. Replica 0 is exactly that; replicas r >= 1 are
    that arrangement perturbed, g_i = d_f + 1e-6 (g_i^random - d_f) (a few nanometres per
    gap at d_f = 5 mm), which the chaotic collisions amplify: an ensemble of the paper's
    arrangement. Replica 0 is the same for every seed, so two uniform ensembles are not
    independent (compare uniform with random, not uniform with uniform). With d_f = 0 or
    two floes nothing can differ: one chain runs (``ModelConfig.n_chains``).
    ``confined`` points run one chain at the uniform arrangement.
    """
    n = cfg.n_floes
    R = cfg.n_chains
    uniform = cfg.L_x / 2.0 + np.arange(n) * (cfg.L_x + cfg.d_f)
    out = np.tile(uniform, (R, 1))
    if cfg.confined or n < 2 or cfg.d_f == 0.0:
        return out
    children = replica_seed_sequence(cfg).spawn(R)
    for r in range(R):
        if cfg.placement == "uniform" and r == 0:
            continue
        u = np.random.Generator(np.random.PCG64(children[r])).random(n - 1)
        e = -np.log1p(-u)
        gaps = (n - 1) * cfg.d_f * (e / e.sum())
        if cfg.placement == "uniform":
            gaps = cfg.d_f + 1e-6 * (gaps - cfg.d_f)
        out[r, 1:] = cfg.L_x / 2.0 + np.arange(1, n) * cfg.L_x + np.cumsum(gaps)
    return out


def march_rows(cfg: ModelConfig, S_sd: np.ndarray, c_g: float, k: float) -> np.ndarray:
    """:func:`floewave.model.march_amplitude` for every row of ``S_sd`` (..., N_f) at once
    (same operations per element, so the same bits as the one-row version)."""
    S = np.asarray(S_sd, dtype=float)
    fac = cfg.L_x / (cfg.rho_w * G * c_g)
    a = np.empty_like(S)
    a2 = cfg.a0**2 + fac * S[..., 0]
    a[..., 0] = np.sqrt(np.maximum(a2, 0.0))
    for i in range(1, S.shape[-1]):
        prev = a[..., i - 1]
        a2 = prev * prev + fac * (S[..., i - 1] + S[..., i])
        if cfg.overwash:
            h_ow = cfg.c_ow * np.maximum(k * prev - cfg.s_min, 0.0)
            a2 = a2 - 3.0 * math.sqrt(G) * h_ow**2.5 / c_g
        a[..., i] = np.sqrt(np.maximum(a2, 0.0))
    return a


def residual(a_old: np.ndarray, a_new: np.ndarray) -> float:
    """max_i |a_new - a_old| / a_old over floes with a_old > 0 (0 if there are none): the
    iteration's residual (docs/model.md §4 step 6)."""
    ok = a_old > 0
    if not ok.any():
        return 0.0
    return float(np.max(np.abs(a_new[ok] - a_old[ok]) / a_old[ok]))


def coefficients(S: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Dissipation coefficients c = S_sd / a^3 [W m^-5] of windows run with amplitudes
    ``A`` [m] (same shape); NaN where a = 0 (no wave reached the floe: c not measured)."""
    S = np.asarray(S, dtype=float)
    A = np.asarray(A, dtype=float)
    out = np.full(S.shape, np.nan)
    ok = A > 0
    out[ok] = S[ok] / (A[ok] * A[ok] * A[ok])
    return out


def mean_coefficients(C: np.ndarray, axis: int | tuple = 0) -> np.ndarray:
    """The mean of coefficients ``C`` over ``axis``, ignoring NaN (unmeasured); a floe
    never measured takes its upwave neighbour's value (0 at the ice edge)."""
    C = np.asarray(C, dtype=float)
    ok = np.isfinite(C)
    count = ok.sum(axis=axis)
    total = np.where(ok, C, 0.0).sum(axis=axis)
    m = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    m = np.array(m, dtype=float, ndmin=1)
    for i in range(m.shape[-1]):
        prev = m[..., i - 1] if i > 0 else 0.0
        m[..., i] = np.where(np.isfinite(m[..., i]), m[..., i], prev)
    return m


def effective_sample_size(samples: np.ndarray) -> float:
    """n (1 - rho1) / (1 + rho1) with rho1 the lag-1 autocorrelation pooled over floes."""
    n = samples.shape[0]
    if n < 3:
        return float(n)
    d = samples - samples.mean(axis=0)
    var = (d * d).sum(axis=0)
    ok = var > 0
    if not ok.any():
        return float(n)
    rho = float(np.mean((d[1:, ok] * d[:-1, ok]).sum(axis=0) / var[ok]))
    rho = min(max(rho, 0.0), 0.95)
    return max(n * (1.0 - rho) / (1.0 + rho), 2.0)


def stderr(samples: list[np.ndarray]) -> np.ndarray:
    """Per-floe standard error of the mean of iteration samples (autocorrelation-corrected)."""
    S = np.asarray(samples)
    return S.std(axis=0, ddof=1) / math.sqrt(effective_sample_size(S))


@dataclass
class Iteration:
    """What an attenuation protocol hands :func:`floewave.run_point`.

    status : ``converged``, ``converged_noisy`` or ``not_converged``
        (:data:`floewave.results.STATUSES`).
    estimate : the point's estimates by output name (:func:`estimate_point`, with the
        protocol's ``a_stderr``): the :data:`floewave.outputs.OUTPUTS` it computes.
    history : the update's residual max_i |a_new - a| / a per iteration (or window).
    noise : the residual's noise floor (0 when ``converged``).
    truncation : windows discarded as transient (the stationary protocol; else None).
    """

    status: str
    estimate: dict[str, Any]
    history: list[float]
    noise: float
    truncation: int | None = None


@dataclass
class Records:
    """What the averaging window kept of every replica.

    S : (J, R, N_f) dissipation per averaging iteration and replica [W m^-2]
    a_new : (J, R, N_f) the marched amplitudes per iteration (rows equal under ``mean``)
    profiles : name -> (R, N_f) time mean over the J iterations of each Window field
    W_c, compact_end : (J, R) the compact zone of each iteration's window and replica
        (:func:`zone_of` of that window's mean positions and gaps; NaN: none)
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


def fit_zone(x: np.ndarray, L_x: float, layout: str, W_c: float, end: float,
             ice_extent: float) -> Zones:
    """A :class:`Zones` for fitting from an ensemble's mean bounds: the compact zone runs
    from the pair nearest W_c to the pair nearest its end (pairs sit at x_i + L_x / 2)."""
    n = len(x)
    keep = np.zeros(max(n - 1, 0), dtype=bool)
    if layout == "none" or not math.isfinite(W_c):
        return Zones("none", math.nan, math.nan, ice_extent, keep, (0, 0), 0)
    right = x[:-1] + 0.5 * L_x
    i0 = 0 if W_c <= 0 else int(np.argmin(np.abs(right - W_c)))
    i1 = n - 1 if end >= ice_extent - 1e-9 else int(np.argmin(np.abs(right - end))) + 1
    i1 = max(i1, i0 + 1)
    keep[i0:i1] = True
    return Zones(layout, W_c, end, ice_extent, keep, (i0, i1), 1)


def _majority(layouts: list[str]) -> str:
    """The most common layout; ties go to the earlier entry of :data:`LAYOUTS`."""
    counts = Counter(layouts)
    return max(LAYOUTS, key=lambda name: (counts[name], -LAYOUTS.index(name)))


def estimate_point(cfg: ModelConfig, rec: Records, c_g: float, k: float) -> dict:
    """The point's estimates and their jackknife standard errors from the replicas.

    Returns a dict with the profiles (``a``, ``a_stderr`` and every Window field as the
    replica mean), ``W_c``, ``W_c_stderr``, ``W_c_n``, ``compact_zone``, ``compact_end``,
    ``ice_extent``, the per-replica ``W_c_replicas`` / ``compact_end_replicas``,
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
        if rec.C is not None:         # the march of the mean coefficient (protocol.py)
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
    # the same rule on each replica's gaps time-averaged over the whole averaging, and the
    # ice-wide collision statistics (floewave.collision_stats); no effect on the above
    out.update(gap_rule_widths(cfg, prof))
    out.update(collision_statistics(cfg, prof))
    if R < 2:
        out["a_stderr"] = np.full(len(full["a"]), np.nan)
        for name in fits:
            out[name + "_stderr"] = math.nan
        out["a_end_stderr"] = math.nan
        return out
    loo = []
    for r in range(R):
        sub = np.ones(R, dtype=bool)
        sub[r] = False
        loo.append(estimate(sub))
    out["a_stderr"] = jackknife_se(np.array([e["a"] for e in loo]))
    out["a_end_stderr"] = float(out["a_stderr"][-1])
    for name in fits:
        out[name + "_stderr"] = float(jackknife_se(np.array([e[name][0] for e in loo])))
    return out
