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

    def say(self, text: str) -> None:
        """Add one line (Markdown) to the page."""
        self.lines.append(text)


def start_page(df: pd.DataFrame, figdir: Path, bootstrap: int, plt: Any, *,
               command: str) -> Page:
    """The page's title, what made it from which table, and the status counts;
    ``bootstrap`` is 0 when ``df`` holds the whole grid (no sampling error)."""
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
                 " each shard a uniform random sample of the grid, so until all eight are"
                 " in, every mean below also carries a sampling error: the SE quoted is the"
                 " larger of the stochastic one and a bootstrap over points).")
    say(f"Made by `{command}` from `results/herman2019`"
        f" ({len(files)} shard tables):" + cover + " Model version"
        f" {sorted(set(json.loads(p)['model_version'] for p in df['provenance']))[0]},"
        " ensembles of 8 replicas, **stochastic** (another seed or CPU moves the values"
        " within their error bars); machine and dates in"
        " `results/herman2019/provenance.json`.\n")
    say("Status: " + ", ".join(f"{s} {int(c)}" for s, c in counts.items() if c) + ".\n")
    ok = df[df["status"].isin(["converged", "converged_noisy", "not_converged"])].copy()
    return Page(ok=ok, rng=rng, bootstrap=bootstrap, figdir=figdir, plt=plt, lines=lines,
                head_at=len(lines))
