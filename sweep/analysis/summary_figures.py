"""The summary figures of a store: W_c(eps), collision-zone statistics, alpha(omega) laws.

``collision_zone.png``, ``collision_stats.png`` (:func:`sweep.collision_stats`) and
``alpha_omega.png`` (:func:`sweep.alpha_omega`): the ``summary`` kind of ``sweep figures``.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from sweep.analysis.plotting import (
    DISP_ORDER,
    DISP_STYLE,
    ProfileCache,
    closeness_to_paper,
    colour_cycle,
    curve_styles,
    draw_ring,
    format_value,
    group_title,
    legend_of,
    not_converged_mask,
    point_groups,
    save_figure,
    status_handles,
)
from sweep.analysis.stats import SWEPT, alpha_omega, collision_stats, derived

__all__ = ["summary", "RATE_LABEL"]

def summary(df: pd.DataFrame, profiles: ProfileCache, out: Path, limit: int) -> list[Path]:
    """W_c versus eps, and alpha_inner(omega) with the fitted exponents."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    written: list[Path] = []
    keys = ("L_x", "T", "a0", "C_sd", "d_f", "dispersion")
    groups = point_groups(df, keys, "eps")
    if groups:
        written += collision_zone_figure(df, keys, groups[:12], out)
    if df["eps"].nunique() > 1:
        written += collision_stats_figure(df, out)
    rate = "alpha_inner"
    fits = alpha_omega(df, rate)
    if not np.isfinite(fits["m"]).any():     # no inner zone anywhere: fit all floes
        rate = "alpha_all"
        fits = alpha_omega(df, rate)
    fits = fits[np.isfinite(fits["m"])]
    if not fits.empty:
        by = [k for k in SWEPT if k in fits.columns]
        fits = fits.assign(_order=[closeness_to_paper(by, tuple(r[k] for k in by))
                                   for _, r in fits.iterrows()]).sort_values("_order")
        fig, ax = plt.subplots(figsize=(7.0, 4.6), constrained_layout=True)
        for colour, (_, fit) in zip(colour_cycle(min(len(fits), 8)), fits.head(8).iterrows(),
                                    strict=False):
            sel = np.ones(len(df), dtype=bool)
            for k in by:
                sel &= (df[k] == fit[k]).to_numpy()
            pts = df[sel].sort_values("T")
            om = 2 * np.pi / pts["T"].to_numpy(float)
            label = ", ".join(format_value(k, fit[k]) for k in by if df[k].nunique() > 1) or "all"
            ax.loglog(om, pts[rate], "o", color=colour,
                      label=f"{label}: m = {fit['m']:.2f} ± {fit['m_stderr']:.2f}")
            nc = not_converged_mask(pts).to_numpy()
            if nc.any():
                draw_ring(ax, om[nc], pts[rate].to_numpy(float)[nc], colour)
            ok = (om >= fit["omega_min"]) & (om <= fit["omega_max"])
            ax.loglog(om[ok], fit["c"] * om[ok] ** fit["m"], "-", color=colour, lw=1)
            ax.loglog(om, pts["alpha_c"], "x--", color=colour, lw=0.8, ms=4,
                      label=f"  α_c (eq. 24): m = {fit['m_c']:.2f}")
        from matplotlib.ticker import ScalarFormatter  # lazy: optional (plot extra), 0.8 s

        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(ScalarFormatter())
            axis.set_minor_formatter(ScalarFormatter())
        ax.tick_params(which="both", labelsize=7)
        same = [k for k in by if df[k].nunique() == 1]
        ax.set_title(group_title(same, [df[k].iloc[0] for k in same]), fontsize=8)
        ax.set_xlabel("angular frequency ω [rad s⁻¹]")
        ax.set_ylabel(f"{RATE_LABEL[rate]} (dots; fit: line) and α_c [m⁻²]")
        ax.grid(alpha=0.3, which="both")
        handles, labels = ax.get_legend_handles_labels()   # one entry per fit, not deduped
        handles += status_handles(df, ring=True)
        ax.legend(handles=handles, fontsize=6)
        save_figure(fig, out / "alpha_omega.png", written)
    return written


def collision_zone_figure(df: pd.DataFrame, keys: Sequence[str],
                           shown: Sequence[tuple[tuple, pd.DataFrame]], out: Path) -> list[Path]:
    """``collision_zone.png``: W_c versus eps, one curve per group (colour and marker by the
    parameters that differ between the groups, :func:`curve_styles`), offset in eps so that equal
    values stay visible; no compact zone: a cross at the top; not converged: a square."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

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
            zip(shown, curve_styles(keys, [kv[0] for kv in shown]), strict=True)):
        sub = sub.sort_values("eps")
        x = sub["eps"].to_numpy(float) + (i - 0.5 * (len(shown) - 1)) * dodge
        label = group_title([keys[j] for j in vary], [key[j] for j in vary]) or "all points"
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
        nc = not_converged_mask(sub).to_numpy()
        if nc.any():
            draw_ring(ax, x[nc], np.where(none[nc], ax_top, sub["W_c"].to_numpy(float)[nc]), colour)
    ax.set_title(group_title([keys[j] for j in same], [shown[0][0][j] for j in same])
                 + (f"\n(curves offset in ε by up to ±{0.5 * dodge * (len(shown) - 1):.2g}"
                    " for visibility)" if len(shown) > 1 else ""), fontsize=8)
    ax.set_xlabel("restitution coefficient ε [–]")
    ax.set_ylabel("collision-zone width W_c [m]")
    extra = status_handles(pd.concat([sub for _, sub in shown]), ring=True)
    if marked_none:
        from matplotlib.lines import Line2D  # lazy: optional (plot extra), 0.8 s

        extra.append(Line2D([], [], ls="none", marker="x", color="k",
                            label=f"no compact zone (drawn at {ax_top:g} m)"))
    ax.grid(alpha=0.3)
    handles, labels = legend_of([ax], extra)
    fig.legend(handles, labels, fontsize=7, loc="outside right upper")
    written: list[Path] = []
    save_figure(fig, out / "collision_zone.png", written)
    return written


def collision_stats_figure(df: pd.DataFrame, out: Path) -> list[Path]:
    """``collision_stats.png``: W_c / L_sheet and alpha_inner / alpha_c versus eps per floe
    size and dispersion relation, pooled over every other swept parameter
    (:func:`sweep.collision_stats`; bars: +-1 standard deviation over the pooled points)."""
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    st = collision_stats(df, by=["L_x", "dispersion", "eps"])
    if not (st["W_c_rel_mean"].notna().any() or st["inner_over_c_median"].notna().any()):
        return []       # no compact zone anywhere: nothing to draw (WHY says so)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11.5, 4.0), constrained_layout=True)
    curves = sorted({(r.L_x, r.dispersion) for r in st.itertuples()},
                    key=lambda c: (c[0], DISP_ORDER.index(c[1]) if c[1] in DISP_ORDER else 9))
    empty = []  # series without a compact zone at any eps: named, not drawn
    for (L_x, disp), (colour, marker) in zip(curves, curve_styles(("L_x", "dispersion"), curves),
                                             strict=True):
        sub = st[(st["L_x"] == L_x) & (st["dispersion"] == disp)].sort_values("eps")
        label = f"L_x = {L_x:g} m, {str(disp).upper()}"
        if not (sub["W_c_rel_mean"].notna().any() or sub["inner_over_c_median"].notna().any()):
            empty.append(label)
            continue
        ax1.errorbar(sub["eps"], sub["W_c_rel_mean"], yerr=sub["W_c_rel_std"].fillna(0.0),
                     marker=marker, ls=DISP_STYLE.get(disp, "-"), color=colour, ms=5,
                     lw=1.2, capsize=2, label=label)
        ax2.plot(sub["eps"], sub["inner_over_c_median"], marker=marker,
                 ls=DISP_STYLE.get(disp, "-"), color=colour, ms=5, lw=1.2, label=label)
        nc = (sub["n_not_converged"] > 0).to_numpy()
        if nc.any():
            draw_ring(ax1, sub["eps"][nc], sub["W_c_rel_mean"][nc], colour)
            draw_ring(ax2, sub["eps"][nc], sub["inner_over_c_median"][nc], colour)
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
    from matplotlib.lines import Line2D  # lazy: matplotlib is the plot extra

    absent = [Line2D([], [], ls="none", label=f"{label}: no compact zone (not drawn)")
              for label in empty]
    handles, labels = legend_of([ax1], [*status_handles(df, ring=True), *absent])
    fig.legend(handles, labels, fontsize=7, loc="outside right upper")
    written: list[Path] = []
    save_figure(fig, out / "collision_stats.png", written)
    return written



RATE_LABEL = {"alpha_inner": "α_inner (x ≥ W_c)", "alpha_all": "α_all (all floes)"}
