"""Paper-style figures from a store (``sweep figures STORE --out DIR``).

- One figure per combination of the swept values other than ``eps`` (the paper's Fig. 2
  layout): a/a0 versus the floe position for every eps, with standard errors, the
  confined-ice curve of eq. 25 with alpha_c from eq. 24, and a dot where the
  collisional zone ends (x = W_c, the paper's dots).
- ``collision_zone.png``: W_c versus eps, one line per such combination (up to 12).

Needs matplotlib (the ``plot`` extra).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .analysis import load, load_profile
from .errors import ConfigError

__all__ = ["make_figures"]

GROUP = ("L_x", "T", "a0", "C_sd", "d_f", "dispersion")
STORED_RESULTS = ("converged", "converged_noisy", "not_converged")


def _name(key: tuple) -> str:
    text = "_".join(f"{k}{v}" for k, v in zip(GROUP, key, strict=True))
    return "profile_" + re.sub(r"[^A-Za-z0-9_.-]", "", text) + ".png"


def make_figures(path: str | Path, outdir: str | Path, max_figures: int = 50) -> list[Path]:
    """Write the figures for the store ``path`` into ``outdir``; return the files written.

    At most ``max_figures`` profile figures (the first groups in sorted order).
    Raises :class:`ConfigError` if matplotlib is missing or the store has no results.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ConfigError("sweep figures needs matplotlib: pip install 'floewave[plot]'") \
            from None
    df = load(path)
    df = df[df["status"].isin(STORED_RESULTS)]
    if df.empty:
        raise ConfigError(f"{path}: no stored results to plot")
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    groups = sorted(df.groupby(list(GROUP)), key=lambda kv: tuple(map(str, kv[0])))
    for key, sub in groups[:max_figures]:
        fig, ax = plt.subplots(figsize=(6.5, 3.8))
        a0 = float(sub["a0"].iloc[0])
        for _, row in sub.sort_values("eps").iterrows():
            prof = load_profile(path, row["hash"])
            x = prof["x"].values
            line = ax.errorbar(x, prof["a"].values / a0, yerr=prof["a_stderr"].values / a0,
                               lw=1, ms=2, fmt=".-", label=f"eps = {row['eps']:g}")
            if row["W_c"] < x[-1]:
                i = int(np.searchsorted(x, row["W_c"]))
                i = min(i, len(x) - 1)
                ax.plot([row["W_c"]], [prof["a"].values[i] / a0], "o",
                        color=line[0].get_color(), ms=6)
        alpha_c = float(sub["alpha_c"].iloc[0])
        xx = np.linspace(0.0, float(sub["n_floes"].iloc[0] * sub["L_x"].iloc[0]), 200)
        ax.plot(xx, 1.0 / (a0 * alpha_c * xx + 1.0), "k-", lw=1.2, label="eq. 25")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("a / a0")
        ax.set_title(", ".join(f"{k}={v}" for k, v in zip(GROUP, key, strict=True)),
                     fontsize=8)
        ax.legend(fontsize=7)
        fig.tight_layout()
        target = out / _name(key)
        fig.savefig(target, dpi=110)
        plt.close(fig)
        written.append(target)
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    for key, sub in groups[:12]:
        sub = sub.sort_values("eps")
        ax.plot(sub["eps"], sub["W_c"], "o-", ms=3, lw=1,
                label=" ".join(f"{v}" for v in key))
    ax.set_xlabel("eps")
    ax.set_ylabel("collision-zone width W_c [m]")
    ax.legend(fontsize=6, title=" ".join(GROUP), title_fontsize=6)
    fig.tight_layout()
    target = out / "collision_zone.png"
    fig.savefig(target, dpi=110)
    plt.close(fig)
    written.append(target)
    return written
