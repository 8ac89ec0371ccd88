"""The atlas of the paper's grid: what the whole campaign says, from its shipped table.

    python benchmarks/atlas.py [results/herman2019] [--out docs] [--bootstrap 200]

Reads the per-point table (``sweep.load`` of ``results/herman2019``: the shards present)
and writes ``OUT/atlas.md`` with its figures in ``OUT/atlas/``:

- headlines, computed from what follows;
- where a compact zone forms: the share of points whose layout is not ``none`` by each
  parameter, over the pairs T x a0, C_sd x eps and d_f x L_x, and the layouts;
- W_c, alpha_inner / alpha_c, alpha_all and a_end / a0: the marginal mean over the grid at
  each value of each of the 7 parameters, and a variance decomposition (the share of the
  variance over the grid that the 7 main effects explain, and what each pairwise
  interaction adds: least squares with categorical factors);
- a power law for W_c in physically motivated groups (wave steepness a0 k, drag time over
  period tau_d / T, eps; ``floewave.transient.drag_time``), with its residuals;
- the paper's trend statements of §4.2 and §5 tested on every pair of grid points that
  differ in one parameter alone (``paired``), with where the contradictions concentrate;
- the grid's cost: the wall-time distribution and why the slowest 1 % are slow;
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


def paired(ok, y, se, p, sign, *, order=None, where=None):
    """The paper's "all else equal": every pair of points that differ only in ``p``, at
    adjacent values (or the two of ``order``), the later minus the earlier, z = sign x
    difference / its SE. Counts: pairs with both values, agreeing (z >= 2), contradicting
    (z <= -2), and the share with the stated sign. ``where`` (a boolean per point) keeps
    the pairs whose earlier point has it."""
    others = [q for q in PARAMS if q != p]
    frame = ok.assign(_y=y.to_numpy(float), _s=se.to_numpy(float),
                      _w=(where.to_numpy(bool) if where is not None
                          else np.ones(len(ok), bool)))
    frame[p] = frame[p].astype(str)
    vals = list(order) if order else [str(v) for v in sorted(ok[p].unique())]
    piv = frame.pivot_table(index=others, columns=p, values=["_y", "_s", "_w"],
                            aggfunc="first", observed=True)
    zs, rel, at = [], [], []
    keys = piv.index.to_frame(index=False)
    for v1, v2 in zip(vals[:-1], vals[1:], strict=True):
        if any(v not in piv[c].columns for c in ("_y", "_s", "_w") for v in (v1, v2)):
            continue  # a value with no point at all (pivot_table drops it): no pair
        y1, y2 = piv["_y"][v1].to_numpy(float), piv["_y"][v2].to_numpy(float)
        s1, s2 = piv["_s"][v1].to_numpy(float), piv["_s"][v2].to_numpy(float)
        w = piv["_w"][v1].to_numpy(float) > 0
        d = sign * (y2 - y1)
        s = np.sqrt(s1**2 + s2**2)
        # a pair counts only with both values and both error bars (a point without an SE
        # cannot decide a pair)
        ok2 = np.isfinite(d) & w & np.isfinite(s) & (s > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = d / s
        zs.append(z[ok2])
        at.append(keys[ok2].assign(**{p: f"{v1}->{v2}"}))
        with np.errstate(divide="ignore", invalid="ignore"):
            rel.append((d / np.abs(y1))[ok2])
    z = np.concatenate(zs) if zs else np.array([])
    r = np.concatenate(rel) if rel else np.array([])
    n = int(z.size)
    return {"n": n, "agree": int((z >= 2).sum()), "contra": int((z <= -2).sum()),
            "neg": int((z < 0).sum()),
            "sign": float((z > 0).mean()) if n else math.nan,
            "median_rel": float(np.nanmedian(r[np.isfinite(r)])) if n else math.nan,
            "z": z, "at": pd.concat(at, ignore_index=True) if at else None}


def where_contra(t, top=3):
    """Where a statement's contradictions concentrate: the parameter values whose pairs
    contradict most often (share of that value's pairs), the largest first."""
    if t.get("at") is None or t["contra"] == 0:
        return ""
    bad = pd.Series(t["z"] <= -2)
    cells = []
    for q in t["at"].columns:
        share = bad.groupby(t["at"][q].astype(str).to_numpy()).mean()
        v = share.idxmax()
        cells.append((float(share.max()), f"{q} = {v} ({100 * share.max():.0f} %)"))
    cells.sort(key=lambda c: -c[0])
    return ", ".join(c[1] for c in cells[:top])


#: The chance of z <= -2 for one pair when there is no effect: a difference of two
#: 8-replica jackknife means is about Student's t with 14 degrees of freedom (3.3 %; the
#: normal's would be 2.3 %).
CHANCE = 0.0327
#: With an effect >= 0 in every pair, at most this share of the pairs with z < 0 reach
#: z <= -2 (t_14: P(t <= -2) / P(t < 0) = 0.065; more means real reversals).
REVERSAL = 0.065


def verdict(t):
    """One phrase for a trend over the grid, from its pairs.

    - **holds over the grid**: at least half the pairs agree (z >= 2), and those that go
      the other way are what chance gives when the effect is >= 0 everywhere: at most
      :data:`CHANCE` of all pairs at z <= -2, and at most :data:`REVERSAL` of the pairs
      with z < 0;
    - **holds, with real reversals**: at least half agree and at least 80 % of the pairs
      that decide, but more contradict than chance allows;
    - **split**: the pairs that decide agree more often than not, but fewer than 80 % (or
      fewer than half of all pairs agree, with reversals beyond chance);
    - **not resolved**: fewer than half the pairs agree, no reversal beyond chance;
    - **mostly reversed**: the pairs that decide mostly contradict.
    """
    if t["n"] == 0:
        return "no pairs"
    dec = t["agree"] + t["contra"]
    if dec == 0:
        return "not resolved"
    share = t["agree"] / dec
    neg = t.get("neg", t["contra"])
    chance = t["contra"] <= CHANCE * t["n"] and t["contra"] <= REVERSAL * max(neg, 1)
    if t["agree"] >= 0.5 * t["n"]:
        if chance:
            return "holds over the grid"
        return "holds, with real reversals" if share >= 0.8 else "split"
    if chance:
        return "not resolved"
    return "split" if share >= 0.5 else "mostly reversed"


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
    complete = n == GRID_POINTS
    if complete:  # every point: a mean over the grid has no sampling error
        args.bootstrap = 0
        cover = (f" **all {GRID_POINTS} points of the grid**: a mean over the grid has no"
                 " sampling error, its SE is the points' stochastic one,"
                 " sqrt(sum SE_i²) / n, from their jackknife SEs.")
    else:
        cover = (f" **{n} of the grid's {GRID_POINTS} points** ({100 * n / GRID_POINTS:.1f} %;"
                 " each shard a uniform random sample of the grid, so until all eight are"
                 " in, every mean below also carries a sampling error: the SE quoted is the"
                 " larger of the stochastic one and a bootstrap over points).")
    say(f"Made by `python benchmarks/atlas.py` from `results/herman2019`"
        f" ({len(files)} shard tables):" + cover + " Model version"
        f" {sorted(set(json.loads(p)['model_version'] for p in df['provenance']))[0]},"
        " ensembles of 8 replicas, **stochastic** (another seed or CPU moves the values"
        " within their error bars); machine and dates in"
        " `results/herman2019/provenance.json`.\n")
    say("Status: " + ", ".join(f"{s} {int(c)}" for s, c in counts.items() if c) + ".\n")
    head_at = len(lines)
    ok = df[df["status"].isin(["converged", "converged_noisy", "not_converged"])].copy()

    # --- where a compact zone forms
    ok["compact"] = (ok["compact_zone"].astype(str) != "none").astype(float)
    say("## Where a compact zone forms\n")
    lay = ok["compact_zone"].astype(str).value_counts()
    say("Layouts (`compact_zone`): " + ", ".join(f"{k} {v} ({100 * v / len(ok):.1f} %)"
                                                 for k, v in lay.items()) + ".\n")
    say("Share of points with a compact zone (± binomial SE) by each parameter:\n")
    say("| parameter | value: share |")
    say("|---|---|")
    for p in PARAMS:
        cells = []
        for v, g in ok.groupby(p, observed=True):
            s = g["compact"].mean()
            cells.append(f"{v}: {s:.3f} ± {math.sqrt(s * (1 - s) / len(g)):.3f}")
        say(f"| {p} | {'; '.join(cells)} |")
    say("")
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for ax, (a, b) in zip(axes, (("T", "a0"), ("C_sd", "eps"), ("d_f", "L_x")), strict=True):
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
    say("![Share of points with a compact zone over T x a0, C_sd x eps and d_f x L_x]"
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
    decomp = {}
    for name, (y, _, label) in resp.items():
        yy = np.log10(y.where(y > 0)) if name in ("W_c", "alpha_all") else y
        k, mains, full, pairs = decomposition(ok, yy)
        decomp[name] = (k, mains, full, pairs)
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


    # --- the paper's trend statements over the whole grid
    say("## The paper's statements of §4.2 and §5, over the whole grid\n")
    say("The paper reads its trends off slices (Figs. 2, 5, 6). Here each is tested on every"
        " pair of points of the grid that differ in that parameter alone (adjacent values;"
        " ep against ml for the dispersion relation): z is the pair's difference in the"
        " paper's direction over its SE (the points' jackknife SEs in quadrature). A pair"
        " *agrees* at z ≥ 2 and *contradicts* at z ≤ −2. With no effect, chance alone puts"
        " about 3.3 % of pairs at z ≤ −2 (a difference of two 8-replica jackknife means is"
        " about Student's t with 14 degrees of freedom), and with an effect ≥ 0 in every"
        " pair at most 6.5 % of the pairs with z < 0 reach z ≤ −2. A statement **holds over"
        " the grid** when at least half its pairs agree and its contradictions stay within"
        " both; *holds, with real reversals* when more contradict than that but 80 % of the"
        " deciding pairs agree; *split* below 80 %. Pairs without an SE on either point are"
        " left out. The rule takes the points' SEs at their word (against long reference"
        " runs their RMS z is 0.92-1.15: docs/convergence.md); an SE 15 % too small would"
        " raise the 6.5 % to about 10 %, far below the shares that make the reversals"
        " below real. Two statements are per point (edge"
        " against inner slope; the inner slope against eq. 24's) and count points.\n")
    ice = float(np.nanmedian(ok["ice_extent"]))
    has_zone = np.isfinite(ok["W_c"])
    ya, sa, _ = resp["a_end_rel"]
    trows = []

    def trow(claim, where_, measure, t):
        trows.append((claim, where_, measure, t))

    trow("higher ε, lower wave amplitude (Fig. 2)", "§4.2", "a_end/a0 along eps",
         paired(ok, ya, sa, "eps", -1))
    trow("the collisional zone narrows as ε grows (Figs. 2, 3a)", "§4.2",
         "W_c along eps, pairs where both have a zone",
         paired(ok, ok["W_c"], ok["W_c_stderr"], "eps", -1))
    e, i = ok["alpha_edge"], ok["alpha_inner"]
    z = (e - i) / np.sqrt(ok["alpha_edge_stderr"] ** 2 + ok["alpha_inner_stderr"] ** 2)
    z = z[np.isfinite(e) & np.isfinite(i) & has_zone].to_numpy(float)
    trow("attenuation steep near the edge, flatter downwave", "§4.2",
         "alpha_edge − alpha_inner per point with a zone",
         {"n": z.size, "agree": int((z >= 2).sum()), "contra": int((z <= -2).sum()),
          "neg": int((z < 0).sum()),
          "sign": float((z > 0).mean()), "median_rel": float(np.nanmedian(
              ((e - i) / i)[np.isfinite(e) & np.isfinite(i) & has_zone]))})
    ri, si, _ = resp["inner_c"]
    zz = np.minimum(ri - 0.8, 1.25 - ri) / si
    zz = zz[np.isfinite(ri)].to_numpy(float)
    trow("the compact zone attenuates like confined ice (eq. 25)", "§4.2, §5",
         "alpha_inner/alpha_c inside [0.8, 1.25], per point",
         {"n": zz.size, "agree": int((zz >= 2).sum()), "contra": int((zz <= -2).sum()),
          "neg": int((zz < 0).sum()),
          "sign": float((zz > 0).mean()),
          "median_rel": float(np.nanmedian(ri[np.isfinite(ri)]) - 1)})
    trow("ep attenuates less than ml, all else equal, always", "§4.2, §5",
         "a_end/a0, ep minus ml", paired(ok, ya, sa, "dispersion", 1, order=("ml", "ep")))
    trow("smaller floes attenuate more (Fig. 5)", "§4.2", "a_end/a0 along L_x",
         paired(ok, ya, sa, "L_x", 1))
    trow("small floes undergo more vigorous collisions", "§4.2",
         "collisions per pair per wave period along L_x",
         paired(ok, ok["collision_rate"], ok["collision_rate_stderr"], "L_x", -1))
    per_m = ok["collision_rate"] / ok["L_x"]
    trow("... and more collisions per distance travelled by the wave", "§4.2",
         "collisions per metre of ice per period (per pair / L_x) along L_x: the 1/L_x"
         " is most of it", paired(ok, per_m, ok["collision_rate_stderr"] / ok["L_x"],
                                  "L_x", -1))
    trow("smaller d_f, stronger attenuation near the edge (Fig. 6a)", "§4.2",
         "alpha_edge along d_f", paired(ok, ok["alpha_edge"], ok["alpha_edge_stderr"],
                                        "d_f", -1))
    trow("further downwave the d_f order reverses where the collisional zone is narrow"
         " (Fig. 6a, T 1.2 s)", "§4.2",
         "a_end/a0 along d_f, pairs whose smaller d_f has a zone",
         paired(ok, ya, sa, "d_f", -1, where=has_zone))
    trow("no reversal where the collisional zone spans the domain (Fig. 6a, T 1.8 s)",
         "§4.2", "a_end/a0 along d_f, pairs whose smaller d_f has no zone",
         paired(ok, ya, sa, "d_f", 1, where=~has_zone))
    trow("larger a0, stronger attenuation (Fig. 6b; rate a0 alpha_c)", "§4.2",
         "a_end/a0 along a0", paired(ok, ya, sa, "a0", -1))
    trow("shorter waves attenuate more (alpha(omega), eqs. 24, 27-28)", "§3, §5",
         "alpha_all along T", paired(ok, ok["alpha_all"], ok["alpha_all_stderr"], "T", -1))
    say("| the paper says | where | over the grid | n | agree | contradict | contradict"
        " among z < 0 | right sign | median change | verdict |")
    say("|---|---|---|---|---|---|---|---|---|---|")
    verdicts = []
    for claim, where_, measure, t in trows:
        v = verdict(t)
        verdicts.append((claim, v, t))
        say(f"| {claim} | {where_} | {measure} | {t['n']} | {t['agree']}"
            f" ({100 * t['agree'] / max(t['n'], 1):.1f} %) | {t['contra']}"
            f" ({100 * t['contra'] / max(t['n'], 1):.1f} %)"
            f" | {100 * t['contra'] / max(t.get('neg', 0), 1):.1f} % | {100 * t['sign']:.1f} %"
            f" | {100 * t['median_rel']:+.1f} % | {v} |")
    say("")
    say("Where the contradictions concentrate (the parameter values whose pairs contradict"
        " most often, as a share of that value's pairs), for each statement that does not"
        " hold over the grid:\n")
    for claim, v, t in verdicts:
        if t["n"] and verdict(t) != "holds over the grid" and t.get("at") is not None \
                and t["contra"]:
            say(f"- {claim}: {where_contra(t)}.")
    say("")
    say("Median change: the pair's relative difference in the paper's direction (for the"
        " per-point rows: alpha_edge/alpha_inner − 1, and the median alpha_inner/alpha_c − 1)."
        " The z of one pair is stochastic (8 replicas each); the counts over thousands of"
        " pairs are not, to their binomial error.\n")
    # W_c appearing or vanishing with eps: the zone's existence is part of the statement
    piv = ok.assign(_z=has_zone.astype(float)).pivot_table(
        index=[q for q in PARAMS if q != "eps"], columns="eps", values="_z",
        aggfunc="first", observed=True)
    cols = sorted(piv.columns)
    appear = sum(int(((piv[a] == 0) & (piv[b] == 1)).sum()) for a, b in zip(cols, cols[1:]))
    vanish = sum(int(((piv[a] == 1) & (piv[b] == 0)).sum()) for a, b in zip(cols, cols[1:]))
    say(f"Raising ε by one step makes a compact zone appear in {appear} pairs and vanish in"
        f" {vanish}: where it appears, the collisional zone has shrunk from the whole sheet"
        f" ({ice:.1f} m) to W_c, the same direction as the paper's.\n")
    fig2 = ok[(ok["L_x"] == 0.5) & (ok["d_f"] == 0.005)]
    share_fig2 = fig2["compact"].mean()
    say("Where the grid says other than the paper: the paper writes that \"in most cases\""
        " a(x) has the two zones; over the grid a compact zone forms at"
        f" {100 * ok['compact'].mean():.1f} % of points, and at"
        f" {100 * share_fig2:.1f} % ± {100 * math.sqrt(share_fig2 * (1 - share_fig2) / len(fig2)):.1f} %"
        " of the L_x 0.5 m, d_f 5 mm corner that Figs. 2-4 show. Elsewhere the whole"
        " sheet collides and a(x) has a single regime.\n")

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
        " the CPU of all ranks is in `results/herman2019/provenance.json`).\n")
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
    disp_means = {}
    for disp in ("ep", "ml", "ow"):
        g = ok[ok["dispersion"] == disp]
        s = g["compact"].mean()
        ya, sa, _ = resp["a_end_rel"]
        yw, sw, _ = resp["W_c"]
        ma = marginal(g.assign(_all=0), ya.loc[g.index], sa.loc[g.index], "_all", rng,
                      args.bootstrap)[0]
        mw = marginal(g.assign(_all=0), yw.loc[g.index], sw.loc[g.index], "_all", rng,
                      args.bootstrap)[0]
        disp_means[disp] = fmt(ma[2], ma[3])
        say(f"| {disp} | {len(g)} | {s:.3f} ± {math.sqrt(s * (1 - s) / len(g)):.3f} | "
            f"{fmt(ma[2], ma[3])} | {fmt(mw[2], mw[3])} |")
    say("")
    # --- headlines, at the top
    spread = {q: ok.groupby(q, observed=True)["compact"].mean() for q in PARAMS}
    top = max(spread, key=lambda q: spread[q].max() - spread[q].min())
    d_share = spread[top]
    heads = ["## Headlines\n",
             f"- A compact zone forms at {100 * ok['compact'].mean():.1f} % of the points"
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
    (args.out / "atlas.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
