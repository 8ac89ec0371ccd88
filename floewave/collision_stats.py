"""Ice-wide collision statistics of a point, the compact-zone rule of a configuration
(:func:`zone_of`, used per window by the ensemble) and the collision-zone width of the
time-mean gaps (issue 23): per replica from what its averaging windows recorded, then over the
replicas with a delete-one jackknife standard error (docs/output.md, docs/dfscan.md).

Definitions (``prof`` are the (R, N_f) time means over the averaging windows of the
:class:`floewave.iteration.window.Window` fields, per replica; pairs are (i, i + 1), i < N_f - 1):

``contact_fraction_mean`` [1]
    per replica the mean over the N_f - 1 pairs of the fraction of time steps the pair is
    in contact (overlap > 0); the point's value is the mean over the replicas.
``collision_rate`` [collisions per pair per wave period]
    per replica the mean over the pairs of the contact onsets in an averaging window,
    divided by the window's nT periods; the point's value is the mean over the replicas.
``dissipation_per_collision`` [J]
    the skin-drag power (eq. 19: the wave energy sink), P_r = sum_i (-S_sd,i) L_x L_y [W]
    over the N_f floes, divided by the collision frequency of the whole ice,
    N_r = sum over pairs of onsets / (nT T) [s^-1]; the point's value is the ratio of the
    replica means, mean_r P_r / mean_r N_r (NaN with no collision). It is the drag
    dissipation per collision, not the energy lost in the collisions (the kernel does not
    record that).

Standard errors (``*_stderr``): the delete-one jackknife over replicas
(:func:`floewave.errorbars.jackknife_se`; for the two means it is the standard
error of the mean); NaN with one replica. Fixed floes (``confined``) have no collisions:
every collision statistic is NaN.

``W_c_gap`` [m]: :func:`floewave.results.compact_zones`, with the configuration's rule, of
each replica's gaps time-averaged over the whole averaging (``gap_mean_replicas``, at its
``x_mean_replicas``), instead of per averaging window as ``W_c``; the mean over the
replicas that have a compact zone, ``W_c_gap_stderr`` the standard error of that mean (NaN
with fewer than 2 such replicas).
"""
from __future__ import annotations

import math

import numpy as np

from .config import ModelConfig
from .errorbars import jackknife_se
from .results import Zones, compact_zones

__all__ = ["COLLISION_COLUMNS", "GAP_AND_COLLISION_FIELDS", "point_statistics",
           "collision_statistics",
           "replica_collision_records", "gap_zone_width", "gap_rule_widths", "zone_of"]

#: The point's collision statistics (each with a ``*_stderr``).
COLLISION_COLUMNS = ("contact_fraction_mean", "collision_rate", "dissipation_per_collision")
#: Every scalar this module adds to a point's result (the PointResult fields).
GAP_AND_COLLISION_FIELDS = ("W_c_gap", "W_c_gap_stderr",
                            *(c for n in COLLISION_COLUMNS for c in (n, n + "_stderr")))


def replica_collision_records(cfg: ModelConfig, prof: dict[str, np.ndarray]) -> dict:
    """Per replica (arrays of length R): ``contact_fraction`` (pair mean), ``rate``
    (onsets per pair per wave period), ``power`` [W] (skin-drag dissipation summed over the
    floes) and ``frequency`` [s^-1] (onsets per second summed over the pairs)."""
    cf = np.asarray(prof["contact_fraction"], dtype=float)[:, :-1]
    coll = np.asarray(prof["collisions"], dtype=float)[:, :-1]
    s3 = np.asarray(prof["s3_mean"], dtype=float)
    S_sd = -cfg.rho_w * cfg.C_sd * s3                      # eq. 19 [W m^-2], negative
    return {"contact_fraction": cf.mean(axis=1),
            "rate": coll.mean(axis=1) / cfg.nT,
            "power": -(S_sd * (cfg.L_x * cfg.L_y)).sum(axis=1),
            "frequency": coll.sum(axis=1) / (cfg.nT * cfg.T)}


def _ratio(p: np.ndarray, n: np.ndarray) -> float:
    total = float(n.sum())
    return float(p.sum()) / total if total > 0 else math.nan


def collision_statistics(cfg: ModelConfig, prof: dict[str, np.ndarray]) -> dict[str, float]:
    """The point's :data:`COLLISION_COLUMNS` and their ``*_stderr`` (module docstring)
    from the replicas' time-mean profiles ``prof`` (name -> (R, N_f))."""
    names = [c for name in COLLISION_COLUMNS for c in (name, name + "_stderr")]
    out = dict.fromkeys(names, math.nan)
    if cfg.confined or np.asarray(prof["collisions"]).shape[-1] < 2:
        return out
    rec = replica_collision_records(cfg, prof)
    R = len(rec["rate"])
    keep = [np.arange(R) != r for r in range(R)] if R >= 2 else []   # R = 1: SEs NaN
    for name, key in (("contact_fraction_mean", "contact_fraction"),
                      ("collision_rate", "rate")):
        v = rec[key]
        out[name] = float(v.mean())
        out[name + "_stderr"] = float(jackknife_se(np.array([v[k].mean() for k in keep])))
    p, n = rec["power"], rec["frequency"]
    out["dissipation_per_collision"] = _ratio(p, n)
    out["dissipation_per_collision_stderr"] = float(jackknife_se(
        np.array([_ratio(p[k], n[k]) for k in keep])))
    return out


def zone_of(cfg: ModelConfig, x: np.ndarray, gap: np.ndarray) -> Zones:
    """:func:`floewave.results.compact_zones` with the configuration's rule."""
    return compact_zones(x, gap, cfg.L_x, gap_threshold=cfg.gap_threshold,
                         min_pairs=cfg.compact_min_pairs, min_length=cfg.compact_min_length,
                         bridge=cfg.compact_bridge, bridge_gap=cfg.compact_bridge_gap)


def gap_zone_width(cfg: ModelConfig, x_r: np.ndarray,
                   gap_r: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(W_c_gap, W_c_gap_stderr, per-replica values) from the replicas' time-mean positions
    ``x_r`` and gaps ``gap_r`` (R, N_f): the compact-zone rule per replica, the mean over
    the replicas with a compact zone and the standard error of that mean (NaN if < 2)."""
    W = np.array([zone_of(cfg, x, g).W_c
                  for x, g in zip(np.atleast_2d(x_r), np.atleast_2d(gap_r), strict=True)])
    has = np.isfinite(W)
    m = int(has.sum())
    mean = float(W[has].mean()) if m else math.nan
    se = float(W[has].std(ddof=1) / math.sqrt(m)) if m >= 2 else math.nan
    return mean, se, W


def gap_rule_widths(cfg: ModelConfig, prof: dict[str, np.ndarray]) -> dict[str, float]:
    """``W_c_gap`` and ``W_c_gap_stderr`` (:func:`gap_zone_width`) from the replicas'
    time-mean profiles ``prof`` (name -> (R, N_f)): the W_c rules of
    :data:`floewave.outputs.W_C_RULES` that this module computes."""
    W, se, _ = gap_zone_width(cfg, prof["x_mean"], prof["gap_mean"])
    return {"W_c_gap": W, "W_c_gap_stderr": se}


def point_statistics(cfg: ModelConfig, prof: dict[str, np.ndarray]) -> dict[str, float]:
    """Every output of this module for a point, :data:`GAP_AND_COLLISION_FIELDS`, from the
    replicas' time-mean profiles ``prof`` (name -> (R, N_f)): :func:`gap_rule_widths` and
    :func:`collision_statistics`."""
    return {**gap_rule_widths(cfg, prof), **collision_statistics(cfg, prof)}
