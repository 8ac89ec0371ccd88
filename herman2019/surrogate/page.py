"""docs/surrogate.md: the surrogate's API, how it is built, and its error on the
validation set, made by ``herman2019 surrogate --validate --docs docs`` from the shipped
files (a test holds the page to the command)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from herman2019.surrogate.grid import AXES, DISPERSIONS
from herman2019.surrogate.model import QUANTITIES, Surrogate
from herman2019.surrogate.validate import (
    ROLES,
    brier,
    by_region,
    error_table,
    reliability,
    set_names,
    set_spec,
)

__all__ = ["make_page", "COMMAND", "TARGET_RMS", "TARGET_MEDIAN"]

COMMAND = "herman2019 surrogate --validate --docs docs"
#: Issue 48's targets: RMS z per quantity within this, alpha_all's median relative error
#: at most this.
TARGET_RMS, TARGET_MEDIAN = (0.8, 1.3), 0.05
LABEL = {"alpha_all": "alpha_all [1/m]", "alpha_edge": "alpha_edge [1/m]",
         "a_end_rel": "a_end/a0", "W_c": "W_c [m]"}


_KIND = {"random": "points uniform in the box", "axes": "nodes per axis, that axis alone moved"}


def _fmt(v, nd=2) -> str:
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.{nd}f}"


def _example(sur: Surrogate) -> str:
    p = sur.predict("ml", L_x=1.0, T=1.3, a0=0.02, C_sd=0.05, eps=0.5, d_f=0.01)
    r = p.iloc[0]
    return ", ".join(f"{q} {r[q]:.4g} ± {r[q + '_se']:.2g}" for q in QUANTITIES) \
        + f", p_zone {r['p_zone']:.3f}"


def _machines(provenance: dict | None) -> str:
    """Which CPU ran each off-grid set of ``provenance`` (the surrogate's sets), as a
    sentence."""
    if not provenance:
        return ""
    by: dict[str, list[str]] = {}
    for name, entry in sorted(provenance.items()):
        by.setdefault(str(entry.get("machine")), []).append(f"`{name}`")
    return " The off-grid sets ran on " + "; ".join(
        f"{m} ({', '.join(n)})" for m, n in by.items()) + " (the nodes' machines: each" \
        " table's README)."


def _shape(sur: Surrogate) -> str:
    """The grid's shape, e.g. ``8 x 7 x 4 x 6 x 4 x 4 x 3 = 64,512 points``."""
    n = [len(sur.levels[a]) for a in AXES] + [len(sur.fields)]
    return " x ".join(map(str, n)) + f" = {int(np.prod(n)):,} points"


def _grid_words(sur: Surrogate) -> str:
    """Where the grid's nodes come from, and its floe lengths."""
    src = str(sur.meta.get("source", ""))
    lx = ", ".join(f"{v:g}" for v in sur.levels["L_x"])
    if " + " not in src:
        return f"`{src}`, floe lengths {lx} m"
    return ("the paper's grid and its extensions in floe length, `"
            + "`, `".join(src.split(" + ")) + f"`, floe lengths {lx} m")


def _tail(cmp: pd.DataFrame, q: str, rms: float) -> str:
    """A bullet for a quantity whose RMS z on the uniform set misses the target: its
    largest |z|, where, and the RMS z without that one point."""
    z = cmp[q + "_z"].to_numpy(float)
    ok = np.flatnonzero(np.isfinite(z))
    i = ok[np.argmax(np.abs(z[ok]))]
    rest = np.sqrt(np.mean(np.delete(z, i)[np.isfinite(np.delete(z, i))] ** 2))
    where = ", ".join(f"{a} {cmp[a].iloc[i]:.4g}" for a in AXES) \
        + f", {cmp['dispersion'].iloc[i]}"
    text = (f"- An error bar that holds for {q} at every point: on the uniform set its RMS"
            f" z is {rms:.2f}, outside the target; its largest |z|, {abs(z[i]):.1f}, is one"
            f" point ({where}; p_zone {cmp['p_zone'].iloc[i]:.2f}), without which RMS z is"
            f" {rest:.2f}.")
    return text


def _table(err: pd.DataFrame) -> list[str]:
    lines = ["| quantity | points | RMS z [95 % CI] | median \\|rel. error\\| | 90th pct |"
             " median stated rel. SE | median \\|z\\| | \\|z\\| > 2 | \\|z\\| > 4 |"
             " RMS z target |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in err.itertuples():
        ok = TARGET_RMS[0] <= r.rms_z <= TARGET_RMS[1]
        lines.append(f"| {r.quantity} | {r.points} | {_fmt(r.rms_z, 3)} [{_fmt(r.rms_z_lo)},"
                     f" {_fmt(r.rms_z_hi)}] | {100 * r.median_rel_error:.1f} % |"
                     f" {100 * r.p90_rel_error:.1f} % | {100 * r.median_rel_se:.1f} % |"
                     f" {_fmt(r.median_abs_z)} | {100 * r.beyond_2:.1f} % | {r.beyond_4} |"
                     f" {'met' if ok else 'NOT met'} |")
    return lines


def make_page(sur: Surrogate, cmp: pd.DataFrame, docs: Path | None, source: str,
              provenance: dict | None = None) -> str:
    """The page's text; with ``docs``, written to DOCS/surrogate.md with its figure in
    DOCS/surrogate/validation.png. ``provenance``: the sets' (who ran them)."""
    rnd = cmp["group"].astype(str).to_numpy() == "offgrid"
    err = error_table(cmp[rnd])
    meta = sur.meta
    base = float(np.nanmean(np.concatenate([f[:, sur.column("zone")]
                                            for f in sur.fields.values()])))
    br = brier(cmp[rnd], base)
    rel = reliability(cmp[rnd])
    cal = meta.get("calibration", {})
    lines = [
        "# The surrogate: the released grid as a function",
        "",
        f"Made by `{COMMAND}` from `{source}` (`surrogate.npz`, built by `herman2019"
        f" surrogate --build --jobs 2` from `{meta.get('source')}`: model version"
        f" {', '.join(meta.get('model_version', []))}, {meta.get('points'):,} nodes, their"
        f" {meta.get('standard_errors')} standard errors; commit"
        f" {str(meta.get('commit'))[:12] or 'unknown'}"
        f"{', uncommitted changes' if meta.get('git_dirty') else ', a clean tree'})."
        " **Stochastic**: the nodes and the"
        " validation points are 8-replica ensembles; another seed or CPU gives other"
        " values within their error bars."
        + _machines(provenance),
        "",
        f"The grid ({_shape(sur)}: {_grid_words(sur)}) is a full tensor product, so"
        " it can be read as a function of six continuous parameters per dispersion"
        " relation. The surrogate gives, anywhere inside the grid's box, `alpha_all`,"
        " `alpha_edge` (1/m), `a_end_rel` (a/a0 at the far end), `p_zone` (the"
        " probability that a compact zone forms) and `W_c` (its width where one forms),"
        " each with a standard error: at the nodes the grid's own, between them with an"
        " interpolation error fitted on off-grid runs and checked below on others it was"
        " not fitted on (where it holds and where it does not). Outside the box it"
        " refuses.",
        "",
        "## Using it",
        "",
        "```python",
        "from herman2019.surrogate import surrogate",
        "df = surrogate(L_x=1.0, T=1.3, a0=0.02, C_sd=0.05, eps=0.5, d_f=0.01, dispersion=\"ml\")",
        "# arrays broadcast; one row per point: the parameters, each quantity and its _se",
        "import numpy as np",
        "df = surrogate(L_x=1.0, T=np.linspace(1.1, 2.0, 50), a0=0.02, C_sd=0.05, eps=0.5,",
        "               d_f=0.01, dispersion=\"ep\")",
        "df.set_index(\"T\").to_xarray()          # an xarray Dataset over T",
        "```",
        "",
        "    herman2019 surrogate --L_x 1.0 --T 1.3 --a0 0.02 --C_sd 0.05 --eps 0.5"
        " --d_f 0.01 --dispersion ml",
        "    herman2019 surrogate --csv points.csv --out predictions.csv",
        "",
        f"At that point: {_example(sur)}. `detail=True` (`--detail`) adds each SE's two"
        " parts, relative: `_se_noise` (the nodes' stochastic errors carried through) and"
        " `_se_interp` (the interpolation error). A point outside the box raises"
        " `herman2019.surrogate.OutsideBox` (a `ValueError`; the command exits 2) naming"
        " the parameter and the box's range. The box: "
        + "; ".join(f"{a} {sur.levels[a][0]:g}-{sur.levels[a][-1]:g}" for a in AXES)
        + f"; dispersion {', '.join(DISPERSIONS)}. Its speed: `python"
        " benchmarks/bench_surrogate.py`.",
        "",
        "## How it is built",
        "",
        "- **Values**: multilinear interpolation between the grid's nodes, in log(value),"
        " with L_x, a0, C_sd and d_f on log axes (T and eps linear); quadratic along "
        + "; ".join(f"{', '.join(ax)} for {q}" for q in QUANTITIES
                    if (ax := sur.quadratic_axes(q)))
        + " (with three levels the quadratic through all three, with more the mean of the"
        " quadratics through the cell's two nodes and each neighbour; the axes chosen by"
        " their measured error on the calibration set, `python"
        " benchmarks/surrogate_methods.py --quadratic 3`, against scipy's tensor-grid"
        " interpolators by `python benchmarks/surrogate_methods.py`); at a node it"
        " returns the node. `W_c` is interpolated over the corners with a zone only (NaN"
        " where no corner has one). `p_zone` is the interpolant of the nodes' 0/1 outcome,"
        " recalibrated where it is strictly between 0 and 1 by p' = 1 / (1 + exp(-(a + b"
        " logit p))) fitted on the calibration sets (a, b = "
        + ", ".join(f"{v:.2f}" for v in meta.get("p_zone", [np.nan, np.nan])) + ").",
        "- **Noise**: each node's calibrated standard error (docs/convergence.md,"
        " \"Calibrated standard errors\") carried through the weights,"
        " sqrt(sum w_i^2 se_i^2).",
        "- **Interpolation error**: per axis, a term that vanishes at the nodes, the"
        " curvature of log(value) along the axis (from the leave-one-out residual at each"
        " interior node, its noise taken out) times (t(1-t) h^2)^2 inside a cell of width"
        " h, and a flat one, (4t(1-t))^2 (1 mid-cell)"
        + (("; each of " + " and ".join(sur.interval_axes()) + "'s intervals apart")
           if sur.interval_axes() else "")
        + "; and `missing`, (1 - w)^2 with w the weight of the cell's"
        " corners the value is read from (a corner without a value weighs nothing: W_c"
        " at the margin of the compact zones' region, a node whose ensemble gave no SE),"
        " which is 0 where every corner has one. Each term has its own scale per"
        " quantity, fitted by likelihood (the better of two starts, the flat terms at"
        " 100 % and at 1 %) on the *calibration sets* "
        f"({cal.get('points', '?')} off-grid points run for the purpose: "
        + ", ".join(f"{k}: {v[1]} {_KIND[v[0]]}, draw seed {v[2]}"
                    for k, v in cal.get("sets", {}).items())
        + "). The terms' variances v combine as (sum v^(p/2))^(2/p), p fitted too (2 adds"
        " them, a large p takes the largest); then one common factor so that the two"
        " kinds of calibration set weigh the same in a mean z^2 of 1. The scales (the"
        " curvature terms' are factors on the curvature's estimate; the `:flat` terms' are"
        " the relative error mid-cell along that axis) and p; at a bound of the fit: "
        + (", ".join(f"`{b}`" for b in meta.get("at_bound", [])) or "none")
        + " (a flat scale at its lower bound is none; p at 64 is the largest):",
        "",
        "| term | " + " | ".join(QUANTITIES) + " |",
        "|---|" + "---|" * len(QUANTITIES),
        *[f"| `{n}` | " + " | ".join(f"{sur.scale.get(f'{q}:{n}', np.nan):.2f}"
                                     for q in QUANTITIES) + " |"
          for n in sur.term_names()],
        "| p | " + " | ".join(f"{sur.combine_power(q):.1f}" for q in QUANTITIES) + " |",
        "",
        "- **The points off the grid**: uniform in the box in each axis's coordinate (log"
        " for L_x, a0, C_sd, d_f), or one axis at values between its levels with the"
        " others at random grid nodes; T on the model's 4 ms lattice, L_x on its 1 cm one;"
        " the dispersion relation at random; each run at the released defaults and seed 0"
        " as the grid's points were (`herman2019.surrogate.validate`; who ran them:"
        " `results/surrogate/provenance.json`).",
        "",
        "## Its error on the validation sets (never fitted on)",
        "",
        "The validation sets, "
        + ", ".join(f"`{n}`" for n in set_names(sur.levels, "validation"))
        + ", were drawn after the error model's last change and looked at by this check"
        " alone. "
        + ("The sets first drawn to validate it, "
           + ", ".join(f"`{n}`" for n in set_names(sur.levels, "calibration")
                       if not n.startswith(ROLES["calibration"][0]))
           + ", were looked at point by point (their worst residuals showed the `missing`"
           " term and the flat terms' fit stopping at its bound), so they are calibration"
           " sets now."
           if len(ROLES["calibration"]) > 1 else ""),
        "",
        "z = (log q_surrogate - log q_model) / sqrt(se_surrogate^2 + se_model^2), in log"
        " (so relative), with the model point's calibrated SE; W_c where the model point"
        " has a compact zone and the surrogate's cell one at a corner. Target (issue 48):"
        f" RMS z in [{TARGET_RMS[0]}, {TARGET_RMS[1]}] for each quantity, median relative"
        f" error of alpha_all at most {TARGET_MEDIAN:.0%}. For a normal z, median |z| is"
        " 0.67 and 4.6 % lie beyond |z| 2.",
        "",
        f"**Uniform in the box** ({int(rnd.sum())} points):",
        "",
        *_table(err),
        "",
        f"**Each axis alone** ({int((~rnd).sum())} points:"
        f" {set_spec(set_names(sur.levels, 'validation')[1])[1]}"
        " grid nodes of the other five axes per axis, the axis at values between its"
        " levels; the surrogate interpolates along that axis only):",
        "",
        *_table(error_table(cmp[~rnd])),
        "",
        "Per axis, RMS z (\\* outside the target) and alpha_all's median relative error:",
        "",
        "| axis | points | alpha_all | alpha_edge | a_end_rel | W_c (points) |"
        " alpha_all median \\|rel. error\\| |",
        "|---|---|---|---|---|---|---|",
    ]
    along = {}
    for a in AXES:
        m = cmp["group"].astype(str).to_numpy() == f"axis:{a}"
        e = error_table(cmp[m]).set_index("quantity")
        along[a] = float(e.loc["alpha_all", "median_rel_error"])

        def cell(q, e=e):
            v = e.loc[q, "rms_z"]
            star = "" if TARGET_RMS[0] <= v <= TARGET_RMS[1] else "\\*"
            return f"{_fmt(v)}{star}"
        lines.append(f"| {a} | {int(m.sum())} | {cell('alpha_all')} | {cell('alpha_edge')} |"
                     f" {cell('a_end_rel')} | {cell('W_c')} ({e.loc['W_c', 'points']}) |"
                     f" {100 * e.loc['alpha_all', 'median_rel_error']:.1f} % |")
    cmp = cmp[rnd]
    med = float(err.loc[err["quantity"] == "alpha_all", "median_rel_error"].iloc[0])
    lines += [
        "",
        f"alpha_all's median relative error: {100 * med:.1f} %"
        f" ({'met' if med <= TARGET_MEDIAN else 'NOT met'}: target"
        f" {100 * TARGET_MEDIAN:.0f} %).",
        "",
        "**Where in the box it is worst** (alpha_all; each axis's range cut in three equal"
        " parts of its coordinate):",
        "",
        "| region | points | RMS z | median \\|rel. error\\| |",
        "|---|---|---|---|",
    ]
    reg = by_region(cmp, "alpha_all")
    for r in reg.itertuples():
        lines.append(f"| {r.region} | {r.points} | {_fmt(r.rms_z)} |"
                     f" {100 * r.median_rel_error:.1f} % |")
    worst = reg.loc[reg["median_rel_error"].idxmax()]
    lines += [
        "",
        f"Worst: {worst['region']} (median {100 * worst['median_rel_error']:.1f} %).",
        "",
        "**The compact zone's probability** against the validation points' outcomes"
        f" (Brier score {br['brier']:.3f}; a constant, the grid's share {base:.3f}:"
        f" {br['brier_constant']:.3f}; skill {br['skill']:.2f}):",
        "",
        "| p_zone | points | mean p_zone | observed share |",
        "|---|---|---|---|",
    ]
    for r in rel.itertuples():
        lines.append(f"| {r.p_zone} | {r.points} | {_fmt(r.mean_p, 3)} |"
                     + (f" {r.observed:.3f} ± {r.observed_se:.3f} |" if r.points else " – |"))
    lines += [
        "",
        "![The surrogate against the model at the validation points](surrogate/validation.png)",
        "",
        "*The surrogate against the model at the validation points (stochastic; error bars"
        " ±1 SE, the surrogate's horizontal, the model's vertical), and p_zone's"
        " reliability. Made by the command above.*",
        "",
        "## What it is not",
        "",
        "- A statement about the paper's model between the nodes beyond what the grid's"
        " nodes and its validation points bear out: the interpolation error is fitted on"
        " off-grid points, so its error bars are checked in the bulk and along each axis,"
        " not at every corner of the box (the tables above show where they hold less"
        " well, and the errors are heavier-tailed than normal: more points beyond |z| 4"
        " than a normal z would give).",
        *([f"- As fine in L_x as in the other axes: the grid has"
           f" {len(sur.levels['L_x'])} floe lengths, and along L_x alone the surrogate's"
           f" median error in alpha_all is {100 * along['L_x']:.1f} %, against at most"
           f" {100 * other:.1f} % along any other axis (the table above)."]
          if along["L_x"] > (other := max(v for a, v in along.items() if a != "L_x"))
          else []),
        *[_tail(cmp, r.quantity, r.rms_z) for r in err.itertuples()
          if not TARGET_RMS[0] <= r.rms_z <= TARGET_RMS[1]],
        "- A model of other defaults: every node and every off-grid point runs at the"
        " released defaults (L_sheet 42 m, 8 replicas...).",
    ]
    text = "\n".join(lines)
    if docs is not None:
        docs = Path(docs)
        (docs / "surrogate").mkdir(parents=True, exist_ok=True)
        _figure(cmp, docs / "surrogate" / "validation.png")
        (docs / "surrogate.md").write_text(text + "\n")
    return text


def _figure(cmp: pd.DataFrame, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 5, figsize=(19, 3.9))
    for ax, q in zip(axes, QUANTITIES, strict=False):
        z = cmp[q + "_z"].to_numpy(float)
        m = np.isfinite(z)
        x, y = cmp[q + "_sur"].to_numpy(float)[m], cmp[q].to_numpy(float)[m]
        ax.errorbar(x, y, xerr=cmp[q + "_sur_se"].to_numpy(float)[m],
                    yerr=cmp[q + "_se"].to_numpy(float)[m], fmt="o", ms=3, lw=0.6,
                    alpha=0.7)
        lo, hi = np.nanmin([x.min(), y.min()]), np.nanmax([x.max(), y.max()])
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8)
        if q.startswith("alpha"):
            ax.set_xscale("log")
            ax.set_yscale("log")
        ax.set_xlabel(f"surrogate: {LABEL[q]}")
        ax.set_ylabel(f"model: {LABEL[q]}")
        ax.set_title(f"{q} ({m.sum()} points)")
    ax = axes[-1]
    rel = reliability(cmp)
    ok = rel["points"] > 0
    ax.errorbar(rel["mean_p"][ok], rel["observed"][ok], yerr=rel["observed_se"][ok], fmt="o")
    ax.plot([0, 1], [0, 1], "k-", lw=0.8)
    ax.set_xlabel("p_zone (surrogate)")
    ax.set_ylabel("share with a compact zone (model)")
    ax.set_title("p_zone reliability")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
