"""The atlas's statistics: marginal means with their SE, the variance decomposition, and
the paired test of a trend "all else equal" with its verdict (:mod:`herman2019.atlas`)."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from sweep.store.schema import column

__all__ = ["PARAMS", "GRID_POINTS", "CHANCE", "REVERSAL", "responses", "marginal", "design",
           "r2", "decomposition", "paired", "where_contra", "verdict", "fmt", "axis_label"]

#: The grid's seven parameters (configs/herman2019.toml's [sweep]).
PARAMS = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
#: The points of the paper's whole grid.
GRID_POINTS = 24192


def axis_label(param: str) -> str:
    """A parameter's axis label with its unit as the store declares it ("T [s]"; a
    dimensionless one "[1]"; the dispersion relation has none)."""
    units = column(param).units
    return f"{param} [{units}]" if units else param


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


def paired(ok, y, se, p, sign, *, order=None, where=None, ref=None):
    """The paper's "all else equal": every pair of points that differ only in ``p``, at
    adjacent values (or the two of ``order``), the later minus the earlier, z = sign x
    difference / its SE. Counts: pairs with both values, agreeing (z >= 2), contradicting
    (z <= -2), and the share with the stated sign. ``where`` (a boolean per point) keeps
    the pairs whose earlier point has it. ``ref`` = (value, SE) of another quantity: the
    pair's direction is then its difference's sign (``sign`` x that), and only pairs
    whose ``ref`` difference is resolved (|z| >= 2) count ("the order of ref holds in y")."""
    others = [q for q in PARAMS if q != p]
    r_y, r_s = ref if ref is not None else (y * 0.0, se * 0.0)   # unused without ref
    frame = ok.assign(_y=y.to_numpy(float), _s=se.to_numpy(float),
                      _ry=r_y.to_numpy(float), _rs=r_s.to_numpy(float),
                      _w=(where.to_numpy(bool) if where is not None
                          else np.ones(len(ok), bool)))
    frame[p] = frame[p].astype(str)
    vals = list(order) if order else [str(v) for v in sorted(ok[p].unique())]
    piv = frame.pivot_table(index=others, columns=p, values=["_y", "_s", "_w", "_ry", "_rs"],
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
        if ref is not None:
            rd = piv["_ry"][v2].to_numpy(float) - piv["_ry"][v1].to_numpy(float)
            rs = np.sqrt(piv["_rs"][v1].to_numpy(float) ** 2
                         + piv["_rs"][v2].to_numpy(float) ** 2)
            with np.errstate(divide="ignore", invalid="ignore"):
                resolved = np.abs(rd / rs) >= 2
            d = np.sign(rd) * d
            w = w & resolved
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
