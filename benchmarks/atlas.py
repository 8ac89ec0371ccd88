"""The atlas of the paper's grid: what the whole campaign says, from its shipped table.

    python benchmarks/atlas.py [results/herman2019] [--out docs] [--bootstrap 200]

Reads the per-point table (``sweep.load`` of ``results/herman2019``: the shards present)
and writes ``OUT/atlas.md`` with its figures in ``OUT/atlas/``:

- where a compact zone forms: the share of points whose layout is not ``none`` by each
  parameter, over the pairs T x a0 and C_sd x eps, and the layouts;
- W_c, alpha_inner / alpha_c, alpha_all and a_end / a0: the marginal mean over the grid at
  each value of each of the 7 parameters, and a variance decomposition (the share of the
  variance over the grid that the 7 main effects explain, and what each pairwise
  interaction adds: least squares with categorical factors);
- a power law for W_c in physically motivated groups (wave steepness a0 k, drag time over
  period tau_d / T, eps; ``floewave.transient.drag_time``), with its residuals;
- the three dispersion relations side by side.

Error bars. A point's values are ensemble means with jackknife standard errors (stochastic:
docs/convergence.md); a marginal mean over n points has the stochastic SE sqrt(sum se_i^2)
/ n. While only some shards are present the points are a uniform random sample of the
grid (a shard is the points whose hash is K mod 8), so a mean also has a sampling error:
the SE quoted is the larger of the two, the sampling one by a bootstrap over points
(``--bootstrap`` draws, seed 0). Every number in the page is printed by this command.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
GRID_POINTS = 24192


def responses(df: pd.DataFrame) -> dict[str, tuple[pd.Series, pd.Series, str]]:
    """name -> (value, SE, label) per point (NaN where undefined)."""
    ratio = df["alpha_inner"] / df["alpha_c"]
    return {
        "W_c": (df["W_c"], df["W_c_stderr"], "W_c [m]"),
        "inner_c": (ratio, df["alpha_inner_stderr"] / df["alpha_c"],
                    "alpha_inner / alpha_c"),
        "alpha_all": (df["alpha_all"], df["alpha_all_stderr"], "alpha_all [m^-2]"),
        "a_end_rel": (df["a_end_rel"], df["a_end_rel_stderr"], "a_end / a0"),
    }


def marginal(df, y, se, by, rng, n_boot):
    """Per value of ``by``: n, mean, SE (max of stochastic and bootstrap)."""
    out = []
    for v, idx in df.groupby(by, observed=True).groups.items():
        yy, ss = y.loc[idx].to_numpy(float), se.loc[idx].to_numpy(float)
        ok = np.isfinite(yy)
        yy, ss = yy[ok], ss[ok]
        if yy.size == 0:
            out.append((v, 0, math.nan, math.nan))
            continue
        stoch = math.sqrt(np.nansum(ss**2)) / yy.size
        boot = (np.std([rng.choice(yy, yy.size).mean() for _ in range(n_boot)])
                if yy.size > 1 and n_boot else 0.0)
        out.append((v, int(yy.size), float(yy.mean()), float(max(stoch, boot))))
    return out


def design(df, factors, pairs=()):
    """One-hot design matrix of categorical ``factors`` (and their pairwise products)."""
    cols = [np.ones(len(df))]
    for f in factors:
        d = pd.get_dummies(df[f].astype(str), drop_first=True, dtype=float)
        cols += [d[c].to_numpy() for c in d]
    for a, b in pairs:
        key = df[a].astype(str) + "|" + df[b].astype(str)
        d = pd.get_dummies(key, drop_first=True, dtype=float)
        cols += [d[c].to_numpy() for c in d]
    return np.column_stack(cols)


def r2(X, y):
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ beta
    return 1.0 - float(res @ res) / float(((y - y.mean()) ** 2).sum())


def decomposition(df, y):
    ok = np.isfinite(y.to_numpy(float))
    d, yy = df[ok], y[ok].to_numpy(float)
    main = {f: r2(design(d, [f]), yy) for f in PARAMS}
    full = r2(design(d, PARAMS), yy)
    pairs = []
    for i, a in enumerate(PARAMS):
        for b in PARAMS[i + 1:]:
            pairs.append(((a, b), r2(design(d, PARAMS, [(a, b)]), yy) - full))
    pairs.sort(key=lambda t: -t[1])
    return int(ok.sum()), main, full, pairs


def fmt(x, se):
    if not np.isfinite(x):
        return "n/a"
    if not np.isfinite(se) or se == 0:
        return f"{x:.4g}"
    digits = max(0, -int(math.floor(math.log10(se))) + 1)
    return f"{x:.{digits}f} ± {se:.{digits}f}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("table", nargs="?", default=str(ROOT / "results" / "herman2019"))
    ap.add_argument("--out", type=Path, default=ROOT / "docs")
    ap.add_argument("--bootstrap", type=int, default=200)
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import sweep
    from floewave import ModelConfig
    from floewave.transient import drag_time

    df = sweep.load(args.table)
    files = list(df.attrs.get("files", ()))
    rng = np.random.default_rng(0)
    figdir = args.out / "atlas"
    figdir.mkdir(parents=True, exist_ok=True)
    lines: list[str] = []
    say = lines.append
    n = len(df)
    counts = df["status"].value_counts()
    say("# Atlas of the paper's grid\n")
    say(f"Made by `python benchmarks/atlas.py` from `results/herman2019` ({', '.join(files)}):"
        f" **{n} of the grid's {GRID_POINTS} points** ({100 * n / GRID_POINTS:.1f} %; each"
        " shard a uniform random sample of the grid, so until all eight are in, every mean"
        " below also carries a sampling error, included in its SE). Model version"
        f" {sorted(set(json.loads(p)['model_version'] for p in df['provenance']))[0]},"
        " ensembles of 8 replicas, **stochastic** (another seed or CPU moves the values"
        " within their error bars); machine and dates in"
        " `results/herman2019/provenance.json`.\n")
    say("Status: " + ", ".join(f"{s} {int(c)}" for s, c in counts.items() if c) + ".\n")
    ok = df[df["status"].isin(["converged", "converged_noisy", "not_converged"])].copy()

    # --- where a compact zone forms
    ok["compact"] = (ok["compact_zone"].astype(str) != "none").astype(float)
    say("## Where a compact zone forms\n")
    lay = ok["compact_zone"].astype(str).value_counts()
    say("Layouts (`compact_zone`): " + ", ".join(f"{k} {v} ({100 * v / len(ok):.1f} %)"
                                                 for k, v in lay.items()) + ".\n")
    say("Share of points with a compact zone (± binomial SE) by each parameter:\n")
    say("| parameter | " + " | ".join(["value: share"] * 1) + " |")
    say("|---|---|")
    for p in PARAMS:
        cells = []
        for v, g in ok.groupby(p, observed=True):
            s = g["compact"].mean()
            cells.append(f"{v}: {s:.3f} ± {math.sqrt(s * (1 - s) / len(g)):.3f}")
        say(f"| {p} | {'; '.join(cells)} |")
    say("")
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, (a, b) in zip(axes, (("T", "a0"), ("C_sd", "eps")), strict=True):
        piv = ok.pivot_table(index=a, columns=b, values="compact", aggfunc="mean",
                             observed=True)
        im = ax.imshow(piv.to_numpy(), origin="lower", vmin=0, vmax=1, cmap="viridis",
                       aspect="auto")
        ax.set_xticks(range(piv.shape[1]), [str(c) for c in piv.columns])
        ax.set_yticks(range(piv.shape[0]), [str(r) for r in piv.index])
        ax.set_xlabel(b)
        ax.set_ylabel(a)
        for i in range(piv.shape[0]):
            for j in range(piv.shape[1]):
                ax.text(j, i, f"{piv.iat[i, j]:.2f}", ha="center", va="center",
                        color="w" if piv.iat[i, j] < 0.6 else "k", fontsize=8)
    fig.colorbar(im, ax=axes, label="share of points with a compact zone")
    fig.savefig(figdir / "compact_share.png", dpi=110)
    plt.close(fig)
    say("![Share of points with a compact zone over T x a0 and C_sd x eps]"
        "(atlas/compact_share.png)\n")

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
            m = marginal(ok, y, se, p, rng, args.bootstrap)
            say(f"| {p} | " + "; ".join(f"{v}: {fmt(mu, s)} ({k})" for v, k, mu, s in m)
                + " |")
            ax = axes[r, c]
            xs = np.arange(len(m))
            ax.errorbar(xs, [t[2] for t in m], yerr=[t[3] for t in m], fmt="o-", ms=4)
            ax.set_xticks(xs, [str(t[0]) for t in m], rotation=45, fontsize=7)
            if r == len(resp) - 1:
                ax.set_xlabel(p)
            if c == 0:
                ax.set_ylabel(label, fontsize=8)
        say("")
    fig.tight_layout()
    fig.savefig(figdir / "marginal.png", dpi=100)
    plt.close(fig)
    say("![Marginal means of W_c, alpha_inner/alpha_c, alpha_all and a_end/a0 by each"
        " parameter](atlas/marginal.png)\n")

    # --- variance decomposition
    say("## Which parameters matter, and which interact\n")
    say("Least squares over the points with the 7 parameters as categorical factors: R² of"
        " each factor alone, of all 7 main effects together, and the R² each pairwise"
        " interaction adds to the main effects (the three largest). log10 of W_c and"
        " alpha_all (positive, spanning decades).\n")
    say("| response | n | R² alone: " + ", ".join(PARAMS) + " | 7 main effects | largest"
        " interactions (ΔR²) |")
    say("|---|---|---|---|---|")
    for name, (y, _, label) in resp.items():
        yy = np.log10(y.where(y > 0)) if name in ("W_c", "alpha_all") else y
        k, mains, full, pairs = decomposition(ok, yy)
        say(f"| {label if name not in ('W_c', 'alpha_all') else 'log10 ' + label} | {k} | "
            + ", ".join(f"{mains[p]:.2f}" for p in PARAMS) + f" | {full:.3f} | "
            + "; ".join(f"{a}×{b} {d:.3f}" for (a, b), d in pairs[:3]) + " |")
    say("")

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
    fits = {}
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

    # --- dispersion relations side by side
    say("## The three dispersion relations\n")
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for ax, (name, (y, se, label)) in zip(axes, [(k, resp[k]) for k in
                                                  ("a_end_rel", "W_c", "inner_c")],
                                          strict=True):
        for disp, c in (("ep", "C0"), ("ml", "C1"), ("ow", "C2")):
            g = ok[ok["dispersion"] == disp]
            m = marginal(g, y.loc[g.index], se.loc[g.index], "T", rng, args.bootstrap)
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
    say("| dispersion | points | share with a compact zone | a_end/a0 | W_c [m] |")
    say("|---|---|---|---|---|")
    for disp in ("ep", "ml", "ow"):
        g = ok[ok["dispersion"] == disp]
        s = g["compact"].mean()
        ya, sa, _ = resp["a_end_rel"]
        yw, sw, _ = resp["W_c"]
        ma = marginal(g.assign(_all=0), ya.loc[g.index], sa.loc[g.index], "_all", rng,
                      args.bootstrap)[0]
        mw = marginal(g.assign(_all=0), yw.loc[g.index], sw.loc[g.index], "_all", rng,
                      args.bootstrap)[0]
        say(f"| {disp} | {len(g)} | {s:.3f} ± {math.sqrt(s * (1 - s) / len(g)):.3f} | "
            f"{fmt(ma[2], ma[3])} | {fmt(mw[2], mw[3])} |")
    say("")
    (args.out / "atlas.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
