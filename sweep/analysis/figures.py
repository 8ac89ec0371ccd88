"""The paper's figures from a store: ``sweep figures STORE --out DIR [--only KIND ...]``.

Each kind is drawn for every group of points that varies the figure's parameter with
everything else fixed, so a store of any campaign gives whatever figures its grid allows
(the analytic Fig. 1 needs no store: ``floewave figures --out DIR``):

``fig2``  a/a0 versus x for each eps, one panel per dispersion relation (``ml``, ``ep``,
          ``ow``), with the standard error of a(x) as a band, the confined-ice curve of
          eq. 25 (alpha_c from eq. 24, solid black), a dot where the phase-averaged gap drops
          below ``gap_threshold`` (x = W_c) and the compact-ice solution started from that dot
          (dashed black: 1/a = 1/a(W_c) + alpha_c (x - W_c)). Groups: (L_x, T, a0, C_sd, d_f).
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

Status is marked in every figure and explained in its legend: a ``not_converged`` curve
(``max_iterations`` reached; the mean so far) carries crosses, a ``not_converged`` point (or a
pooled group holding one) an open square. Curves differ in colour and marker by the swept
parameters that differ between them (:func:`_styles`). A figure the grid does not allow is
named with the reason (:data:`WHY`); when none of the asked kinds can be drawn,
:func:`make_figures` raises :class:`NothingToDrawError` and ``sweep figures`` exits with
status 2.

The number of figures per kind is capped (``--max``); groups closest to the paper's
reference setup (L_x = 0.5 m, T = 1.2 s, a0 = 0.0125 m, C_sd = 0.05, eps = 0.6,
d_f = 0.005 m, ``ml``) come first. Needs matplotlib (the ``plot`` extra).
"""
from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sweep.analysis.load import load, load_profile
from sweep.analysis.stats import RESULT_STATUSES, SWEPT, alpha_omega, collision_stats, derived
from sweep.errors import ConfigError
from sweep.store.schema import column

__all__ = ["make_figures", "KINDS", "PAPER_SETUP", "WHY", "NothingToDrawError"]

KINDS = ("fig2", "fig3", "fig5", "fig6", "summary")
#: The paper's reference setup: groups closest to it are drawn first.
PAPER_SETUP = {"L_x": 0.5, "T": 1.2, "a0": 0.0125, "C_sd": 0.05, "eps": 0.6, "d_f": 0.005,
               "dispersion": "ml"}
DISP_ORDER = ("ml", "ep", "ow")
DISP_STYLE = {"ep": "-", "ml": "--", "ow": ":"}
SYMBOL = {"L_x": "L_x", "T": "T", "a0": "a_0", "C_sd": "C_sd", "eps": "ε", "d_f": "d_f",
          "dispersion": ""}


def _fmt(name: str, value: Any) -> str:
    if name == "dispersion":
        return str(value).upper()
    units = column(name).units
    unit = f" {units}" if units not in ("", "1") else ""
    return f"{SYMBOL[name]} = {value:g}{unit}"


def _title(keys: Sequence[str], values: Sequence[Any]) -> str:
    return ", ".join(_fmt(k, v) for k, v in zip(keys, values, strict=True))


def _file(prefix: str, keys: Sequence[str], values: Sequence[Any]) -> str:
    """``fig5_T=1.2_a0=0.0125_C_sd=0.05….png``: name=value, so that ``a0`` and its value
    do not run together (``a00.0125``)."""
    text = "_".join(f"{k}={v}" for k, v in zip(keys, values, strict=True))
    return f"{prefix}_" + re.sub(r"[^A-Za-z0-9_.=-]", "", text) + ".png"


def _closeness(keys: Sequence[str], values: Sequence[Any]) -> tuple:
    """Sort key: number of values differing from the paper's setup, then the values."""
    diff = sum(PAPER_SETUP[k] != v for k, v in zip(keys, values, strict=True))
    return (diff, tuple(str(v) for v in values))


def _groups(df: pd.DataFrame, keys: Sequence[str], varying: str,
            min_values: int = 2) -> list[tuple[tuple, pd.DataFrame]]:
    """Groups of ``df`` by ``keys`` in which ``varying`` takes >= min_values values."""
    out = []
    for key, sub in df.groupby(list(keys), sort=False, observed=True):
        key = key if isinstance(key, tuple) else (key,)
        if sub[varying].nunique() >= min_values:
            out.append((key, sub))
    return sorted(out, key=lambda kv: _closeness(keys, kv[0]))


class _Profiles:
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


def _colours(n: int) -> list:
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("tab10" if n <= 10 else "viridis")
    return [cmap(i if n <= 10 else i / max(n - 1, 1)) for i in range(n)]


MARKERS = ("o", "s", "^", "D", "v", "P", "*", "X", "<", ">")
#: The legend entry of the crosses on a not-converged curve.
NOT_CONVERGED = "× not converged (max_iterations reached; the estimate so far)"
#: The legend entry of the open square around a not-converged point (or a pooled group
#: holding one).
NOT_CONVERGED_RING = "□ not converged (max_iterations reached), or a group holding one"


def _not_converged(df: pd.DataFrame) -> pd.Series:
    return df["status"].astype(str) == "not_converged"


def _status_handles(df: pd.DataFrame, ring: bool = False) -> list:
    """The legend entries explaining the status marks, for the points of ``df``."""
    from matplotlib.lines import Line2D

    if not _not_converged(df).any():
        return []
    if ring:
        return [Line2D([], [], ls="none", marker="s", ms=9, mfc="none", mec="k",
                       label=NOT_CONVERGED_RING)]
    return [Line2D([], [], ls="none", marker="x", color="k", ms=5, label=NOT_CONVERGED)]


def _ring(ax, x: Any, y: Any, colour: Any = "k") -> None:
    """An open square around each (x, y): a not-converged point."""
    ax.plot(x, y, ls="none", marker="s", ms=9, mfc="none", mec=colour, mew=1.2, zorder=6)


def _legend_of(axes: Iterable, extra: Sequence = ()) -> tuple[list, list[str]]:
    """Handles and labels of every panel (each label once, first panel first; a curve's
    entry without the status crosses, which :data:`NOT_CONVERGED` explains) plus ``extra``
    handles."""
    from matplotlib.lines import Line2D

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


def _styles(keys: Sequence[str], groups: Sequence[tuple]) -> list[tuple[Any, str]]:
    """(colour, marker) per group: colour by the values of the first key that differs
    between the groups, marker by the combination of the other differing keys (by the same
    key when only one differs), so that no two groups look alike."""
    vary = [i for i in range(len(keys)) if len({g[i] for g in groups}) > 1]
    if not vary:
        return [(_colours(1)[0], MARKERS[0])] * len(groups)
    first = sorted({g[vary[0]] for g in groups}, key=str)
    if len(vary) == 1:
        vary = vary * 2
    rest = sorted({tuple(g[i] for i in vary[1:]) for g in groups}, key=str)
    colours = _colours(len(first))
    return [(colours[first.index(g[vary[0]])],
             MARKERS[rest.index(tuple(g[i] for i in vary[1:])) % len(MARKERS)])
            for g in groups]


def _amplitude(ax, row: pd.Series, prof: dict[str, np.ndarray], colour, style: str = "-",
               label: str | None = None, band: bool = True, zone: bool = False) -> None:
    """a/a0 versus x (with SE band); with ``zone``: the W_c dot and compact-ice line.

    A ``not_converged`` point (``max_iterations`` reached: the mean so far) is drawn with
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


def _confined(ax, row: pd.Series, x_end: float, label: bool = True) -> None:
    """The confined-ice solution of eq. 25 from the ice edge."""
    a0, alpha_c = float(row["a0"]), float(row["alpha_c"])
    if not np.isfinite(alpha_c):
        return
    xx = np.linspace(0.0, x_end, 200)
    ax.plot(xx, 1.0 / (1.0 + a0 * alpha_c * xx), "k-", lw=1.4,
            label="eq. 25 (confined ice)" if label else None)


def _save(fig, target: Path, written: list[Path]) -> None:
    import matplotlib.pyplot as plt

    fig.savefig(target, dpi=120)
    plt.close(fig)
    written.append(target)


def fig2(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int) -> list[Path]:
    """a/a0 per eps, one panel per dispersion relation (the paper's Fig. 2)."""
    import matplotlib.pyplot as plt

    keys = ("L_x", "T", "a0", "C_sd", "d_f")
    written: list[Path] = []
    for key, sub in _groups(df, keys, "eps")[:limit]:
        disps = [d for d in DISP_ORDER if d in set(sub["dispersion"])]
        eps_values = sorted(sub["eps"].unique())
        colours = dict(zip(eps_values, _colours(len(eps_values)), strict=True))
        fig, axes = plt.subplots(1, len(disps), figsize=(4.6 * len(disps) + 2.2, 4.0),
                                 sharey=True, squeeze=False, constrained_layout=True)
        for panel, (ax, disp) in enumerate(zip(axes[0], disps, strict=True)):
            rows = sub[sub["dispersion"] == disp].sort_values("eps")
            x_end = 0.0
            for _, row in rows.iterrows():
                prof = profiles(row["hash"])
                x_end = max(x_end, float(prof["x"][-1]))
                _amplitude(ax, row, prof, colours[row["eps"]],
                           label=f"ε = {row['eps']:g}", zone=True)
            _confined(ax, rows.iloc[0], x_end)
            ax.plot([], [], "k--", lw=0.9, label="compact ice from x = W_c")
            ax.plot([], [], "o", color="0.6", mec="k", mew=0.6,
                    label="start of the compact zone (x = W_c)")
            ax.set_title(f"({chr(97 + panel)}) {disp.upper()}", loc="left")
            ax.set_xlabel("distance from the ice edge x [m]")
            ax.grid(alpha=0.3)
            ax.set_xlim(0, x_end)
        axes[0][0].set_ylabel("relative wave amplitude a / a₀ [–]")
        handles, labels = _legend_of(axes[0], _status_handles(sub))
        fig.legend(handles, labels, fontsize=8, loc="outside lower center", ncol=4)
        fig.suptitle(_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        _save(fig, out / _file("fig2", keys, key), written)
    return written


def fig3(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int) -> list[Path]:
    """Mean gap, |F_w|, |F_c|, |F_d| versus x per eps (the paper's Fig. 3)."""
    import matplotlib.pyplot as plt

    keys = ("L_x", "T", "a0", "C_sd", "d_f", "dispersion")
    panels = (("gap_mean", "mean floe–floe distance [m]"), ("F_w_mean", "mean |F_w| [N]"),
              ("F_c_mean", "mean |F_c| [N]"), ("F_d_mean", "mean |F_d| [N]"))
    written: list[Path] = []
    for key, sub in _groups(df, keys, "eps")[:limit]:
        eps_values = sorted(sub["eps"].unique())
        colours = dict(zip(eps_values, _colours(len(eps_values)), strict=True))
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
        extra = _status_handles(sub)
        if replica_ticks:
            from matplotlib.lines import Line2D

            extra.append(Line2D([], [], ls="none", marker="|", ms=10, mew=1.6, color="k",
                                label=REPLICA_W_C))
        handles, labels = _legend_of([axes[0][0]], extra)
        fig.legend(handles, labels, fontsize=7, ncol=2, loc="outside lower center")
        fig.suptitle(_title(keys, key) + "  (dots: x = W_c; gaps <= 0 not shown on the log"
                     " axis)", fontsize=9)
        _save(fig, out / _file("fig3", keys, key), written)
    return written


#: Fig. 3's legend entry of the ticks at the threshold: an ensemble's replicas' own W_c.
REPLICA_W_C = ("| each replica's W_c (its own gaps drop below gap_threshold); the dot: their"
               " mean, on the replicas' mean gap")


def _gap_threshold(row: pd.Series) -> float:
    """The point's ``gap_threshold`` [m] (from its config; the paper's 1e-4 m if absent)."""
    import json

    try:
        return float(json.loads(str(row["config_json"])).get("gap_threshold", 1e-4))
    except (KeyError, ValueError, TypeError):
        return 1e-4


def fig5(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int) -> list[Path]:
    """a/a0 per floe size, ep solid and ml dashed (the paper's Fig. 5)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    keys = ("T", "a0", "C_sd", "eps", "d_f")
    written: list[Path] = []
    for key, sub in _groups(df, keys, "L_x")[:limit]:
        sizes = sorted(sub["L_x"].unique())
        colours = dict(zip(sizes, _colours(len(sizes)), strict=True))
        fig, ax = plt.subplots(figsize=(7.0, 4.2), constrained_layout=True)
        x_end = 0.0
        for _, row in sub.sort_values(["dispersion", "L_x"]).iterrows():
            prof = profiles(row["hash"])
            x_end = max(x_end, float(prof["x"][-1]))
            _amplitude(ax, row, prof, colours[row["L_x"]], DISP_STYLE[row["dispersion"]])
        handles = [Line2D([], [], color=colours[s], lw=2, label=f"L_x = {s:g} m")
                   for s in sizes]
        handles += [Line2D([], [], color="k", ls=DISP_STYLE[d], label=d.upper())
                    for d in DISP_ORDER if d in set(sub["dispersion"])]
        handles += _status_handles(sub)
        ax.legend(handles=handles, fontsize=8)
        ax.set_xlim(0, x_end)
        ax.set_xlabel("distance from the ice edge x [m]")
        ax.set_ylabel("relative wave amplitude a / a₀ [–]")
        ax.grid(alpha=0.3)
        ax.set_title(_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        _save(fig, out / _file("fig5", keys, key), written)
    return written


def _fig6(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int,
          varying: str) -> list[Path]:
    import matplotlib.pyplot as plt

    keys = tuple(k for k in ("L_x", "a0", "d_f", "C_sd", "eps", "dispersion")
                 if k != varying)
    written: list[Path] = []
    for key, sub in _groups(df, keys, varying)[:limit]:
        values = sorted(sub[varying].unique())
        colours = dict(zip(values, _colours(len(values)), strict=True))
        periods = sorted(sub["T"].unique())
        fig, axes = plt.subplots(1, len(periods), figsize=(4.6 * len(periods) + 0.6, 4.0),
                                 sharey=True, squeeze=False, constrained_layout=True)
        for panel, (ax, T) in enumerate(zip(axes[0], periods, strict=True)):
            x_end = 0.0
            for _, row in sub[sub["T"] == T].sort_values(varying).iterrows():
                prof = profiles(row["hash"])
                x_end = max(x_end, float(prof["x"][-1]))
                _amplitude(ax, row, prof, colours[row[varying]],
                           label=_fmt(varying, row[varying]))
            ax.set_xlim(0, x_end)
            ax.set_title(f"({chr(97 + panel)}) T = {T:g} s", loc="left")
            ax.set_xlabel("distance from the ice edge x [m]")
            ax.grid(alpha=0.3)
        axes[0][0].set_ylabel("relative wave amplitude a / a₀ [–]")
        handles, labels = _legend_of(axes[0], _status_handles(sub))
        axes[0][-1].legend(handles, labels, fontsize=8)
        fig.suptitle(_title(keys, key) + "  (band: ±1 standard error)", fontsize=9)
        _save(fig, out / _file(f"fig6_{varying.replace('_', '')}", keys, key), written)
    return written


def fig6(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int) -> list[Path]:
    """a/a0 per d_f and per a0, one panel per wave period (the paper's Fig. 6)."""
    return (_fig6(df, profiles, out, limit, "d_f")
            + _fig6(df, profiles, out, limit, "a0"))


def summary(df: pd.DataFrame, profiles: _Profiles, out: Path, limit: int) -> list[Path]:
    """W_c versus eps, and alpha_inner(omega) with the fitted exponents."""
    import matplotlib.pyplot as plt

    written: list[Path] = []
    keys = ("L_x", "T", "a0", "C_sd", "d_f", "dispersion")
    groups = _groups(df, keys, "eps")
    if groups:
        written += _collision_zone_figure(df, keys, groups[:12], out)
    if df["eps"].nunique() > 1:
        written += _collision_stats_figure(df, out)
    rate = "alpha_inner"
    fits = alpha_omega(df, rate)
    if not np.isfinite(fits["m"]).any():     # no inner zone anywhere: fit all floes
        rate = "alpha_all"
        fits = alpha_omega(df, rate)
    fits = fits[np.isfinite(fits["m"])]
    if not fits.empty:
        by = [k for k in SWEPT if k in fits.columns]
        fits = fits.assign(_order=[_closeness(by, tuple(r[k] for k in by))
                                   for _, r in fits.iterrows()]).sort_values("_order")
        fig, ax = plt.subplots(figsize=(7.0, 4.6), constrained_layout=True)
        for colour, (_, fit) in zip(_colours(min(len(fits), 8)), fits.head(8).iterrows(),
                                    strict=False):
            sel = np.ones(len(df), dtype=bool)
            for k in by:
                sel &= (df[k] == fit[k]).to_numpy()
            pts = df[sel].sort_values("T")
            om = 2 * np.pi / pts["T"].to_numpy(float)
            label = ", ".join(_fmt(k, fit[k]) for k in by if df[k].nunique() > 1) or "all"
            ax.loglog(om, pts[rate], "o", color=colour,
                      label=f"{label}: m = {fit['m']:.2f} ± {fit['m_stderr']:.2f}")
            nc = _not_converged(pts).to_numpy()
            if nc.any():
                _ring(ax, om[nc], pts[rate].to_numpy(float)[nc], colour)
            ok = (om >= fit["omega_min"]) & (om <= fit["omega_max"])
            ax.loglog(om[ok], fit["c"] * om[ok] ** fit["m"], "-", color=colour, lw=1)
            ax.loglog(om, pts["alpha_c"], "x--", color=colour, lw=0.8, ms=4,
                      label=f"  α_c (eq. 24): m = {fit['m_c']:.2f}")
        from matplotlib.ticker import ScalarFormatter

        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(ScalarFormatter())
            axis.set_minor_formatter(ScalarFormatter())
        ax.tick_params(which="both", labelsize=7)
        same = [k for k in by if df[k].nunique() == 1]
        ax.set_title(_title(same, [df[k].iloc[0] for k in same]), fontsize=8)
        ax.set_xlabel("angular frequency ω [rad s⁻¹]")
        ax.set_ylabel(f"{RATE_LABEL[rate]} (dots; fit: line) and α_c [m⁻²]")
        ax.grid(alpha=0.3, which="both")
        handles, labels = ax.get_legend_handles_labels()   # one entry per fit, not deduped
        handles += _status_handles(df, ring=True)
        ax.legend(handles=handles, fontsize=6)
        _save(fig, out / "alpha_omega.png", written)
    return written


def _collision_zone_figure(df: pd.DataFrame, keys: Sequence[str],
                           shown: Sequence[tuple[tuple, pd.DataFrame]], out: Path) -> list[Path]:
    """``collision_zone.png``: W_c versus eps, one curve per group (colour and marker by the
    parameters that differ between the groups, :func:`_styles`), offset in eps so that equal
    values stay visible; no compact zone: a cross at the top; not converged: a square."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.4, 4.6), constrained_layout=True)
    vary = [i for i, k in enumerate(keys) if len({kv[0][i] for kv in shown}) > 1]
    same = [i for i in range(len(keys)) if i not in vary]
    sheet = derived(df)["L_sheet"].max()
    ax_top = float(sheet) if np.isfinite(sheet) else float(np.nanmax(df["W_c"]))
    eps_all = np.sort(df["eps"].unique())
    step = float(np.min(np.diff(eps_all))) if len(eps_all) > 1 else 0.1
    dodge = 0.25 * step / max(len(shown) - 1, 1)
    marked_none = False
    for i, ((key, sub), (colour, marker)) in enumerate(
            zip(shown, _styles(keys, [kv[0] for kv in shown]), strict=True)):
        sub = sub.sort_values("eps")
        x = sub["eps"].to_numpy(float) + (i - 0.5 * (len(shown) - 1)) * dodge
        label = _title([keys[j] for j in vary], [key[j] for j in vary]) or "all points"
        ax.plot(x, sub["W_c"], ls="-", marker=marker, color=colour, ms=5, lw=1, label=label)
        se = sub["W_c_stderr"] if "W_c_stderr" in sub.columns else None
        if se is not None and se.notna().any():   # bars only where there is an SE
            ok = (se.notna() & sub["W_c"].notna()).to_numpy()
            ax.errorbar(x[ok], sub["W_c"][ok], yerr=se[ok], fmt="none", ecolor=colour,
                        capsize=3, lw=1)
        none = sub["W_c"].isna().to_numpy()
        if none.any():      # no compact zone: marked at the top, not a width
            ax.plot(x[none], np.full(int(none.sum()), ax_top), "x", color=colour, ms=7)
            marked_none = True
        nc = _not_converged(sub).to_numpy()
        if nc.any():
            _ring(ax, x[nc], np.where(none[nc], ax_top, sub["W_c"].to_numpy(float)[nc]), colour)
    ax.set_title(_title([keys[j] for j in same], [shown[0][0][j] for j in same])
                 + (f"\n(curves offset in ε by up to ±{0.5 * dodge * (len(shown) - 1):.2g}"
                    " for visibility)" if len(shown) > 1 else ""), fontsize=8)
    ax.set_xlabel("restitution coefficient ε [–]")
    ax.set_ylabel("collision-zone width W_c [m]")
    extra = _status_handles(pd.concat([sub for _, sub in shown]), ring=True)
    if marked_none:
        from matplotlib.lines import Line2D

        extra.append(Line2D([], [], ls="none", marker="x", color="k",
                            label=f"no compact zone (drawn at {ax_top:g} m)"))
    ax.grid(alpha=0.3)
    handles, labels = _legend_of([ax], extra)
    fig.legend(handles, labels, fontsize=7, loc="outside right upper")
    written: list[Path] = []
    _save(fig, out / "collision_zone.png", written)
    return written


def _collision_stats_figure(df: pd.DataFrame, out: Path) -> list[Path]:
    """``collision_stats.png``: W_c / L_sheet and alpha_inner / alpha_c versus eps per floe
    size and dispersion relation, pooled over every other swept parameter
    (:func:`sweep.collision_stats`; bars: +-1 standard deviation over the pooled points)."""
    import matplotlib.pyplot as plt

    st = collision_stats(df, by=["L_x", "dispersion", "eps"])
    if not (st["W_c_rel_mean"].notna().any() or st["inner_over_c_median"].notna().any()):
        return []       # no compact zone anywhere: nothing to draw (WHY says so)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11.5, 4.0), constrained_layout=True)
    curves = sorted({(r.L_x, r.dispersion) for r in st.itertuples()},
                    key=lambda c: (c[0], DISP_ORDER.index(c[1]) if c[1] in DISP_ORDER else 9))
    for (L_x, disp), (colour, marker) in zip(curves, _styles(("L_x", "dispersion"), curves),
                                             strict=True):
        sub = st[(st["L_x"] == L_x) & (st["dispersion"] == disp)].sort_values("eps")
        label = f"L_x = {L_x:g} m, {str(disp).upper()}"
        ax1.errorbar(sub["eps"], sub["W_c_rel_mean"], yerr=sub["W_c_rel_std"].fillna(0.0),
                     marker=marker, ls=DISP_STYLE.get(disp, "-"), color=colour, ms=5,
                     lw=1.2, capsize=2, label=label)
        ax2.plot(sub["eps"], sub["inner_over_c_median"], marker=marker,
                 ls=DISP_STYLE.get(disp, "-"), color=colour, ms=5, lw=1.2, label=label)
        nc = (sub["n_not_converged"] > 0).to_numpy()
        if nc.any():
            _ring(ax1, sub["eps"][nc], sub["W_c_rel_mean"][nc], colour)
            _ring(ax2, sub["eps"][nc], sub["inner_over_c_median"][nc], colour)
    n = int(st["n_points"].sum())
    ax1.set_ylabel("collision-zone width / sheet length W_c / L_sheet [–]")
    ax1.set_title(f"(a) mean ± std over the other parameters ({n} points)", loc="left",
                  fontsize=9)
    ax2.axhline(1.0, color="k", lw=0.8, ls=":")
    ax2.set_ylabel("α_inner / α_c (median) [–]")
    ax2.set_title("(b) inner zone versus confined ice (1 = eq. 25)", loc="left", fontsize=9)
    for ax in (ax1, ax2):
        ax.set_xlabel("restitution coefficient ε [–]")
        ax.grid(alpha=0.3)
    handles, labels = _legend_of([ax1], _status_handles(df, ring=True))
    fig.legend(handles, labels, fontsize=7, loc="outside right upper")
    written: list[Path] = []
    _save(fig, out / "collision_stats.png", written)
    return written


RATE_LABEL = {"alpha_inner": "α_inner (x ≥ W_c)", "alpha_all": "α_all (all floes)"}

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


class NothingToDrawError(ConfigError):
    """No figure of the asked kinds can be drawn from the store's grid (exit status 2, as
    any input that cannot give what was asked); ``reasons`` maps each figure to why."""

    def __init__(self, message: str, reasons: dict[str, str]) -> None:
        super().__init__(message)
        self.reasons = dict(reasons)


def _stderr(message: str) -> None:
    import sys

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
        import matplotlib

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
    profiles = _Profiles(path)
    written: list[Path] = []
    reasons: dict[str, str] = {}
    for kind in kinds:
        drawn = _DRAW[kind](df, profiles, out, max_figures)
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
