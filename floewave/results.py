"""Per-point results (MODEL.md §6): profiles, collision-zone width and attenuation fits."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["PointResult", "PROFILE_FIELDS", "SCALAR_FIELDS", "collision_zone_width",
           "fit_inverse", "fit_exponential", "power_law"]

#: Per-floe (length N_f) or per-pair (length N_f - 1, padded to N_f with NaN) profiles.
PROFILE_FIELDS = ("x_mean", "a", "a_stderr", "S_sd", "gap_mean", "contact_fraction",
                  "collisions", "F_w_mean", "F_c_mean", "F_d_mean")

#: Scalar results and diagnostics.
SCALAR_FIELDS = ("n_floes", "W_c", "alpha_all", "alpha_all_resid", "alpha_edge",
                 "alpha_edge_resid", "alpha_inner", "alpha_inner_resid", "alpha_exp",
                 "alpha_exp_resid", "alpha_c", "k", "c_g", "status", "noise", "iterations",
                 "residual", "floe_steps", "wall_time", "kernel_mode", "a_end")

STATUSES = ("converged", "converged_noisy", "not_converged")


@dataclass
class PointResult:
    """Everything one model point reports.

    Profiles (numpy arrays of length N_f; per-pair quantities have N_f - 1 values and a
    trailing NaN so every profile has the same length):

    x_mean [m] time-mean floe centre over the last nT window, from the ice edge;
    a [m] converged (or iteration-averaged) amplitude; a_stderr [m] its standard error;
    S_sd [W m^-2] skin-drag dissipation (eq. 19, negative); gap_mean [m] mean gap per pair;
    contact_fraction [-] fraction of time steps in contact per pair; collisions [-] contact
    onsets per pair in the last nT window; F_w_mean, F_c_mean, F_d_mean [N] time-mean
    |F_w|, |F_c| (sum over contacts of the floe), |F_d| per floe.

    Scalars: see :data:`SCALAR_FIELDS`; ``residual_history`` holds max_i |a_new-a|/a per
    iteration.
    """

    x_mean: np.ndarray
    a: np.ndarray
    a_stderr: np.ndarray
    S_sd: np.ndarray
    gap_mean: np.ndarray
    contact_fraction: np.ndarray
    collisions: np.ndarray
    F_w_mean: np.ndarray
    F_c_mean: np.ndarray
    F_d_mean: np.ndarray
    n_floes: int
    W_c: float
    alpha_all: float
    alpha_all_resid: float
    alpha_edge: float
    alpha_edge_resid: float
    alpha_inner: float
    alpha_inner_resid: float
    alpha_exp: float
    alpha_exp_resid: float
    alpha_c: float
    k: float
    c_g: float
    status: str
    noise: float
    iterations: int
    residual: float
    floe_steps: int
    wall_time: float
    kernel_mode: str
    a_end: float
    a0: float
    residual_history: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def a_rel(self) -> np.ndarray:
        """a / a0 per floe."""
        return self.a / self.a0

    def to_dict(self) -> dict[str, Any]:
        """All fields; arrays stay numpy arrays."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


def collision_zone_width(x_mean: np.ndarray, gap_mean: np.ndarray, L_x: float,
                         gap_threshold: float, L_sheet: float) -> float:
    """W_c: distance from the ice edge (x = 0) to the first pair whose mean gap < threshold.

    The pair (i, i+1) sits at x_mean[i] + L_x / 2. ``L_sheet`` when no pair qualifies
    (the collisional zone spans the domain), MODEL.md §6.
    """
    gaps = np.asarray(gap_mean)[: len(x_mean) - 1]
    idx = np.flatnonzero(gaps < gap_threshold)
    if idx.size == 0:
        return float(L_sheet)
    return float(x_mean[idx[0]] + 0.5 * L_x)


def _linfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    A = np.vstack([x, np.ones_like(x)]).T
    (slope, intercept), *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(slope), float(intercept), slope * x + intercept


def power_law(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares power law y = c x^m in log-log: (m, c, standard error of m, RMS of
    ln y - fit). The standard error is NaN with fewer than 3 points. Used for alpha(omega)
    (the paper's m): :func:`floewave.figures.fit_power_law`, :func:`sweep.alpha_omega`."""
    lx, ly = np.log(np.asarray(x, dtype=float)), np.log(np.asarray(y, dtype=float))
    m, lc, fit = _linfit(lx, ly)
    resid = ly - fit
    n = len(lx)
    sxx = float(((lx - lx.mean()) ** 2).sum())
    m_se = math.sqrt(float(resid @ resid) / (n - 2) / sxx) if n > 2 and sxx > 0 else math.nan
    return m, math.exp(lc), m_se, float(np.sqrt(np.mean(resid**2)))


def fit_inverse(x: np.ndarray, a: np.ndarray, a0: float) -> tuple[float, float]:
    """Slope alpha [m^-2] of 1/a = c + alpha x (free intercept) and the RMS misfit.

    The misfit is RMS((a_fit - a) / a0) over the fitted floes, the same measure as
    :func:`fit_exponential` so the two laws can be compared. NaN with < 3 floes.
    """
    ok = a > 0
    if ok.sum() < 3:
        return float("nan"), float("nan")
    slope, _, fit = _linfit(x[ok], 1.0 / a[ok])
    with np.errstate(divide="ignore"):
        resid = np.sqrt(np.mean(((1.0 / fit) - a[ok]) ** 2)) / a0
    return slope, float(resid)


def fit_exponential(x: np.ndarray, a: np.ndarray, a0: float) -> tuple[float, float]:
    """Rate alpha_exp [m^-1] of ln a = c - alpha_exp x and RMS((a_fit - a) / a0)."""
    ok = a > 0
    if ok.sum() < 3:
        return float("nan"), float("nan")
    slope, _, fit = _linfit(x[ok], np.log(a[ok]))
    resid = np.sqrt(np.mean((np.exp(fit) - a[ok]) ** 2)) / a0
    return -slope, float(resid)
