"""The atlas's last sections and its headlines: the grid's cost, the three dispersion
relations side by side, and the headlines put at the top of the page."""
from __future__ import annotations

import json
import math

import numpy as np

from herman2019.atlas.page import Page
from herman2019.atlas.stats import PARAMS, fmt, marginal

__all__ = ["cost", "dispersions", "headlines"]


def cost(page: Page) -> None:
    """Where the time goes: the wall-time distribution and why the slowest 1 % are slow."""
    say = page.say
    ok = page.all[np.isfinite(page.all["model_wall_time"].astype(float))]
    ok = ok.assign(compact=(ok["compact_zone"].astype(str) != "none").astype(float))
    # every point with a wall time: the not_converged ones cost most
    # --- the grid's cost: where the time goes
    say("## The cost of the grid\n")
    wt = ok["model_wall_time"].to_numpy(float)
    maxit = int(json.loads(ok["config_json"].iloc[0]).get("max_iterations", 0)) or None
    q99 = float(np.quantile(wt, 0.99))
    slow = ok[ok["model_wall_time"] >= q99]
    say(f"Model wall time per point (one core, 8 replicas): median {np.median(wt):.2f} s,"
        f" mean {wt.mean():.2f} s, 99th percentile {q99:.2f} s, maximum {wt.max():.2f} s;"
        f" {wt.sum() / 3600:.2f} hours summed over these {len(ok)} points (wall time of"
        " each point on its rank, with 3 ranks sharing 2 cores: more than the CPU time;"
        f" the CPU of all ranks is in `{page.source}/provenance.json`).\n")
    cap = (slow["iterations"] >= maxit).mean() if maxit else math.nan
    say(f"The slowest 1 % ({len(slow)} points, ≥ {q99:.2f} s) are slow because their"
        " attenuation iteration does not settle: median"
        f" {np.median(slow['iterations']):.0f} iterations against"
        f" {np.median(ok['iterations']):.0f} over the grid,"
        f" {100 * cap:.0f} % of them stopped at the cap of {maxit}, and"
        f" {100 * (slow['status'] == 'not_converged').mean():.0f} % are not_converged"
        f" (against {100 * (ok['status'] == 'not_converged').mean():.1f} % overall);"
        f" {100 * slow['compact'].mean():.0f} % have a compact zone (against"
        f" {100 * ok['compact'].mean():.0f} %), whose boundary wanders from window to"
        " window. The values over-represented among them (share in the slowest 1 % over"
        " the share in the grid, ≥ 1.5):"
        + "; ".join(f" {q} = {v} ({share:.1f}x)" for q in PARAMS
                    for v, share in (slow[q].astype(str).value_counts(normalize=True)
                                     / ok[q].astype(str).value_counts(normalize=True)
                                     ).dropna().items() if share >= 1.5) + ".\n")


def dispersions(page: Page) -> None:
    """The three dispersion relations side by side (a table and a figure)."""
    say, ok = page.say, page.ok
    plt, figdir = page.plt, page.figdir
    rng, resp = page.rng, page.resp
    # --- dispersion relations side by side
    say("## The three dispersion relations\n")
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for ax, (name, (y, se, label)) in zip(axes, [(k, resp[k]) for k in
                                                  ("a_end_rel", "W_c", "inner_c")],
                                          strict=True):
        for disp, c in (("ep", "C0"), ("ml", "C1"), ("ow", "C2")):
            g = ok[ok["dispersion"] == disp]
            m = marginal(g, y.loc[g.index], se.loc[g.index], "T", rng, page.bootstrap)
            ax.errorbar([t[0] for t in m], [t[2] for t in m], yerr=[t[3] for t in m],
                        fmt="o-", ms=3, color=c, label=disp)
        ax.set_xlabel("T [s]")
        ax.set_ylabel(label)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(figdir / "dispersion.png", dpi=110)
    plt.close(fig)
    say("Mean over the other parameters at each period:\n")
    say("![a_end/a0, W_c and alpha_inner/alpha_c against T for ep, ml, ow]"
        "(atlas/dispersion.png)\n")
    say("| dispersion | points with results | share with a compact zone | converged points |"
        " a_end/a0 | W_c [m] |")
    say("|---|---|---|---|---|---|")
    disp_means = {}
    for disp in ("ep", "ml", "ow"):
        g = ok[ok["dispersion"] == disp]
        sg = page.shares[page.shares["dispersion"] == disp]
        s = sg["compact"].mean()
        ya, sa, _ = resp["a_end_rel"]
        yw, sw, _ = resp["W_c"]
        ma = marginal(g.assign(_all=0), ya.loc[g.index], sa.loc[g.index], "_all", rng,
                      page.bootstrap)[0]
        mw = marginal(g.assign(_all=0), yw.loc[g.index], sw.loc[g.index], "_all", rng,
                      page.bootstrap)[0]
        disp_means[disp] = fmt(ma[2], ma[3])
        say(f"| {disp} | {len(sg)} | {s:.3f} ± {math.sqrt(s * (1 - s) / len(sg)):.3f} |"
            f" {len(g)} | {fmt(ma[2], ma[3])} | {fmt(mw[2], mw[3])} |")
    say("")
    page.disp_means = disp_means


def headlines(page: Page) -> None:
    """The headlines, computed from the sections, put at the top of the page."""
    lines, head_at, lay = page.lines, page.head_at, page.lay
    verdicts, decomp, law = page.verdicts, page.decomp, page.law
    disp_means = page.disp_means
    # --- headlines, at the top
    shares = page.shares
    spread = {q: shares.groupby(q, observed=True)["compact"].mean() for q in PARAMS}
    top = max(spread, key=lambda q: spread[q].max() - spread[q].min())
    d_share = spread[top]
    heads = ["## Headlines\n",
             f"- A compact zone forms at {100 * shares['compact'].mean():.1f} % of the points"
             f" ({lay.get('edge', 0)} edge, {lay.get('patchy', 0)} patchy,"
             f" {lay.get('inverted', 0)} inverted); of the 7 parameters {top} moves its"
             f" share most: {100 * d_share.max():.1f} % at {top} = {d_share.idxmax()} against"
             f" {100 * d_share.min():.1f} % at {d_share.idxmin()}.",
             "- The paper's trend statements, over every pair of the grid:"]
    for v in dict.fromkeys(vv for _, vv, _ in verdicts):
        heads.append(f"  - **{v}**: " + "; ".join(
            f"{c}" + (f" ({100 * t['contra'] / t['n']:.0f} % contradict)"
                      if vv != "holds over the grid" else "")
            for c, vv, t in verdicts if vv == v) + ".")
    heads += [
             f"- alpha_all is set by C_sd and T (R² {decomp['alpha_all'][1]['C_sd']:.2f} and"
             f" {decomp['alpha_all'][1]['T']:.2f} alone); log W_c by d_f"
             f" ({decomp['W_c'][1]['d_f']:.2f}), T ({decomp['W_c'][1]['T']:.2f}) and the"
             f" {'×'.join(decomp['W_c'][3][0][0])} interaction"
             f" ({decomp['W_c'][3][0][1]:.2f}); the 7 main effects explain"
             f" {100 * decomp['W_c'][2]:.0f} % of log W_c's variance and"
             f" {100 * decomp['alpha_all'][2]:.0f} % of log alpha_all's.",
             ]
    if law:
        b = law["beta"]
        heads.append(f"- W_c ∝ (a0 k)^{b[1]:.2f} (tau_d/T)^{b[2]:.2f} eps^{b[3]:.2f}"
                     f" (k L_x)^{b[4]:.2f} d_f^{b[5]:.2f} to within a factor"
                     f" {math.exp(law['rms']):.2f}, {law['ratio']:.0f} times its error bars:"
                     " a rough scaling, no law within them.")
    heads.append("- By dispersion relation (mean a_end/a0): " + "; ".join(
        f"{k} {v}" for k, v in disp_means.items()) + ".")
    heads.append("")
    lines[head_at:head_at] = heads
