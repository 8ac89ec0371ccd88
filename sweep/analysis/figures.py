"""The paper's figures from a store: ``sweep figures STORE --out DIR [--only KIND ...]``.

Each kind is drawn for every group of points that varies the figure's parameter with
everything else fixed, so a store of any campaign gives whatever figures its grid allows
(the analytic Fig. 1 needs no store: ``floewave figures --out DIR``):

``fig2``  a/a0 versus x for each eps, one panel per dispersion relation (``ml``, ``ep``,
          ``ow``), with the standard error of a(x) as a band, the confined-ice curve of
          eq. 25 (alpha_c from eq. 24, solid black), a dot where the phase-averaged gap drops
          below ``gap_threshold`` (x = W_c) and the compact-ice solution started from that dot
          (dashed black: 1/a = 1/a(W_c) + alpha_c (x - W_c)); an open marker where each other
          rule of ``floewave.outputs.W_C_RULES`` puts it (a diamond: the same rule on the gaps
          averaged over the whole averaging, schema 4).
          Groups: (L_x, T, a0, C_sd, d_f).
          Ensembles: the a(x) band is ±1 standard error, the bar on the dot ±1 SE(W_c).
``fig3``  mean gap (log axis; dashed: the initial d_f; dotted: ``gap_threshold``, 1e-4 m, below
          which a pair is compact; dots at W_c), mean |F_w|, |F_c|, |F_d| versus x for
          each eps. Groups: (L_x, T, a0, C_sd, d_f, dispersion).
``fig5``  a/a0 for each floe size L_x (colours), ``ep`` solid, ``ml`` dashed, ``ow`` dotted.
          Groups: (T, a0, C_sd, eps, d_f).
``fig6``  a/a0 for each d_f (``fig6_df_*``) and for each a0 (``fig6_a0_*``), one panel per wave
          period. Groups: (L_x, a0 or d_f, C_sd, eps, dispersion).
``summary``  ``collision_zone.png`` (W_c versus eps), ``collision_stats.png`` (W_c / L_sheet and
          alpha_inner / alpha_c versus eps per floe size and dispersion relation, pooled over
          the other parameters, :func:`sweep.collision_stats`) and ``alpha_omega.png``
          (alpha_inner, or alpha_all where no point has an inner zone, and alpha_c versus
          omega with the fitted exponents m, :func:`sweep.alpha_omega`; groups with >= 3
          periods).

A campaign that sweeps ``seed`` gets each seed's figures in ``OUT/seed=<seed>/``, drawn from
that seed's points alone: figures neither pool nor average seeds (pool them with
:func:`sweep.collision_stats` or :func:`sweep.alpha_omega` with a ``by`` without ``seed``).

Status is marked in every figure and explained in its legend: a ``not_converged`` curve
(error bars above their targets, or never stationary; the estimate so far) carries crosses, a ``not_converged`` point (or a
pooled group holding one) an open square. Curves differ in colour and marker by the swept
parameters that differ between them (:func:`sweep.analysis.plotting.curve_styles`). A
figure the grid does not allow is named with the reason (:data:`WHY`); when none of the
asked kinds can be drawn, :func:`make_figures` raises
:class:`sweep.errors.NothingToDrawError` and ``sweep figures`` exits with status 2.

The number of figures per kind is capped (``--max``); groups closest to the paper's
reference setup (L_x = 0.5 m, T = 1.2 s, a0 = 0.0125 m, C_sd = 0.05, eps = 0.6,
d_f = 0.005 m, ``ml``) come first. Needs matplotlib (the ``plot`` extra).
"""
from __future__ import annotations

import json
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from floewave.outputs import W_C_RULES
from sweep.analysis.load import load
from sweep.analysis.plotting import (
    DISP_ORDER,
    DISP_STYLE,
    ProfileCache,
    colour_cycle,
    draw_amplitude,
    draw_confined,
    figure_file,
    format_value,
    group_title,
    legend_of,
    other_rules,
    point_groups,
    save_figure,
    status_handles,
)
from sweep.analysis.stats import RESULT_STATUSES
from sweep.analysis.summary_figures import summary
from sweep.errors import ConfigError, NothingToDrawError

__all__ = ["make_figures", "KINDS", "WHY", "fig2", "fig3", "fig5", "fig6"]

KINDS = ("fig2", "fig3", "fig5", "fig6", "summary")

def fig2(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int) -> list[Path]:
    """a/a0 per eps, one panel per dispersion relation (the paper's Fig. 2)."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    keys = ("L_x", "T", "a0", "C_sd", "d_f")
    written: list[Path] = []
    for key, sub in point_groups(df, keys, "eps")[:limit]:
        disps = [d for d in DISP_ORDER if d in set(sub["dispersion"])]
        eps_values = sorted(sub["eps"].unique())
        colours = dict(zip(eps_values, colour_cycle(len(eps_values)), strict=True))
        fig, axes = plt.subplots(1, len(disps), figsize=(4.6 * len(disps) + 2.2, 4.0),
                                 sharey=True, squeeze=False, constrained_layout=True)
        for panel, (ax, disp) in enumerate(zip(axes[0], disps, strict=True)):
            rows = sub[sub["dispersion"] == disp].sort_values("eps")
            x_end = 0.0
            for _, row in rows.iterrows():
                prof = profiles(row["hash"])
                x_end = max(x_end, float(prof["x"][-1]))
                draw_amplitude(ax, row, prof, colours[row["eps"]],
                           label=f"ε = {row['eps']:g}", zone=True)
            draw_confined(ax, rows.iloc[0], x_end)
            ax.plot([], [], "k--", lw=0.9, label="compact ice from x = W_c")
            first = W_C_RULES[0]
            ax.plot([], [], "o", color="0.6", mec="k", mew=0.6,
                    label=f"start of the compact zone (x = {first.name}, {first.rule})")
            for rule, marker in other_rules():
                if rule.name in rows.columns and rows[rule.name].notna().any():
                    ax.plot([], [], marker, mfc="none", mec="0.4", mew=1.2,
                            label=f"W_c from {rule.rule}")
            ax.set_title(f"({chr(97 + panel)}) {disp.upper()}", loc="left")
            ax.set_xlabel("distance from the ice edge x [m]")
            ax.grid(alpha=0.3)
            ax.set_xlim(0, x_end)
        axes[0][0].set_ylabel("relative wave amplitude a / a₀ [–]")
        handles, labels = legend_of(axes[0], status_handles(sub))
        fig.legend(handles, labels, fontsize=8, loc="outside lower center", ncol=4)
        fig.suptitle(group_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        save_figure(fig, out / figure_file("fig2", keys, key), written)
    return written


def fig3(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int) -> list[Path]:
    """Mean gap, |F_w|, |F_c|, |F_d| versus x per eps (the paper's Fig. 3)."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    keys = ("L_x", "T", "a0", "C_sd", "d_f", "dispersion")
    panels = (("gap_mean", "mean floe–floe distance [m]"), ("F_w_mean", "mean |F_w| [N]"),
              ("F_c_mean", "mean |F_c| [N]"), ("F_d_mean", "mean |F_d| [N]"))
    written: list[Path] = []
    for key, sub in point_groups(df, keys, "eps")[:limit]:
        eps_values = sorted(sub["eps"].unique())
        colours = dict(zip(eps_values, colour_cycle(len(eps_values)), strict=True))
        fig, axes = plt.subplots(2, 2, figsize=(10.0, 7.2), sharex=True,
                                 constrained_layout=True)
        L_x = float(sub["L_x"].iloc[0])
        x_end = 0.0
        replica_ticks = False
        for _, row in sub.sort_values("eps").iterrows():
            prof = profiles(row["hash"])
            colour = colours[row["eps"]]
            x = prof["x"]
            x_end = max(x_end, float(x[-1]))
            label = f"ε = {row['eps']:g}"
            marks: dict[str, Any] = {}
            if str(row["status"]) == "not_converged":
                marks = {"marker": "x", "ms": 4, "markevery": max(1, len(x) // 10)}
            for ax, (name, _) in zip(axes.flat, panels, strict=True):
                if name == "gap_mean":
                    xp, gap = x[:-1] + 0.5 * L_x, prof["gap_mean"][:-1]
                    ax.plot(xp, gap, "-", color=colour, lw=1.2, label=label, **marks)
                    W_c = float(row["W_c"])
                    if np.isfinite(W_c) and W_c < x[-1]:
                        ax.plot([W_c], [np.interp(W_c, xp, gap)], "o", color=colour, ms=6,
                                mec="k", mew=0.6, zorder=5)
                    # an ensemble's W_c is the mean of its replicas' W_c, each where that
                    # replica's own gaps drop below the threshold; the curve is the mean of
                    # the replicas' gaps, which the non-compact ones lift above it
                    own = np.asarray(prof.get("W_c_replicas", []), float)
                    own = own[np.isfinite(own)]
                    if len(own) > 1:
                        ax.plot(own, np.full(len(own), _gap_threshold(row)), "|", color=colour,
                                ms=12, mew=1.6, zorder=5)
                        replica_ticks = True
                else:
                    ax.plot(x, prof[name], "-", color=colour, lw=1.2, **marks)
        d_f = float(sub["d_f"].iloc[0])
        axes[0][0].axhline(d_f, color="k", ls="--", lw=1, label=f"domain-average d_f = {d_f:g} m")
        threshold = _gap_threshold(sub.iloc[0])
        axes[0][0].set_yscale("log", nonpositive="mask")
        axes[0][0].axhline(threshold, color="k", ls=":", lw=1.2,
                           label=f"gap_threshold = {threshold:g} m (a pair is compact below"
                                 " it)")
        for i, (ax, (_, label)) in enumerate(zip(axes.flat, panels, strict=True)):
            ax.set_ylabel(label)
            ax.set_title(f"({chr(97 + i)})", loc="left")
            ax.grid(alpha=0.3)
            ax.set_xlim(0, x_end)
        for ax in axes[1]:
            ax.set_xlabel("distance from the ice edge x [m]")
        extra = status_handles(sub)
        if replica_ticks:
            from matplotlib.lines import Line2D  # lazy: optional (plot extra), 0.8 s

            extra.append(Line2D([], [], ls="none", marker="|", ms=10, mew=1.6, color="k",
                                label=REPLICA_W_C))
        handles, labels = legend_of([axes[0][0]], extra)
        fig.legend(handles, labels, fontsize=7, ncol=2, loc="outside lower center")
        fig.suptitle(group_title(keys, key) + "  (dots: x = W_c; gaps <= 0 not shown on the log"
                     " axis)", fontsize=9)
        save_figure(fig, out / figure_file("fig3", keys, key), written)
    return written


#: Fig. 3's legend entry of the ticks at the threshold: an ensemble's replicas' own W_c.
REPLICA_W_C = ("| each replica's W_c (its own gaps drop below gap_threshold); the dot: their"
               " mean, on the replicas' mean gap")


def _gap_threshold(row: pd.Series) -> float:
    """The point's ``gap_threshold`` [m] (from its config; the paper's 1e-4 m if absent)."""
    try:
        return float(json.loads(str(row["config_json"])).get("gap_threshold", 1e-4))
    except (KeyError, ValueError, TypeError):
        return 1e-4


def fig5(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int) -> list[Path]:
    """a/a0 per floe size, ep solid and ml dashed (the paper's Fig. 5)."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s
    from matplotlib.lines import Line2D  # lazy: optional (plot extra), 0.8 s

    keys = ("T", "a0", "C_sd", "eps", "d_f")
    written: list[Path] = []
    for key, sub in point_groups(df, keys, "L_x")[:limit]:
        sizes = sorted(sub["L_x"].unique())
        colours = dict(zip(sizes, colour_cycle(len(sizes)), strict=True))
        fig, ax = plt.subplots(figsize=(7.0, 4.2), constrained_layout=True)
        x_end = 0.0
        for _, row in sub.sort_values(["dispersion", "L_x"]).iterrows():
            prof = profiles(row["hash"])
            x_end = max(x_end, float(prof["x"][-1]))
            draw_amplitude(ax, row, prof, colours[row["L_x"]], DISP_STYLE[row["dispersion"]])
        handles = [Line2D([], [], color=colours[s], lw=2, label=f"L_x = {s:g} m")
                   for s in sizes]
        handles += [Line2D([], [], color="k", ls=DISP_STYLE[d], label=d.upper())
                    for d in DISP_ORDER if d in set(sub["dispersion"])]
        handles += status_handles(sub)
        ax.legend(handles=handles, fontsize=8)
        ax.set_xlim(0, x_end)
        ax.set_xlabel("distance from the ice edge x [m]")
        ax.set_ylabel("relative wave amplitude a / a₀ [–]")
        ax.grid(alpha=0.3)
        ax.set_title(group_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        save_figure(fig, out / figure_file("fig5", keys, key), written)
    return written


def _fig6(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int,
          varying: str) -> list[Path]:
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    keys = tuple(k for k in ("L_x", "a0", "d_f", "C_sd", "eps", "dispersion")
                 if k != varying)
    written: list[Path] = []
    for key, sub in point_groups(df, keys, varying)[:limit]:
        values = sorted(sub[varying].unique())
        colours = dict(zip(values, colour_cycle(len(values)), strict=True))
        periods = sorted(sub["T"].unique())
        fig, axes = plt.subplots(1, len(periods), figsize=(4.6 * len(periods) + 0.6, 4.0),
                                 sharey=True, squeeze=False, constrained_layout=True)
        for panel, (ax, T) in enumerate(zip(axes[0], periods, strict=True)):
            x_end = 0.0
            for _, row in sub[sub["T"] == T].sort_values(varying).iterrows():
                prof = profiles(row["hash"])
                x_end = max(x_end, float(prof["x"][-1]))
                draw_amplitude(ax, row, prof, colours[row[varying]],
                           label=format_value(varying, row[varying]))
            ax.set_xlim(0, x_end)
            ax.set_title(f"({chr(97 + panel)}) T = {T:g} s", loc="left")
            ax.set_xlabel("distance from the ice edge x [m]")
            ax.grid(alpha=0.3)
        axes[0][0].set_ylabel("relative wave amplitude a / a₀ [–]")
        handles, labels = legend_of(axes[0], status_handles(sub))
        axes[0][-1].legend(handles, labels, fontsize=8)
        fig.suptitle(group_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        save_figure(fig, out / figure_file(f"fig6_{varying.replace('_', '')}", keys, key), written)
    return written


def fig6(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int) -> list[Path]:
    """a/a0 per d_f and per a0, one panel per wave period (the paper's Fig. 6)."""
    return (_fig6(df, profiles, out, limit, "d_f")
            + _fig6(df, profiles, out, limit, "a0"))


_DRAW = {"fig2": fig2, "fig3": fig3, "fig5": fig5, "fig6": fig6, "summary": summary}
#: The figures of each kind, by file-name prefix.
PARTS = {"fig2": ("fig2",), "fig3": ("fig3",), "fig5": ("fig5",),
         "fig6": ("fig6_df", "fig6_a0"),
         "summary": ("collision_zone", "collision_stats", "alpha_omega")}
#: Why a figure is not drawn: what its grid needs.
WHY = {
    "fig2": "needs points that differ only in eps (L_x, T, a0, C_sd, d_f fixed)",
    "fig3": "needs points that differ only in eps (L_x, T, a0, C_sd, d_f, dispersion fixed)",
    "fig5": "needs points that differ only in L_x (T, a0, C_sd, eps, d_f fixed)",
    "fig6_df": "needs points that differ only in d_f (and T) (L_x, a0, C_sd, eps, dispersion"
               " fixed)",
    "fig6_a0": "needs points that differ only in a0 (and T) (L_x, d_f, C_sd, eps, dispersion"
               " fixed)",
    "collision_zone": "needs points that differ only in eps (L_x, T, a0, C_sd, d_f,"
                      " dispersion fixed)",
    "collision_stats": "needs more than one eps and points with a compact zone (a W_c)",
    "alpha_omega": "needs >= 3 wave periods T with the other parameters fixed and a finite"
                   " alpha_inner or alpha_all",
}


def _stderr(message: str) -> None:
    print(f"sweep: {message}", file=sys.stderr)


def make_figures(path: str | Path, outdir: str | Path, max_figures: int = 20,
                 kinds: Iterable[str] = KINDS,
                 log: Callable[[str], None] | None = _stderr) -> list[Path]:
    """Write the figures for the store ``path`` into ``outdir``; return the files written.

    At most ``max_figures`` figures per kind (per varying parameter for ``fig6``). Each
    figure of ``kinds`` that the grid does not allow is named with the reason (:data:`WHY`)
    through ``log`` (default: a ``sweep: ... not drawn: ...`` line on stderr).

    Raises
    ------
    ConfigError
        matplotlib is missing, a kind is unknown or the store has no results; nothing is
        written then.
    NothingToDrawError
        (a ConfigError) none of the figures of ``kinds`` can be drawn from the grid.
    """
    kinds = list(kinds)
    unknown = [k for k in kinds if k not in KINDS]
    if unknown:
        raise ConfigError(f"unknown figure kind {unknown[0]!r}; choose from {', '.join(KINDS)}")
    try:
        import matplotlib  # lazy: optional (plot extra): its absence is reported

        matplotlib.use("Agg")
    except ImportError:
        raise ConfigError("sweep figures needs matplotlib: pip install 'floewave[plot]'") \
            from None
    df = load(path)
    df = df[df["status"].isin(RESULT_STATUSES)]
    if df.empty:
        raise ConfigError(f"{path}: no stored results to plot")
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    profiles = ProfileCache(path)
    written: list[Path] = []
    reasons: dict[str, str] = {}
    seeds = sorted(df["seed"].unique()) if "seed" in df else []
    # swept seeds are not pooled: each seed's points are drawn as a campaign of their own
    parts = ([(df, out)] if len(seeds) < 2 else
             [(df[df["seed"] == s], out / f"seed={s}") for s in seeds])
    if len(seeds) > 1 and log is not None:
        log(f"{len(seeds)} seeds swept: each seed's figures are in {out}/seed=<seed>/ (its"
            " points alone: seeds are not pooled nor averaged)")
    for kind in kinds:
        drawn = []
        for sub, where in parts:
            where.mkdir(parents=True, exist_ok=True)
            drawn += _DRAW[kind](sub, profiles, where, max_figures)
        for part in PARTS[kind]:
            if not any(f.name.startswith(part) for f in drawn):
                reasons[part] = WHY[part]
        written += drawn
    if log is not None:
        for part, why in reasons.items():
            log(f"{part} not drawn: {why}")
    if not written:
        raise NothingToDrawError(f"{path}: no figure of {', '.join(kinds)} can be drawn from"
                                 " this grid (see the reasons above)", reasons)
    return written
