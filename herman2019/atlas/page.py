"""The atlas page being written (:class:`Page`): its lines, the points it reads, and what
its sections hand on to the headlines; :func:`start_page` writes its opening."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from herman2019.atlas.stats import GRID_POINTS

__all__ = ["Page", "start_page"]


@dataclass
class Page:
    """The page: Markdown ``lines`` (the headlines go in at ``head_at``), the points with a
    result ``ok``, the bootstrap's generator and draws, the figures' directory and pyplot,
    and each section's result that a later one reads."""

    ok: pd.DataFrame
    rng: np.random.Generator
    bootstrap: int
    figdir: Path
    plt: Any
    lines: list[str] = field(default_factory=list)
    head_at: int = 0
    lay: Any = None
    resp: Any = None
    decomp: Any = None
    law: Any = None
    verdicts: Any = None
    disp_means: Any = None
    profiles: Any = None
    all: Any = None
    shares: Any = None
    source: str = "results/herman2019"
    se_factor: dict = field(default_factory=dict)
    not_converged: int = 0
    zone_rules: Any = None

    def say(self, text: str) -> None:
        """Add one line (Markdown) to the page."""
        self.lines.append(text)


def start_page(df: pd.DataFrame, figdir: Path, bootstrap: int, plt: Any, *,
               command: str, profiles: Any = None,
               source: str = "results/herman2019") -> Page:
    """The page's title, what made it from which table, and the status counts;
    ``bootstrap`` is 0 when ``df`` holds the whole grid (no sampling error). The points
    read are those that converged (``not_converged`` ones counted and left out); their
    standard errors are the calibrated ones (``herman2019.calibration``) when the table is
    of the model version the calibration was made at; ``profiles`` (the table's
    ``profiles/`` files, ``sweep.load_profiles``) or None."""
    from herman2019.factors import CALIBRATED_VERSION, calibrated_factors, factors_of
    files = list(df.attrs.get("files", ()))
    rng = np.random.default_rng(0)
    lines: list[str] = []
    say = lines.append
    n = len(df)
    counts = df["status"].value_counts()
    say("# Atlas of the paper's grid\n")
    complete = n == GRID_POINTS
    if complete:  # every point: a mean over the grid has no sampling error
        bootstrap = 0
        cover = (f" **all {GRID_POINTS} points of the grid**: a mean over the grid has no"
                 " sampling error, its SE is the points' stochastic one,"
                 " sqrt(sum SE_i²) / n, from their jackknife SEs.")
    else:
        cover = (f" **{n} of the grid's {GRID_POINTS} points** ({100 * n / GRID_POINTS:.1f} %;"
                 " each shard a uniform random sample of the grid, so until every shard is"
                 " in, every mean below also carries a sampling error: the SE quoted is the"
                 " larger of the stochastic one and a bootstrap over points).")
    say(f"Made by `{command}` from `{source}`"
        f" ({len(files)} shard table{'s' if len(files) != 1 else ''}):" + cover + " Model version"
        f" {sorted(set(json.loads(p)['model_version'] for p in df['provenance']))[0]},"
        " ensembles of 8 replicas, **stochastic** (another seed or CPU moves the values"
        " within their error bars); machine and dates in"
        f" `{source}/provenance.json`.\n")
    say("Status: " + ", ".join(f"{s} {int(c)}" for s, c in counts.items() if c) + ".\n")
    ok = df[df["status"].isin(["converged", "converged_noisy"])].copy()
    n_nc = int((df["status"] == "not_converged").sum())
    nc_zone = int(((df["status"] == "not_converged")
                   & (df["compact_zone"].astype(str) != "none")).sum())
    say(f"**Left out: the {n_nc} `not_converged` points** ({100 * n_nc / max(n, 1):.1f} %;"
        f" {nc_zone} of them with a compact zone, against"
        f" {100 * (ok['compact_zone'].astype(str) != 'none').mean():.0f} % of the others):"
        " their error bars are not honest (docs/convergence.md), so every statistic with"
        f" an error bar below is over the {len(ok)} converged points. Counts and shares"
        " of layouts (where a zone forms, under either rule) are over all"
        f" {len(ok) + n_nc} points with results: a point's layout is known even where its"
        " error bars are not.\n")
    versions = sorted(set(json.loads(p)["model_version"] for p in df["provenance"]))
    se_factor: dict = {}
    if versions == [CALIBRATED_VERSION]:
        factors = calibrated_factors()
        for q in dict.fromkeys(factors["quantity"]):
            f = pd.Series(factors_of(ok, factors, q), index=ok.index)
            se_factor[q] = f
            ok[q + "_stderr"] = ok[q + "_stderr"] * f
            if q == "a_end":
                ok["a_end_rel_stderr"] = ok["a_end_rel_stderr"] * f
        wc = np.isfinite(ok["W_c"]).to_numpy()
        say("**Error bars: calibrated.** Every SE below of a_end (and a/a0), W_c, W_c_gap"
            " and the alpha fits is the point's stated one times its calibration factor"
            " (`herman2019.factors.calibrated`: a factor by L_x, C_sd, d_f and"
            " dispersion fitted to 340 points on three seeds, docs/convergence.md,"
            " \"Calibrated standard errors\"; median factor of W_c over the points with a"
            f" W_c {float(se_factor['W_c'][wc].median()):.2f}, of alpha_all"
            f" {float(se_factor['alpha_all'].median()):.2f}, largest"
            f" {max(float(f.max()) for f in se_factor.values()):.2f}). a/a0 at a distance"
            " from the edge takes a_end's factor, calibrated at the far end: an"
            " extrapolation the calibration does not test.\n")
    else:
        say(f"**Error bars: as stated** (the calibration was made at model version"
            f" {CALIBRATED_VERSION}, this table is version {', '.join(versions)}).\n")
    return Page(ok=ok, rng=rng, bootstrap=bootstrap, figdir=figdir, plt=plt, lines=lines,
                head_at=len(lines), profiles=profiles, se_factor=se_factor, all=df.copy(),
                source=source, shares=df[df["status"].isin(["converged", "converged_noisy",
                                             "not_converged"])].copy(),
                not_converged=n_nc)
