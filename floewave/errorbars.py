"""The point's error bars (docs/model.md §4 "Ensembles", §6): the delete-one jackknife over
the R replicas (:func:`jackknife_se`; Efron & Stein 1981: for a mean it is exactly the
standard error of the mean) and, for one trajectory, the autocorrelation-corrected standard
error of the mean over iterations (:func:`stderr`)."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["jackknife_se", "stderr", "max_stderr", "effective_sample_size"]


def jackknife_se(loo: np.ndarray) -> np.ndarray:
    """Delete-one jackknife standard error from the R leave-one-out values (axis 0);
    NaN where any leave-one-out value is NaN or R < 2 (a 0-d array for 1-D ``loo``: float() it)."""
    loo = np.asarray(loo, dtype=float)
    R = loo.shape[0]
    if R < 2:
        return np.full(loo.shape[1:], np.nan)
    d = loo - loo.mean(axis=0)
    return np.sqrt((R - 1) / R * (d * d).sum(axis=0))


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


def max_stderr(samples: list[np.ndarray]) -> float:
    """max_i of :func:`stderr` [m]."""
    return float(np.max(stderr(samples)))
