"""The d_f scan (issue 23, ``configs/dfscan.toml``, docs/dfscan.md): how the floe-floe distance
changes the attenuation near the ice edge, and the collision statistics that go with it.

:func:`d_f_scan` is a pure function of a store's table (``sweep.load``) and, optionally,
a ``profile(campaign, hash)`` callable returning a point's profiles (a mapping with
``x_mean``, ``a``, ``a_stderr``, ``contact_fraction``, ``collisions``, ``S_sd``,
``F_c_mean``: :func:`sweep.load_profile`, as :data:`herman2019.points.Profile`).
:func:`plot_d_f_scan` draws its table.

Columns of the table (units in ``table.attrs["units"]``), one row per d_f:

- ``d_f`` [m], ``status``, ``replicas``;
- ``x_near`` [m]: the time-mean centre of the floe nearest ``X_NEAR`` (5 m,
  :data:`herman2019.points.X_NEAR`) from the
  ice edge; ``a_near_rel``, ``a_near_rel_stderr`` [1]: a / a0 there and its standard error
  (the profile's ``a_stderr``; needs ``profile``);
- ``a_end_rel``, ``a_end_rel_stderr`` [1]: a / a0 of the last floe (``a_end / a0``);
- ``W_c``, ``W_c_gap`` [m] (stored columns);
- the stored ice-wide collision statistics and their jackknife standard errors
  (:mod:`floewave.collision_stats`): ``contact_fraction_mean`` [1], ``collision_rate``
  [collisions per pair per wave period], ``dissipation_per_collision`` [J];
- the same three over the near-edge region, from the replica-mean profiles (no standard
  error: the store keeps no per-replica contact records): ``contact_fraction_edge``,
  ``collision_rate_edge``, ``dissipation_per_collision_edge``. The region's floes are
  those whose mean centre is at most :data:`X_NEAR` from the edge, its pairs those whose
  contact point (left floe's centre + L_x / 2) is; the dissipation per collision is the
  skin-drag power of the region's floes, sum of -S_sd L_x L_y [W], over the region's
  collisions per second;
- ``impulse_per_collision`` and ``impulse_per_collision_edge`` [N s]: an impact-strength
  proxy, sum over floes of the time-mean |net contact force| (``F_c_mean``) times the
  window's duration nT T, over twice the collisions in the window (each pair's force
  acts on two floes). It is a lower bound of the contact impulse per collision (a floe
  squeezed from both sides nets out) and includes sustained contacts' forces, so it reads
  as impact strength only where contacts are brief (small contact fraction).
"""
from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from herman2019.points import X_NEAR, Profile, col

__all__ = ["X_NEAR", "UNITS", "d_f_scan", "plot_d_f_scan"]

#: The model's statuses: points that carry results.
_RESULT = ("converged", "converged_noisy", "not_converged")
_COLLISION = ("contact_fraction_mean", "collision_rate", "dissipation_per_collision")

UNITS: dict[str, str] = {
    "d_f": "m", "status": "", "replicas": "1", "x_near": "m", "a_near_rel": "1",
    "a_near_rel_stderr": "1", "a_end_rel": "1", "a_end_rel_stderr": "1", "W_c": "m",
    "W_c_gap": "m", "contact_fraction_mean": "1", "contact_fraction_mean_stderr": "1",
    "collision_rate": "per pair per wave period",
    "collision_rate_stderr": "per pair per wave period", "dissipation_per_collision": "J",
    "dissipation_per_collision_stderr": "J", "contact_fraction_edge": "1",
    "collision_rate_edge": "per pair per wave period", "dissipation_per_collision_edge": "J",
    "impulse_per_collision": "N s", "impulse_per_collision_edge": "N s",
}



def _config(row: pd.Series) -> dict[str, Any]:
    try:
        return json.loads(row.get("config_json", "") or "{}")
    except (TypeError, ValueError):
        return {}


def _region(p: Mapping[str, Any], row: pd.Series, cfg: dict[str, Any],
            floes: np.ndarray, pairs: np.ndarray) -> dict[str, float]:
    """Contact fraction, collision rate, dissipation and impulse per collision of the
    ``floes`` and ``pairs`` (boolean masks over the profile)."""
    L_x, T = col(row, "L_x"), col(row, "T")
    L_y, nT = float(cfg.get("L_y", math.nan)), float(cfg.get("nT", math.nan))
    cf = np.asarray(p["contact_fraction"], dtype=float)
    coll = np.asarray(p["collisions"], dtype=float)
    S = np.asarray(p["S_sd"], dtype=float)
    Fc = np.asarray(p["F_c_mean"], dtype=float) if "F_c_mean" in p else np.full(len(S), np.nan)
    n_coll = float(np.nansum(coll[pairs]))
    per_second = n_coll / (nT * T)
    power = float(-(S[floes] * L_x * L_y).sum())
    impulse = float(Fc[floes].sum()) * nT * T / 2.0
    ok = n_coll > 0
    return {"contact_fraction": float(np.mean(cf[pairs])) if pairs.any() else math.nan,
            "collision_rate": float(np.mean(coll[pairs])) / nT if pairs.any() else math.nan,
            "dissipation_per_collision": power / per_second if ok else math.nan,
            "impulse_per_collision": impulse / n_coll if ok else math.nan}


def _from_profile(p: Mapping[str, Any], row: pd.Series, x_near: float) -> dict[str, float]:
    cfg = _config(row)
    a0, L_x = col(row, "a0"), col(row, "L_x")
    x = np.asarray(p["x_mean"], dtype=float)
    i = int(np.nanargmin(np.abs(x - x_near)))
    out = {"x_near": float(x[i]),
           "a_near_rel": float(np.asarray(p["a"], dtype=float)[i]) / a0,
           "a_near_rel_stderr": float(np.asarray(p["a_stderr"], dtype=float)[i]) / a0}
    n = len(x)
    pair_at = np.concatenate([x[:-1] + 0.5 * L_x, [np.inf]])      # last entry: no pair
    every = _region(p, row, cfg, np.ones(n, dtype=bool), np.arange(n) < n - 1)
    edge = _region(p, row, cfg, x <= x_near, pair_at <= x_near)
    out["impulse_per_collision"] = every["impulse_per_collision"]
    out.update({f"{k}_edge": v for k, v in edge.items()})
    return out


def d_f_scan(df: pd.DataFrame, profile: Profile | None = None, *, campaign: str = "dfscan",
             x_near: float = X_NEAR) -> pd.DataFrame:
    """One row per d_f of ``df`` (a store's table: one setting, d_f swept), sorted by d_f;
    columns and units in the module docstring (``attrs["units"]``). ``profile(campaign,
    hash)`` gives a point's profiles; without it (or where it raises ``KeyError``) the
    profile-based columns are NaN. Points without results (failed, invalid, ...) give NaN.
    Raises ``ValueError`` if two rows share a d_f (more than one setting in ``df``)."""
    d = df.sort_values("d_f")
    if d["d_f"].duplicated().any():
        raise ValueError("d_f_scan: several points per d_f; select one setting (T, L_x, ...)"
                         " first")
    rows = []
    for _, row in d.iterrows():
        ok = str(row.get("status", "")) in _RESULT
        r: dict[str, Any] = {k: math.nan for k in UNITS}
        r.update(d_f=float(row["d_f"]), status=str(row.get("status", "")),
                 replicas=col(row, "replicas"))
        if ok:
            a0 = col(row, "a0")
            r.update(a_end_rel=col(row, "a_end") / a0,
                     a_end_rel_stderr=col(row, "a_end_stderr") / a0,
                     W_c=col(row, "W_c"), W_c_gap=col(row, "W_c_gap"))
            for name in _COLLISION:
                r[name] = col(row, name)
                r[name + "_stderr"] = col(row, name + "_stderr")
            if profile is not None:
                try:
                    p = profile(campaign, str(row["hash"]))
                except KeyError:
                    p = None
                if p is not None:
                    r.update(_from_profile(p, row, x_near))
        rows.append(r)
    out = pd.DataFrame(rows, columns=list(UNITS))
    out.attrs["units"] = dict(UNITS)
    out.attrs["x_near"] = x_near
    return out


def plot_d_f_scan(table: pd.DataFrame, path: str | Path) -> Path:
    """A 2 x 3 figure of :func:`d_f_scan`'s ``table`` against d_f (log axis): a / a0 at the
    floe nearest x_near and at the far end (separate panels: their ranges differ tenfold);
    contact fraction; collision rate; dissipation per collision; the impulse proxy.
    Ice-wide values are filled markers with one-standard-error bars (often smaller than
    the marker), the near-edge region's open markers without error bars (replica-mean
    profiles); points are not joined (nine separate ensembles: nothing is measured between
    them). Written as PNG to ``path``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = table.sort_values("d_f")
    x_near = float(table.attrs.get("x_near", X_NEAR))
    dmm = t["d_f"].to_numpy() * 1e3
    fig, axes = plt.subplots(2, 3, figsize=(14, 7.5), sharex=True)
    edge = f"x ≤ {x_near:g} m (profiles)"

    def draw(ax, name, se, label, colour, filled=True, marker="o"):
        y = t[name].to_numpy(dtype=float)
        if not np.isfinite(y).any():
            return
        e = t[se].to_numpy(dtype=float) if se else None
        if e is not None:
            e = np.where(np.isfinite(e), e, 0.0)
        ax.errorbar(dmm, y, yerr=e, fmt=marker, ls="none", color=colour, capsize=3,
                    mfc=colour if filled else "none", label=label)

    panels = (
        ((0, 0), "(a) near the edge", f"a / a0 at the floe nearest x = {x_near:g} m [1]",
         [("a_near_rel", "a_near_rel_stderr", "replica mean ± SE", "C0", True)]),
        ((0, 1), "(b) far end (last floe)", "a_end / a0 [1]",
         [("a_end_rel", "a_end_rel_stderr", "replica mean ± SE", "C3", True)]),
        ((0, 2), "(c) contact", "fraction of time steps in contact [1]",
         [("contact_fraction_mean", "contact_fraction_mean_stderr", "all pairs", "C2", True),
          ("contact_fraction_edge", None, "pairs at " + edge, "C2", False)]),
        ((1, 0), "(d) collisions", "contact onsets per pair per wave period [1]",
         [("collision_rate", "collision_rate_stderr", "all pairs", "C1", True),
          ("collision_rate_edge", None, "pairs at " + edge, "C1", False)]),
        ((1, 1), "(e) skin-drag dissipation per collision",
         "drag power / collisions per second [J]",
         [("dissipation_per_collision", "dissipation_per_collision_stderr",
           "all floes and pairs", "C4", True),
          ("dissipation_per_collision_edge", None, edge, "C4", False)]),
        ((1, 2), "(f) impact proxy (lower bound)",
         "contact impulse per collision [N s]",
         [("impulse_per_collision", None, "all floes and pairs (profiles, no SE)", "C5", True),
          ("impulse_per_collision_edge", None, edge, "C5", False)]),
    )
    for (i, j), title, ylabel, series in panels:
        ax = axes[i, j]
        for name, se, label, colour, filled in series:
            draw(ax, name, se, label, colour, filled)
        ax.set_title(title, fontsize=10)
        ax.set_ylabel(ylabel, fontsize=9)
        ax.set_xscale("log")
        ax.set_xticks(dmm)
        ax.set_xticklabels([f"{v:g}" for v in dmm], fontsize=8)
        ax.minorticks_off()
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    for ax in axes[1]:
        ax.set_xlabel("initial floe-floe distance d_f [mm] (log scale)")
    fig.suptitle("d_f scan: filled markers with one-standard-error bars over the replicas"
                 " (mostly smaller than the markers); open markers from the replica-mean"
                 " profiles (no error bar)", fontsize=10)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
