"""The atlas's readings near the ice edge and of the collisional zone: a(x)/a0 at fixed
distances from the edge (from the shipped profiles), the two rules for W_c side by side,
and W_c over every point (where no compact zone forms: how far floes collide)."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from herman2019.atlas.page import Page
from herman2019.atlas.stats import PARAMS, fmt, marginal

__all__ = ["EDGE_X", "at_distances", "collision_extent", "zone_rules", "near_edge"]

#: The distances from the ice edge [m] at which "near the edge" is read from a(x)/a0.
EDGE_X = (2.0, 5.0, 10.0)


def at_distances(x: np.ndarray, a: np.ndarray, se: np.ndarray, n: np.ndarray,
                 where: tuple[float, ...] = EDGE_X) -> tuple[np.ndarray, np.ndarray]:
    """a/a0 and its SE at each distance of ``where`` per point, from the profiles (points x
    floes: floe centres ``x``, a/a0 ``a``, its SE ``se``; the first ``n`` floes valid), by
    linear interpolation between the two floes whose centres enclose the distance (the SE
    interpolated alike: neighbouring floes' errors are strongly correlated, so this is the
    larger, fully correlated, bound); NaN outside the floes' centres."""
    out = np.full((len(x), len(where)), np.nan)
    out_se = np.full((len(x), len(where)), np.nan)
    for i in range(len(x)):
        k = int(n[i])
        xi, ai, si = x[i, :k].astype(float), a[i, :k].astype(float), se[i, :k].astype(float)
        for j, d in enumerate(where):
            if k < 2 or not xi[0] <= d <= xi[-1]:
                continue
            r = int(np.searchsorted(xi, d))
            r = min(max(r, 1), k - 1)
            w = (d - xi[r - 1]) / (xi[r] - xi[r - 1])
            out[i, j] = (1 - w) * ai[r - 1] + w * ai[r]
            out_se[i, j] = (1 - w) * si[r - 1] + w * si[r]
    return out, out_se


def _rows(page: Page, df: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(rows of ``df`` that have profiles, their index in ``page.profiles``)."""
    prof = page.profiles
    pos = pd.Series(np.arange(prof.sizes["point"]), index=prof["hash"].values.astype(str))
    idx = pos.reindex(df["hash"].astype(str)).to_numpy()
    have = np.isfinite(idx)
    return have, idx[have].astype(int)


def _attach(page: Page) -> None:
    """Put a/a0 at EDGE_X (and SEs) on ``page.ok`` as ``a_rel_{d}m`` columns."""
    prof, ok = page.profiles, page.ok
    if prof is None:
        return
    have, rows = _rows(page, ok)
    vals, ses = at_distances(prof["x"].values[rows], prof["a_rel"].values[rows],
                             prof["a_rel_stderr"].values[rows], prof["n_floes"].values[rows])
    fac = page.se_factor.get("a_end")
    fac = fac.to_numpy(float)[have] if fac is not None else 1.0
    for j, d in enumerate(EDGE_X):
        col = f"a_rel_{d:g}m"
        v, s = np.full(len(ok), np.nan), np.full(len(ok), np.nan)
        v[have], s[have] = vals[:, j], ses[:, j] * fac
        ok[col], ok[col + "_stderr"] = v, s


def collision_extent(page: Page, df: pd.DataFrame) -> pd.Series:
    """Per point without a compact zone, how far from the edge floes collide: the far end
    (centre + L_x / 2) of the farthest floe in contact with its downwave neighbour at any
    time (``contact_fraction`` > 0 in the profiles), 0 where none is; NaN without
    profiles."""
    out = pd.Series(np.nan, index=df.index)
    if page.profiles is None:
        return out
    prof = page.profiles
    have, rows = _rows(page, df)
    x, cf = prof["x"].values[rows], prof["contact_fraction"].values[rows]
    touch = np.nan_to_num(cf, nan=0.0) > 0
    far = np.where(touch, x, -np.inf).max(axis=1) + 0.5 * df["L_x"].to_numpy(float)[have]
    out.iloc[np.flatnonzero(have)] = np.where(np.isfinite(far), far, 0.0)
    return out


def zone_rules(page: Page) -> None:
    """The two rules for the collisional zone side by side, and W_c over every point."""
    say, sh, ok = page.say, page.shares, page.ok
    say("## The collisional zone under both rules\n")
    lay = sh["compact_zone"].astype(str) != "none"
    gap = np.isfinite(sh["W_c_gap"])
    both = lay & gap
    diff = (sh.loc[both, "W_c"] - sh.loc[both, "W_c_gap"]).to_numpy(float)
    say("Two rules place the boundary W_c between the collisional zone and the compact ice"
        " (docs/model.md): the *layout rule* (`W_c`: where a compact zone of at least"
        " `compact_min_pairs` touching pairs over `compact_min_length` begins,"
        " `compact_zone` not `none`) and the *gap rule* (`W_c_gap`: where the time-mean gap"
        " between floes first stays below `gap_threshold`). Over the"
        f" {len(sh)} points with results:\n")
    say("| rule | points with a zone | share | W_c median [m] | W_c 10-90 % [m] |")
    say("|---|---|---|---|---|")
    for name, m, col in (("layout (`W_c`)", lay, "W_c"), ("gap (`W_c_gap`)", gap, "W_c_gap")):
        w = sh.loc[m, col].to_numpy(float)
        w = w[np.isfinite(w)]
        s = m.mean()
        err = 100 * math.sqrt(s * (1 - s) / len(sh))
        spread = (f"{np.median(w):.2f} | {np.quantile(w, 0.1):.2f}-{np.quantile(w, 0.9):.2f}"
                  if w.size else "– | –")
        say(f"| {name} | {int(m.sum())} | {100 * s:.1f} % ± {err:.1f} % | {spread} |")
    say("")
    if diff.size:
        med_se = float(np.nanmedian(sh.loc[both, "W_c_stderr"]))
        med_abs = float(np.median(np.abs(diff)))
        more = ("more than" if med_abs > med_se else "less than")
        say(f"Both rules find a zone at {int(both.sum())} points, only the layout rule at"
            f" {int((lay & ~gap).sum())}, only the gap rule at {int((gap & ~lay).sum())};"
            f" where both do, W_c − W_c_gap has median {np.median(diff):+.2f} m and median"
            f" |W_c − W_c_gap| {med_abs:.2f} m, {more} the median stated SE(W_c),"
            f" {med_se:.2f} m" + (": the rule moves W_c by more than its error bar, so a W_c"
                                  " is quoted with its rule.\n" if med_abs > med_se
                                  else ".\n"))
    # W_c over every point: where no compact zone forms, how far floes collide
    ext = collision_extent(page, ok)
    nz = ~(ok["compact_zone"].astype(str) != "none")
    if ext.notna().any():
        w_all = ok["W_c"].where(~nz, ext)
        w_se = ok["W_c_stderr"].where(~nz, 0.0)
        ice = ok["ice_extent"]
        reach = (ext[nz] >= ice[nz] - ok.loc[nz, "L_x"] - 0.05).mean()
        none = int((ext[nz] == 0).sum())
        say("**The collisional zone's width over every point.** Where no compact zone"
            " forms, W_c is not defined; here it is taken as how far from the edge floes"
            " collide at all: the far end of the farthest floe that touches its downwave"
            " neighbour at any time (`contact_fraction` > 0 in the profiles). Then it is"
            " defined at every converged point and its trends are not conditioned on a zone"
            f" forming. Of the {int(nz.sum())} converged points without a compact zone,"
            f" collisions reach the last floe at {100 * reach:.1f} % (the whole sheet"
            f" collides) and at {none} no floe touches another. Mean over every other"
            " parameter at each value (the layout rule's W_c with its SE where a zone"
            " forms, the collisions' extent without an SE elsewhere):\n")
        say("| parameter | value: mean ± SE (n) |")
        say("|---|---|")
        for p in PARAMS:
            m1 = marginal(ok, w_all, w_se, p, page.rng, page.bootstrap)
            say(f"| {p} | " + "; ".join(f"{v}: {fmt(mu, s)} ({k})" for v, k, mu, s in m1)
                + " |")
        say("")
        page.ok["W_c_all"], page.ok["W_c_all_stderr"] = w_all, w_se
    else:
        say("Without the profiles beside the table, how far collisions reach where no"
            " compact zone forms is not known, and W_c is read only where a zone forms.\n")
    page.zone_rules = {"layout": float(lay.mean()), "gap": float(gap.mean()),
                       "both": int(both.sum())}


def near_edge(page: Page) -> None:
    """a(x)/a0 at fixed distances from the edge, by each parameter (from the profiles)."""
    say, ok = page.say, page.ok
    say("## Near the edge: a(x)/a0 at 2, 5 and 10 m\n")
    if page.profiles is None:
        say("The table has no profiles beside it (`profiles/*.nc`): a(x) near the edge"
            " cannot be read, and the statements about it below are left out.\n")
        return
    _attach(page)
    n_have = int(np.isfinite(ok[f"a_rel_{EDGE_X[0]:g}m"]).sum())
    say("\"Near the edge\" read from the profiles themselves: a/a0 at fixed distances"
        " from the ice edge, interpolated linearly between the two floes whose time-mean"
        " centres enclose the distance (its SE alike: the bound for fully correlated"
        f" neighbours), at {n_have} points. alpha_edge, a slope fitted over the whole"
        " collisional zone, is not used for it: that zone's width changes with the"
        " parameters (the marginal table of W_c above). Mean over every other parameter at"
        " each value:\n")
    for d in EDGE_X:
        col = f"a_rel_{d:g}m"
        say(f"**a/a0 at {d:g} m**\n")
        say("| parameter | value: mean ± SE (n) |")
        say("|---|---|")
        for p in PARAMS:
            m = marginal(ok, ok[col], ok[col + "_stderr"], p, page.rng, page.bootstrap)
            say(f"| {p} | " + "; ".join(f"{v}: {fmt(mu, s)} ({k})" for v, k, mu, s in m)
                + " |")
        say("")
