"""Shared drawing parts of the figures: point groups, curve styles, status marks, saving.

The parts: grouping points by the swept parameters, curve styles, status marks, amplitude
curves, saving.

Used by :mod:`sweep.analysis.figures` and :mod:`sweep.analysis.summary_figures`.
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from floewave.outputs import W_C_RULES
from sweep.analysis.load import load_profile
from sweep.store.schema import column

__all__ = ["PAPER_SETUP", "DISP_ORDER", "DISP_STYLE", "SYMBOL", "format_value", "group_title",
           "figure_file", "closeness_to_paper", "point_groups", "ProfileCache", "colour_cycle",
           "MARKERS", "NOT_CONVERGED", "NOT_CONVERGED_RING", "not_converged_mask",
           "status_handles", "draw_ring", "legend_of", "curve_styles", "draw_amplitude",
           "draw_confined", "save_figure", "RULE_MARKERS", "other_rules"]

#: The paper's reference setup: groups closest to it are drawn first.
PAPER_SETUP = {"L_x": 0.5, "T": 1.2, "a0": 0.0125, "C_sd": 0.05, "eps": 0.6, "d_f": 0.005,
               "dispersion": "ml"}
DISP_ORDER = ("ml", "ep", "ow")
DISP_STYLE = {"ep": "-", "ml": "--", "ow": ":"}
SYMBOL = {"L_x": "L_x", "T": "T", "a0": "a_0", "C_sd": "C_sd", "eps": "ε", "d_f": "d_f",
          "dispersion": "", "seed": "seed"}


def format_value(name: str, value: Any) -> str:
    if name == "dispersion":
        return str(value).upper()
    units = column(name).units
    unit = f" {units}" if units not in ("", "1") else ""
    return f"{SYMBOL[name]} = {value:g}{unit}"


def group_title(keys: Sequence[str], values: Sequence[Any]) -> str:
    return ", ".join(format_value(k, v) for k, v in zip(keys, values, strict=True))


def figure_file(prefix: str, keys: Sequence[str], values: Sequence[Any]) -> str:
    """``fig5_T=1.2_a0=0.0125_C_sd=0.05….png``: name=value, so that ``a0`` and its value
    do not run together (``a00.0125``)."""
    text = "_".join(f"{k}={v}" for k, v in zip(keys, values, strict=True))
    return f"{prefix}_" + re.sub(r"[^A-Za-z0-9_.=-]", "", text) + ".png"


def closeness_to_paper(keys: Sequence[str], values: Sequence[Any]) -> tuple:
    """Sort key: number of values differing from the paper's setup, then the values."""
    diff = sum(PAPER_SETUP.get(k, v) != v for k, v in zip(keys, values, strict=True))
    return (diff, tuple(str(v) for v in values))


def point_groups(df: pd.DataFrame, keys: Sequence[str], varying: str,
            min_values: int = 2) -> list[tuple[tuple, pd.DataFrame]]:
    """Groups of ``df`` by ``keys`` in which ``varying`` takes >= min_values values."""
    out = []
    for key, sub in df.groupby(list(keys), sort=False, observed=True):
        key = key if isinstance(key, tuple) else (key,)
        if sub[varying].nunique() >= min_values:
            out.append((key, sub))
    return sorted(out, key=lambda kv: closeness_to_paper(keys, kv[0]))


class ProfileCache:
    """Per-point profiles read once per figure run (each point's group only)."""

    def __init__(self, path: str | Path):
        self.path = path
        self.cache: dict[str, dict[str, np.ndarray]] = {}

    def __call__(self, h: str) -> dict[str, np.ndarray]:
        if h not in self.cache:
            ds = load_profile(self.path, h)
            self.cache[h] = {k: ds[k].values for k in ("x", "a", "a_stderr", "gap_mean",
                                                        "F_w_mean", "F_c_mean", "F_d_mean",
                                                        "W_c_replicas") if k in ds}
        return self.cache[h]


def colour_cycle(n: int) -> list:
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    cmap = plt.get_cmap("tab10" if n <= 10 else "viridis")
    return [cmap(i if n <= 10 else i / max(n - 1, 1)) for i in range(n)]


MARKERS = ("o", "s", "^", "D", "v", "P", "*", "X", "<", ">")
#: Open markers of the W_c rules after the first (:func:`other_rules`).
RULE_MARKERS = ("D", "s", "^", "v", "P")
#: The legend entry of the crosses on a not-converged curve (its handle shows the cross:
#: the text does not repeat it).
NOT_CONVERGED = "not converged (error bars above target, or not stationary; the estimate so far)"
#: The legend entry of the open square around a not-converged point (or a pooled group
#: holding one).
NOT_CONVERGED_RING = "not converged, or a group holding one"


def not_converged_mask(df: pd.DataFrame) -> pd.Series:
    return df["status"].astype(str) == "not_converged"


def status_handles(df: pd.DataFrame, ring: bool = False) -> list:
    """The legend entries explaining the status marks, for the points of ``df``."""
    from matplotlib.lines import Line2D  # lazy: optional (plot extra), 0.8 s

    if not not_converged_mask(df).any():
        return []
    if ring:
        return [Line2D([], [], ls="none", marker="s", ms=9, mfc="none", mec="k",
                       label=NOT_CONVERGED_RING)]
    return [Line2D([], [], ls="none", marker="x", color="k", ms=5, label=NOT_CONVERGED)]


def draw_ring(ax, x: Any, y: Any, colour: Any = "k") -> None:
    """An open square around each (x, y): a not-converged point."""
    ax.plot(x, y, ls="none", marker="s", ms=9, mfc="none", mec=colour, mew=1.2, zorder=6)


def legend_of(axes: Iterable, extra: Sequence = ()) -> tuple[list, list[str]]:
    """Handles and labels of every panel (each label once, first panel first; a curve's
    entry without the status crosses, which :data:`NOT_CONVERGED` explains) plus ``extra``
    handles."""
    from matplotlib.lines import Line2D  # lazy: optional (plot extra), 0.8 s

    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab in labels:
                continue
            if isinstance(h, Line2D) and h.get_marker() == "x":  # a curve's status marks:
                h = Line2D([], [], color=h.get_color(), ls=h.get_linestyle(),  # not its own
                           lw=h.get_linewidth(), label=lab)
            handles.append(h)
            labels.append(lab)
    for h in extra:
        if h.get_label() not in labels:
            handles.append(h)
            labels.append(h.get_label())
    return handles, labels


def curve_styles(keys: Sequence[str], groups: Sequence[tuple]) -> list[tuple[Any, str]]:
    """(colour, marker) per group: colour by the values of the first key that differs
    between the groups, marker by the combination of the other differing keys (by the same
    key when only one differs), so that no two groups look alike."""
    vary = [i for i in range(len(keys)) if len({g[i] for g in groups}) > 1]
    if not vary:
        return [(colour_cycle(1)[0], MARKERS[0])] * len(groups)
    first = sorted({g[vary[0]] for g in groups}, key=str)
    if len(vary) == 1:
        vary = vary * 2
    rest = sorted({tuple(g[i] for i in vary[1:]) for g in groups}, key=str)
    colours = colour_cycle(len(first))
    return [(colours[first.index(g[vary[0]])],
             MARKERS[rest.index(tuple(g[i] for i in vary[1:])) % len(MARKERS)])
            for g in groups]


def draw_amplitude(ax, row: pd.Series, prof: dict[str, np.ndarray], colour, style: str = "-",
               label: str | None = None, band: bool = True, zone: bool = False) -> None:
    """a/a0 versus x (with SE band); with ``zone``: the W_c dot and compact-ice line.

    A ``not_converged`` point (its error bars above their targets, or never stationary: the
    estimate so far) is drawn with
    crosses (explained by the figure's legend entry :data:`NOT_CONVERGED`; the curve's own
    label stays that of its parameter value, so that one legend serves several panels).
    """
    a0 = float(row["a0"])
    x, a, se = prof["x"], prof["a"], prof["a_stderr"]
    marks: dict[str, Any] = {}
    if str(row.get("status", "")) == "not_converged":
        marks = {"marker": "x", "ms": 4, "markevery": max(1, len(x) // 10)}
    ax.plot(x, a / a0, style, color=colour, lw=1.3, label=label, **marks)
    if band and np.isfinite(se).any():
        ax.fill_between(x, (a - se) / a0, (a + se) / a0, color=colour, alpha=0.25, lw=0)
    if not zone:
        return
    # only where a compact zone exists (W_c is NaN without one): the dot at its start and
    # the compact-ice solution along it
    W_c, alpha_c = float(row["W_c"]), float(row["alpha_c"])
    end = float(row.get("compact_end", np.nan))
    end = min(end, x[-1]) if np.isfinite(end) else x[-1]
    if np.isfinite(W_c) and W_c < end:
        a_w = float(np.interp(W_c, x, a))
        ax.plot([W_c], [a_w / a0], "o", color=colour, ms=6, mec="k", mew=0.6, zorder=5)
        se_w = float(row.get("W_c_stderr", np.nan))
        if np.isfinite(se_w) and se_w > 0:      # an ensemble's standard error of W_c
            ax.errorbar([W_c], [a_w / a0], xerr=[se_w], fmt="none", ecolor=colour,
                        elinewidth=1.2, capsize=3, zorder=5)
        if np.isfinite(alpha_c) and a_w > 0:
            xx = np.linspace(W_c, end, 100)
            ax.plot(xx, 1.0 / (1.0 / a_w + alpha_c * (xx - W_c)) / a0, "k--", lw=0.9)
    # every other W_c rule the model declares (floewave.outputs.W_C_RULES; schema 4: the
    # rule on the gaps averaged over the whole averaging): an open marker each, to show how
    # much the definition moves the zone's start
    for rule, marker in other_rules():
        W_g = float(row.get(rule.name, np.nan))
        if np.isfinite(W_g) and W_g < x[-1]:
            ax.plot([W_g], [float(np.interp(W_g, x, a)) / a0], marker, mfc="none",
                    mec=colour, ms=6, mew=1.2, zorder=5)


def other_rules() -> list[tuple[Any, str]]:
    """(output, open marker) of each W_c rule after the first one (the dot's) that
    :data:`floewave.outputs.W_C_RULES` declares."""
    return list(zip(W_C_RULES[1:], RULE_MARKERS, strict=False))


def draw_confined(ax, row: pd.Series, x_end: float, label: bool = True) -> None:
    """The confined-ice solution of eq. 25 from the ice edge."""
    a0, alpha_c = float(row["a0"]), float(row["alpha_c"])
    if not np.isfinite(alpha_c):
        return
    xx = np.linspace(0.0, x_end, 200)
    ax.plot(xx, 1.0 / (1.0 + a0 * alpha_c * xx), "k-", lw=1.4,
            label="eq. 25 (confined ice)" if label else None)


def save_figure(fig, target: Path, written: list[Path]) -> None:
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    fig.savefig(target, dpi=120)
    plt.close(fig)
    written.append(target)
