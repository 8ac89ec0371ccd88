"""The points of the paper campaigns and their estimates, shared by the claims' modules.

A point is a row of a campaign's table (:func:`sweep.load`), found by its swept values
(:func:`point`); its quantities become :class:`~herman2019.estimates.Estimate` s with the
standard error the store gives (the ensemble columns, else the profile's ``a_stderr``),
else a stated floor (:data:`FLOORS`). :class:`Check` is one row of the table.
"""
from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from herman2019.estimates import INCONCLUSIVE, Estimate, current_hook, hooked

__all__ = ["FLOORS", "X_NEAR", "Check", "Profile", "point", "col", "label_of",
           "a_end", "a_near", "w_c", "inner_over_c", "force_decades", "make_check",
           "sorted_values", "M_OW", "INNER_OVER_C", "FORCE_DECADES", "M_CLOSE",
           "NO_EFFECT", "A_RESOLUTION", "range_bounds", "Tables", "difference", "exact",
           "config_of", "sheet_length"]

#: Standard errors assumed where a store gives none (see the module docstring):
#:
#: - ``a_rel``: a/a0 of a single trajectory, 0.01 (1 % of a0): the default
#:   ``target_stderr``; rounding-level reruns differed by 0.1-0.7 % of a0 (docs/convergence.md).
#:   Used only where the profile's ``a_stderr`` is missing or NaN.
#: - ``W_c`` [m]: 4 m. Measured: the Fig. 2 points rerun with the floe spacing changed by
#:   one ulp (``benchmarks/rounding_spread.py``, docs/reproducibility.md) gave 7 pairs of
#:   W_c differing by 0.5-2.5 m and once 15 m; sigma = RMS difference / sqrt(2) = 4.1 m.
#: - ``inner_over_c``: 0.1 (10 %) on alpha_inner / alpha_c — *assumed, not measured*
#:   (single-trajectory stores carry no spread of alpha_inner).
#: - ``log10_force``: 0.02 decade on a median log10 force ratio over a zone (F_w / F_d,
#:   F_c / F_w). Measured: the time-mean force profiles carry no standard error, so
#:   ``python benchmarks/paper_floors.py paper --seeds 0 1`` compares the Fig. 2
#:   points of two independent ensembles: sigma = RMS difference / sqrt(2) = 0.007-0.017
#:   decade (compact zone 0.007-0.010, collisional 0.017, model version 7), rounded up.
#:   (Until model version 7 this floor was 0.1 decade, assumed.)
FLOORS: dict[str, float] = {"a_rel": 0.01, "W_c": 4.0, "inner_over_c": 0.1,
                            "log10_force": 0.02}

#: Distance from the ice edge [m] at which "near the edge" is read (Fig. 6): ten 0.5 m
#: floes in, inside the collisional zone of every Fig. 6 point with one (W_c >= 12 m).
X_NEAR = 5.0

# ---------------------------------------------------------------------- the claims' targets
#: Claimed range of the exponent m of alpha ~ omega^m (paper §3, §5): "~ omega^4" for
#: ``ow`` read as 4 +- 0.5 (the ``ep`` tail's 2-2.5: :mod:`herman2019.exponents`).
M_OW = (3.5, 4.5)
#: "Close to" for an exponent: within 0.5, the half-width of "~ omega^4".
M_CLOSE = 0.5
#: "Close to", for a ratio (alpha_inner / alpha_c, x_b / W_c, F_c / F_w): within 25 %
#: (0.8-1.25, symmetric in log).
INNER_OVER_C = (0.8, 1.25)
#: "Roughly two orders of magnitude": log10(F_w / F_d) within half a decade of 2.
FORCE_DECADES = (1.5, 2.5)
#: "No influence" on a/a0 (random initial locations, §4.1): a difference within 0.01 (1 %
#: of a0): the resolution the campaigns are run to (ModelConfig's default
#: ``target_stderr``, the SE of a/a0 at which a point stops); a smaller effect is below
#: what a campaign resolves.
NO_EFFECT = 0.01
#: The smallest difference of a/a0 [a0] the paper's figures of a/a0 against x (Figs. 2, 5,
#: 6a, 6b) could show. The text gives their captions, not their axes, but each panel must
#: hold its curves: from 1 at the edge down to 0.55-0.75 (Fig. 2a), 0.75-0.93 (Fig. 5),
#: 0.42-0.98 (Fig. 6a, both periods in one panel), so its a/a0 axis spans at least about
#: half of a0. On a journal panel 5-7 cm tall that is at least 0.007-0.01 of a0 per mm;
#: curves drawn about 0.3 mm wide are told apart, and their order read, only about two
#: line widths (0.5-0.6 mm) apart: 0.004-0.006 of a0. Chosen: 0.005. "No visible
#: effect" (the edge spring, §4.1) is read as a difference within it.
A_RESOLUTION = 0.005


# ---------------------------------------------------------------------- checks
@dataclass(frozen=True)
class Check:
    """One row of the table: a claim of the paper and its verdict."""

    claim: str
    source: str
    campaign: str
    points: str
    quantity: str
    rule: str
    estimates: tuple[Estimate, ...]
    verdict: str
    evidence: str

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["estimates"] = [{k: (None if isinstance(v, float) and not math.isfinite(v)
                                 and k != "dof" else v) for k, v in asdict(e).items()}
                            for e in self.estimates]
        for e in out["estimates"]:
            if isinstance(e["dof"], float) and not math.isfinite(e["dof"]):
                e["dof"] = None
        return out


Profile = Callable[[str, str], Mapping[str, Any]]


def _close(series: pd.Series, value: Any) -> np.ndarray:
    """Where ``series`` equals ``value`` (text), or is within 1e-9 of it (numbers)."""
    if isinstance(value, str):
        return (series.astype(str) == value).to_numpy(dtype=bool)
    return np.isclose(series.to_numpy(dtype=float), float(value), rtol=1e-9, atol=0.0)


def _where(df: pd.DataFrame, values: Mapping[str, Any]) -> np.ndarray:
    mask = np.ones(len(df), dtype=bool)
    for k, v in values.items():
        mask &= _close(df[k], v)
    return mask


def point(df: pd.DataFrame, **values: Any) -> pd.Series | None:
    """The row of ``df`` with these swept values (None if absent or without result)."""
    rows = np.flatnonzero(_where(df, values))
    return None if rows.size == 0 else df.iloc[rows[0]]


def col(row: pd.Series, name: str) -> float:
    """``row[name]`` as float; NaN where the column is absent (an older schema)."""
    v = row.get(name, math.nan)
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    # -1 is the store's fill value of its integer columns (replicas, W_c_n): unknown
    return math.nan if (name in ("replicas", "W_c_n") and v < 0) else v


def config_of(row: Mapping[str, Any]) -> Any:
    """The point's :class:`floewave.ModelConfig`, from its ``config_json`` column."""
    from floewave.config import ModelConfig

    return ModelConfig.from_dict(json.loads(str(row["config_json"])))


def sheet_length(row: pd.Series) -> float:
    """The ice as placed [m]: N_f L_x + (N_f - 1) d_f."""
    n = col(row, "n_floes")
    return n * col(row, "L_x") + (n - 1) * col(row, "d_f")


def label_of(row: pd.Series | None, key: str, value: Any) -> str:
    extra = ""
    if row is not None and math.isfinite(col(row, "replicas")):
        extra = f" (R={int(col(row, 'replicas'))})"
    return f"{key}={value}{extra}"


def a_end(row: pd.Series | None, label: str, profile: Profile | None,
           campaign: str) -> Estimate:
    """a_end / a0 with its SE: ``a_end_stderr``, else the profile's last ``a_stderr``."""
    if row is None:
        return Estimate(label, math.nan)
    a0 = col(row, "a0")
    value = col(row, "a_end") / a0
    se, src = col(row, "a_end_stderr") / a0, "replicas"
    if not math.isfinite(se) and profile is not None:
        try:
            se, src = float(np.asarray(profile(campaign, row["hash"])["a_stderr"])[-1]) / a0, \
                "profile"
        except KeyError:
            se = math.nan
    return Estimate(label, value, se, src if math.isfinite(se) else "none").floored(
        FLOORS["a_rel"])


def a_near(row: pd.Series | None, label: str, profile: Profile | None, campaign: str,
            x_near: float = X_NEAR) -> Estimate:
    """a / a0 at the floe nearest ``x_near`` from the edge, SE from the profile."""
    if row is None or profile is None:
        return Estimate(label, math.nan)
    try:
        p = profile(campaign, row["hash"])
    except KeyError:
        return Estimate(label, math.nan)
    if "a" not in p or "x_mean" not in p:
        return Estimate(label, math.nan)
    x = np.asarray(p["x_mean"], dtype=float)
    i = int(np.nanargmin(np.abs(x - x_near)))
    a0 = col(row, "a0")
    se = (float(np.asarray(p["a_stderr"], dtype=float)[i]) / a0 if "a_stderr" in p
          else math.nan)
    return Estimate(label, float(np.asarray(p["a"], dtype=float)[i]) / a0, se,
                    "profile" if math.isfinite(se) else "none").floored(FLOORS["a_rel"])


def w_c(row: pd.Series | None, label: str, name: str = "W_c") -> Estimate:
    """W_c (or ``name``, e.g. ``W_c_gap``) with its replicas' SE, else the floor."""
    if row is None:
        return Estimate(label, math.nan)
    se = col(row, f"{name}_stderr")
    n = col(row, "W_c_n")
    if math.isfinite(n) and name == "W_c":
        label = f"{label} n={int(n)}"
    return Estimate(label, col(row, name), se, "replicas" if math.isfinite(se) else "none"
                    ).floored(FLOORS["W_c"])


def inner_over_c(row: pd.Series | None, label: str) -> Estimate:
    """alpha_inner / alpha_c with the replicas' SE, else the floor."""
    if row is None:
        return Estimate(label, math.nan)
    c = col(row, "alpha_c")
    se = col(row, "alpha_inner_stderr") / c
    return Estimate(label, col(row, "alpha_inner") / c, se,
                    "replicas" if math.isfinite(se) else "none").floored(FLOORS["inner_over_c"])


def force_decades(row: pd.Series | None, label: str, profile: Profile | None, campaign: str,
                  zone: str, num: str = "F_w_mean", den: str = "F_d_mean") -> Estimate:
    """Median over the floes of a zone of log10(num / den) (default F_w_mean / F_d_mean):
    ``compact`` (from W_c to compact_end) or ``collisional`` (before W_c); SE: the measured
    floor ``log10_force`` (no per-replica forces are stored)."""
    if row is None or profile is None:
        return Estimate(label, math.nan)
    W_c, end = col(row, "W_c"), col(row, "compact_end")
    if not math.isfinite(W_c):
        return Estimate(label, math.nan)
    try:
        p = profile(campaign, row["hash"])
    except KeyError:
        return Estimate(label, math.nan)
    if num not in p or den not in p:
        return Estimate(label, math.nan)
    x = np.asarray(p["x_mean"], dtype=float)
    fn = np.asarray(p[num], dtype=float)
    fd = np.asarray(p[den], dtype=float)
    if zone == "compact":
        sel = (x >= W_c) & (x <= (end if math.isfinite(end) else np.inf))
    else:
        sel = x < W_c
    sel &= (fn > 0) & (fd > 0)
    if not sel.any():
        return Estimate(label, math.nan)
    return Estimate(label, float(np.median(np.log10(fn[sel] / fd[sel])))).floored(
        FLOORS["log10_force"])


def make_check(claim: str, source: str, campaign: str, points: str, quantity: str,
               rule: str, estimates: Sequence[Estimate], verdict: tuple[str, str]) -> Check:
    """A :class:`Check` from a rule's (verdict, evidence) (its estimates and the check
    handed to the hook of :func:`herman2019.estimates.observing`, if any)."""
    check = Check(claim, source, campaign, points, quantity, rule, hooked(estimates), *verdict)
    return created(check)


def created(check: Check) -> Check:
    """``check``, shown to the hook of :func:`herman2019.estimates.observing` (if any)."""
    hook = current_hook()
    return check if hook is None else hook.created(check)


def sorted_values(df: pd.DataFrame, key: str, **fixed: Any) -> list[Any]:
    """The sorted distinct values of ``key`` among the rows with these ``fixed`` values."""
    return sorted(df.loc[_where(df, fixed), key].unique().tolist())


_BOUNDS = re.compile(r"in \[(log10 )?(-?[\d.]+), (log10 )?(-?[\d.]+)\]")
_BELOW = re.compile(r"< (-?[\d.]+)(?:\s|$)")


def range_bounds(quantity: str) -> tuple[float, float] | None:
    """The bounds a range row states in its quantity: ``in [lo, hi]`` (``log10 x`` taken
    as log10(x)) or ``< hi`` (lo = -inf); None if it states neither."""
    m = _BOUNDS.search(quantity)
    if m:
        lo, hi = float(m.group(2)), float(m.group(4))
        return (math.log10(lo) if m.group(1) else lo, math.log10(hi) if m.group(3) else hi)
    m = _BELOW.search(quantity)
    return (-math.inf, float(m.group(1))) if m else None


def difference(lo: Estimate, hi: Estimate, label: str) -> Estimate:
    """hi - lo with the combined SE of two independent estimates."""
    return Estimate(label, hi.value - lo.value, math.hypot(lo.se, hi.se),
                    "replicas" if lo.source == hi.source == "replicas" else "combined",
                    min(lo.dof, hi.dof))


def exact(label: str, value: float) -> Estimate:
    """An exactly computed value (an analytic rate or its fit): SE 0."""
    return Estimate(label, float(value), 0.0, "exact")


@dataclass
class Tables:
    """The campaigns' tables (name -> DataFrame, with :func:`sweep.analysis.stats.derived`
    columns), their profiles, and why a campaign is missing; ``checks`` collects the rows;
    ``trace``: run the Fig. 4 trace (a model run of about a second)."""

    d: dict[str, pd.DataFrame]
    profile: Profile | None
    missing: dict[str, str]
    checks: list[Check]
    trace: bool = True

    def add(self, check: Check) -> None:
        self.checks.append(check)

    def unavailable(self, name: str, claim: str, source: str, points: str, quantity: str,
                    rule: str) -> None:
        """An inconclusive row for a claim whose campaign has no table."""
        self.checks.append(created(Check(claim, source, name, points, quantity, rule, (),
                                         INCONCLUSIVE, f"not checked: {self.missing[name]}")))

    def prof(self, name: str, row: pd.Series | None) -> Mapping[str, Any] | None:
        """The profiles of ``row`` in campaign ``name`` (None if not available)."""
        if row is None or self.profile is None:
            return None
        try:
            return self.profile(name, row["hash"])
        except KeyError:
            return None
