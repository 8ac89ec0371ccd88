"""The atlas's sections on the grid as a whole: where a compact zone forms, each
parameter's marginal effect, the variance decomposition and a power law for W_c."""
from __future__ import annotations

import json
import math

import numpy as np

from floewave import ModelConfig
from floewave.transient import drag_time
from herman2019.atlas.page import Page
from herman2019.atlas.stats import PARAMS, axis_label, decomposition, fmt, marginal, responses

__all__ = ["compact_zones", "marginal_effects", "variance", "wc_law"]


def compact_zones(page: Page) -> None:
    """Where a compact zone forms: the layouts, the share by each parameter and its figure."""
    say = page.say
    plt, figdir = page.plt, page.figdir
    # --- where a compact zone forms: over every point with results (not_converged too)
    page.ok["compact"] = (page.ok["compact_zone"].astype(str) != "none").astype(float)
    page.shares["compact"] = (page.shares["compact_zone"].astype(str) != "none").astype(float)
    ok = page.shares
    say("## Where a compact zone forms\n")
    lay = ok["compact_zone"].astype(str).value_counts()
    say("Layouts (`compact_zone`): " + ", ".join(f"{k} {v} ({100 * v / len(ok):.1f} %)"
                                                 for k, v in lay.items()) + ".\n")
    say(f"Share of the {len(ok)} points with results (not_converged included) that have a"
        " compact zone (± binomial SE) by each parameter:\n")
    say("| parameter | value: share |")
    say("|---|---|")
    for p in PARAMS:
        cells = []
        for v, g in ok.groupby(p, observed=True):
            s = g["compact"].mean()
            cells.append(f"{v}: {s:.3f} ± {math.sqrt(s * (1 - s) / len(g)):.3f}")
        say(f"| {p} | {'; '.join(cells)} |")
    say("")
    fig, axes = plt.subplots(1, 3, figsize=(15, 4), constrained_layout=True)
    for ax, (a, b) in zip(axes, (("T", "a0"), ("C_sd", "eps"), ("d_f", "L_x")), strict=True):
        piv = ok.pivot_table(index=a, columns=b, values="compact", aggfunc="mean",
                             observed=True)
        im = ax.imshow(piv.to_numpy(), origin="lower", vmin=0, vmax=1, cmap="viridis",
                       aspect="auto")
        ax.set_xticks(range(piv.shape[1]), [str(c) for c in piv.columns])
        ax.set_yticks(range(piv.shape[0]), [str(r) for r in piv.index])
        ax.set_xlabel(axis_label(b))
        ax.set_ylabel(axis_label(a))
        for i in range(piv.shape[0]):
            for j in range(piv.shape[1]):
                ax.text(j, i, f"{piv.iat[i, j]:.2f}", ha="center", va="center",
                        color="w" if piv.iat[i, j] < 0.6 else "k", fontsize=8)
    fig.colorbar(im, ax=axes, label="share of points with a compact zone")
    fig.savefig(figdir / "compact_share.png", dpi=110)
    plt.close(fig)
    say("![Share of points with a compact zone over T x a0, C_sd x eps and d_f x L_x]"
        "(atlas/compact_share.png)\n")
    page.lay = lay


def marginal_effects(page: Page) -> None:
    """The mean over every other parameter at each value of each parameter, and their figure."""
    say, ok = page.say, page.ok
    plt, figdir = page.plt, page.figdir
    rng = page.rng
    # --- marginal effects
    resp = responses(ok)
    say("## Marginal effect of each parameter\n")
    say("The mean over every other parameter at each value (W_c and alpha_inner / alpha_c"
        " over the points with a compact zone only; `n` points behind each mean):\n")
    fig, axes = plt.subplots(len(resp), len(PARAMS), figsize=(17, 10), sharey="row")
    for r, (name, (y, se, label)) in enumerate(resp.items()):
        say(f"**{label}**\n")
        say("| parameter | value: mean ± SE (n) |")
        say("|---|---|")
        for c, p in enumerate(PARAMS):
            m = marginal(ok, y, se, p, rng, page.bootstrap)
            say(f"| {p} | " + "; ".join(f"{v}: {fmt(mu, s)} ({k})" for v, k, mu, s in m)
                + " |")
            ax = axes[r, c]
            xs = np.arange(len(m))
            ax.errorbar(xs, [t[2] for t in m], yerr=[t[3] for t in m], fmt="o-", ms=4)
            ax.set_xticks(xs, [str(t[0]) for t in m], rotation=45, fontsize=7)
            if r == len(resp) - 1:
                ax.set_xlabel(axis_label(p))
            if c == 0:
                ax.set_ylabel(label, fontsize=8)
        say("")
    fig.tight_layout()
    fig.savefig(figdir / "marginal.png", dpi=100)
    plt.close(fig)
    say("![Marginal means of W_c, alpha_inner/alpha_c, alpha_all and a_end/a0 by each"
        " parameter](atlas/marginal.png)\n")
    page.resp = resp


def variance(page: Page) -> None:
    """Which parameters matter and which interact: R² of least squares with categorical factors."""
    say, ok = page.say, page.ok
    resp = page.resp
    # --- variance decomposition
    say("## Which parameters matter, and which interact\n")
    say("Least squares over the points with the 7 parameters as categorical factors: R² of"
        " each factor alone, of all 7 main effects together, and the R² each pairwise"
        " interaction adds to the main effects (the three largest). log10 of W_c and"
        " alpha_all (positive, spanning decades).\n")
    say("| response | n | R² alone: " + ", ".join(PARAMS) + " | 7 main effects | largest"
        " interactions (ΔR²) |")
    say("|---|---|---|---|---|")
    decomp = {}
    for name, (y, _, label) in resp.items():
        yy = np.log10(y.where(y > 0)) if name in ("W_c", "alpha_all") else y
        k, mains, full, pairs = decomposition(ok, yy)
        decomp[name] = (k, mains, full, pairs)
        say(f"| {label if name not in ('W_c', 'alpha_all') else 'log10 ' + label} | {k} | "
            + ", ".join(f"{mains[p]:.2f}" for p in PARAMS) + f" | {full:.3f} | "
            + "; ".join(f"{a}×{b} {d:.3f}" for (a, b), d in pairs[:3]) + " |")
    say("")
    page.decomp = decomp


def wc_law(page: Page) -> None:
    """A power law for W_c in physically motivated groups, its residuals and figure."""
    say, ok = page.say, page.ok
    plt, figdir = page.plt, page.figdir
    decomp = page.decomp
    # --- a law for W_c
    say("## A law for W_c\n")
    zc = ok[np.isfinite(ok["W_c"]) & (ok["W_c"] > 0)].copy()
    tau = []
    for cj, k in zip(zc["config_json"], zc["k"], strict=True):
        cfg = ModelConfig.from_dict(json.loads(cj))
        tau.append(drag_time(cfg, float(k)))
    zc["steep"] = zc["a0"] * zc["k"]
    zc["tau_T"] = np.asarray(tau) / zc["T"]
    zc["kL"] = zc["k"] * zc["L_x"]
    groups = ["steep", "tau_T", "eps", "kL", "d_f"]
    X = np.column_stack([np.ones(len(zc))] + [np.log(zc[g].to_numpy(float)) for g in groups])
    Y = np.log(zc["W_c"].to_numpy(float))
    fits, law = {}, None
    for disp in ("all", "ep", "ml", "ow"):
        sel = np.ones(len(zc), bool) if disp == "all" else (zc["dispersion"] == disp).to_numpy()
        if sel.sum() < 10:
            continue
        beta, *_ = np.linalg.lstsq(X[sel], Y[sel], rcond=None)
        res = Y[sel] - X[sel] @ beta
        # SE of the exponents: from the residual scatter (the points' own error bars are
        # far smaller than the law's misfit)
        cov = np.linalg.inv(X[sel].T @ X[sel]) * float(res @ res) / max(sel.sum() - X.shape[1], 1)
        fits[disp] = (beta, np.sqrt(np.diag(cov)), res, sel)
    say("W_c ∝ (a0 k)^p1 (tau_d / T)^p2 eps^p3 (k L_x)^p4 d_f^p5 fitted in log space over"
        f" the {len(zc)} points with a compact zone (tau_d the drag relaxation time,"
        " `floewave.transient.drag_time`); exponent ± SE (from the residual scatter),"
        " and the RMS of the log residual (a factor exp(RMS) typical misfit):\n")
    say("| dispersion | n | " + " | ".join(f"p({g})" for g in groups) + " | RMS log residual |")
    say("|---|---|" + "---|" * len(groups) + "---|")
    for disp, (beta, se, res, sel) in fits.items():
        say(f"| {disp} | {int(sel.sum())} | "
            + " | ".join(fmt(b, s) for b, s in zip(beta[1:], se[1:], strict=True))
            + f" | {math.sqrt(np.mean(res**2)):.3f} |")
    say("")
    if "all" in fits:
        beta, _, res, sel = fits["all"]
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        pred = np.exp(X @ beta)
        for disp, c in (("ep", "C0"), ("ml", "C1"), ("ow", "C2")):
            s = (zc["dispersion"] == disp).to_numpy()
            axes[0].loglog(pred[s], zc["W_c"].to_numpy()[s], ".", ms=2, color=c, label=disp)
        lim = [zc["W_c"].min() * 0.8, zc["W_c"].max() * 1.2]
        axes[0].plot(lim, lim, "k-", lw=0.8)
        axes[0].set_xlabel("law [m]")
        axes[0].set_ylabel("W_c [m]")
        axes[0].legend()
        axes[1].hist(res, bins=60)
        axes[1].set_xlabel("log residual (all dispersions)")
        fig.tight_layout()
        fig.savefig(figdir / "wc_law.png", dpi=110)
        plt.close(fig)
        say("![W_c against the fitted law, and its residuals](atlas/wc_law.png)\n")
        rel_se = (zc["W_c_stderr"] / zc["W_c"]).to_numpy(float)
        rms = math.sqrt(np.mean(res**2))
        say(f"The law's typical misfit (RMS log residual {rms:.3f}, a factor"
            f" {math.exp(rms):.2f}) is {rms / np.nanmedian(rel_se):.0f} times the points' own"
            f" median relative error bar ({100 * np.nanmedian(rel_se):.1f} %): a power law in"
            " these groups is a rough scaling of W_c, not a law that holds to within the"
            " error bars. The variance decomposition says why: log W_c's largest"
            f" interaction is {'×'.join(decomp['W_c'][3][0][0])} (ΔR²"
            f" {decomp['W_c'][3][0][1]:.2f}), and its 7 main effects together explain"
            f" {100 * decomp['W_c'][2]:.0f} % of its variance.\n")
        law = {"rms": rms, "ratio": rms / np.nanmedian(rel_se), "beta": beta}
    page.law = law
