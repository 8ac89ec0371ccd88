"""Pooling the paper checks of independent seeds (``herman2019 check --settle``,
:mod:`herman2019.settle`).

Every rule and every check of :mod:`herman2019.claims` hands its estimates to a hook
(:func:`herman2019.estimates.observing`). A :class:`Recorder` keeps them, check by check,
for one seed's stores; a :class:`Pooler` hands every rule of one more run the estimates
pooled over the seeds' records (:func:`pool`), so the claims' code runs unchanged on
the pooled data. :func:`calibration` compares the seeds' spread with their stated SEs;
:func:`widening` gives the factor by which each estimate's stated SE is too small.
"""
from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from herman2019.claims import PAPER_CAMPAIGNS
from herman2019.estimates import Estimate
from herman2019.points import Check

__all__ = ["EMPIRICAL_MIN", "SHARED_REPLICA0", "pool", "Recorder", "Pooler", "campaigns_of",
           "shared_share", "calibration", "WIDEN_MIN", "widening", "HONEST_R8"]

#: Seeds from which the seeds' spread bounds a pooled SE from below (S - 1 dof).
EMPIRICAL_MIN = 4
#: Paper campaigns whose replica 0 is the same chain for every seed (``placement =
#: "uniform"``: replica 0 is the paper's arrangement, whatever the seed;
#: :func:`floewave.ensemble.initial_positions`), with their replicas R. Their seeds share
#: 1 of R replicas, so the mean of S seeds has the variance of independent seeds times
#: 1 + (S - 1) / R; :func:`pool` widens their SE by its square root (for a difference
#: with a campaign that shares nothing, that is conservative).
SHARED_REPLICA0 = {"uniform": 8}
_STATED = ("replicas", "profile", "fit", "periods", "combined")


_COUNT = re.compile(r"\s+n=\d+")


def _base(label: str) -> str:
    """A label without what may differ between seeds: the count of replicas with a value
    (``n=8``), a parenthesised note or a colon's detail."""
    return _COUNT.sub("", label).split(" (", 1)[0].split(":", 1)[0].strip()


def pool(estimates: Sequence[Estimate], shared: float = 0.0, widen: float = 1.0) -> Estimate:
    """One estimate from the same quantity's estimates on independent seeds (the module
    docstring of :mod:`herman2019.settle`, step 2). Seeds without a value are left out;
    none with one: NaN.

    ``shared``: the share rho of each seed's replicas common to all seeds (1 / R for
    :data:`SHARED_REPLICA0`): the seeds' means then correlate by rho, so a stated SE is
    widened by sqrt(1 + (S - 1) rho) and the seeds' spread (which shrinks by 1 - rho) by
    sqrt((1 + (S - 1) rho) / (1 - rho)). ``widen``: a factor on the stated SE (the audit's,
    :func:`widening`), applied before it is compared with the spread."""
    ok = [e for e in estimates if math.isfinite(e.value)]
    if not ok:
        return estimates[0]
    n = len(ok)
    values = np.array([e.value for e in ok])
    mean = float(values.mean())
    label = ok[0].label
    if all(e.source == "exact" for e in ok):
        return Estimate(label, mean, 0.0 if np.ptp(values) == 0 else math.nan, "exact")
    ses = np.array([e.se for e in ok])
    spread = math.nan
    if n >= EMPIRICAL_MIN:
        spread = float(values.std(ddof=1) / math.sqrt(n)
                       * math.sqrt((1.0 + (n - 1) * shared) / (1.0 - shared)))
    if all(e.source in _STATED for e in ok) and np.all(np.isfinite(ses)):
        se = float(math.sqrt(np.sum(ses ** 2)) / n * math.sqrt(1.0 + (n - 1) * shared)
                   * widen)
        dofs = np.array([e.dof for e in ok])
        if np.all(np.isinf(dofs)):
            dof = math.inf
        else:                                               # Welch-Satterthwaite
            dof = float(np.sum(ses ** 2) ** 2 / np.sum(ses ** 4 / dofs))
        source = ok[0].source if len({e.source for e in ok}) == 1 else "combined"
        if spread > se:                        # the seeds' spread, where it is the larger
            return Estimate(label, mean, spread, "seeds", float(n - 1))
        return Estimate(label, mean, se, source, dof)
    if math.isfinite(spread):
        return Estimate(label, mean, spread, "seeds", float(n - 1))
    if np.all(np.isfinite(ses)):
        return Estimate(label, mean, float(math.sqrt(np.sum(ses ** 2)) / n), "floor")
    return Estimate(label, mean)


_WITH_VALUE = re.compile(r"\b\d+ with a value")


def _key(check: Check) -> tuple[str, str, str, str]:
    """Which check: its claim, campaign, points (a count of points with a value, which may
    differ between seeds, left out) and quantity."""
    return (check.claim, check.campaign, _WITH_VALUE.sub("N with a value", check.points),
            check.quantity)


class Recorder:
    """A hook (:func:`herman2019.estimates.observing`) that keeps, per check made, the
    estimates every rule and the check itself were given (``groups[i]``: check i's;
    ``keys[i]``: which check: claim, campaign, points, quantity and the how-manieth of
    that key). The checks a seed makes depend on its stores (a missing campaign gives
    one row per claim, a present one a row per stored period), so seeds are matched by
    key, never by position."""

    def __init__(self) -> None:
        self.groups: list[list[tuple[Estimate, ...]]] = []
        self.campaigns: list[str] = []
        #: campaign -> a problem with a store that exists (unreadable), by check_stores
        self.problems: dict[str, str] = {}
        self.keys: list[tuple] = []
        self._index: dict[tuple, int] | None = None
        self._open: list[tuple[Estimate, ...]] = []

    def estimates(self, ests: tuple[Estimate, ...]) -> tuple[Estimate, ...]:
        self._open.append(ests)
        return ests

    def created(self, check: Check) -> Check:
        self.groups.append(self._open)
        self.campaigns.append(check.campaign)
        key = _key(check)
        n = sum(k[:-1] == key for k in self.keys)
        self.keys.append((*key, n))
        self._open = []
        return check

    def group(self, key: tuple) -> list[tuple[Estimate, ...]] | None:
        """The recorded group of the check with ``key`` (None: that check not made)."""
        if self._index is None or len(self._index) != len(self.keys):
            self._index = {k: i for i, k in enumerate(self.keys)}
        i = self._index.get(key)
        return None if i is None else self.groups[i]


def _aligned(a: Sequence[tuple[Estimate, ...]], b: Sequence[tuple[Estimate, ...]]) -> bool:
    return len(a) == len(b) and all(
        len(x) == len(y) and all(_base(e.label) == _base(f.label) for e, f in zip(x, y,
                                                                                   strict=True))
        for x, y in zip(a, b, strict=True))


class Pooler:
    """A hook that hands every rule and check of a run the estimates pooled over the
    seeds' :class:`Recorder` s (the carrier's first). A seed whose group differs in shape or
    labels from the carrier's (its store missing, say) is left out of that check;
    ``used[i]``: the seeds pooled for check i."""

    def __init__(self, recorders: Sequence[Recorder],
                 widen: dict[tuple, float] | None = None) -> None:
        self.recorders = recorders
        self.widen = widen or {}
        self.used: list[int] = []
        self._group = 0
        self._call = 0
        self._members: list[list[tuple[Estimate, ...]]] | None = None

    def _current(self) -> list[list[tuple[Estimate, ...]]]:
        if self._members is None:
            carrier = self.recorders[0]
            g = self._group
            self._members = []
            if g < len(carrier.keys):
                mine = carrier.groups[g]
                for rec in self.recorders:
                    theirs = rec.group(carrier.keys[g])
                    if theirs is not None and _aligned(theirs, mine):
                        self._members.append(theirs)
        return self._members

    def estimates(self, ests: tuple[Estimate, ...]) -> tuple[Estimate, ...]:
        members = self._current()
        j = self._call
        self._call += 1
        if not members or j >= len(members[0]) or len(members[0][j]) != len(ests):
            return ests
        carrier = self.recorders[0]
        shared = shared_share(carrier.campaigns[self._group])
        calls = [m[j] for m in members]
        out = []
        for i in range(len(ests)):
            f = self.widen.get((carrier.keys[self._group], j, i), 1.0)
            out.append(pool([c[i] for c in calls], shared, max(f, 1.0)))
        return tuple(out)

    def created(self, check: Check) -> Check:
        self.used.append(len(self._current()))
        self._group += 1
        self._call = 0
        self._members = None
        return check


_NAMES = re.compile(r"[a-z0-9_]+")


def shared_share(campaign: str) -> float:
    """The share of replicas common to all seeds in a row on ``campaign``."""
    names = [w for w in _NAMES.findall(campaign) if w in SHARED_REPLICA0]
    return max((1.0 / SHARED_REPLICA0[w] for w in names), default=0.0)


def campaigns_of(check: Check) -> list[str]:
    """The paper campaigns a row rests on (from its campaign column: ``uniform vs fig2``)."""
    return [w for w in _NAMES.findall(check.campaign) if w in PAPER_CAMPAIGNS]


def _entries(seeds: Sequence[int], recorded: dict[int, Recorder]):
    """(g, key, j, i, chi2, n, estimates) of every pooled estimate with a stated SE on at
    least 3 independent seeds (groups of :data:`SHARED_REPLICA0` campaigns left out)."""
    recs = [recorded[s] for s in seeds]
    if len(recs) < 3:
        return
    carrier = recs[0]
    for g, key in enumerate(carrier.keys):
        if shared_share(carrier.campaigns[g]):   # seeds that share a replica: dependent
            continue
        members = [m for m in (r.group(key) for r in recs)
                   if m is not None and _aligned(m, carrier.groups[g])]
        if len(members) < 3:
            continue
        for j, call in enumerate(carrier.groups[g]):
            for i in range(len(call)):
                es = [m[j][i] for m in members]
                if not all(e.source in _STATED and math.isfinite(e.value) and e.se > 0
                           and math.isfinite(e.se) for e in es):
                    continue
                v = np.array([e.value for e in es])
                se = np.array([e.se for e in es])
                yield g, key, j, i, float(np.sum((v - v.mean()) ** 2 / se ** 2)), len(es), es


def calibration(seeds: Sequence[int], recorded: dict[int, Recorder]) -> dict[str, Any]:
    """How the seeds' spread compares with their stated SEs: over every pooled estimate
    with a stated SE on at least 3 seeds, chi^2 = sum_s (x_s - mean)^2 / se_s^2 with
    S - 1 degrees of freedom (equal SEs); returns the total chi^2 / dof, the dof, the
    number of estimates and the worst. Honest SEs known exactly give 1 (+- sqrt(2 / dof));
    honest SEs that are themselves estimated from R = 8 replicas give about
    E[7 / chi^2_7] = 1.4 (:data:`HONEST_R8`)."""
    chi2 = dof = 0.0
    each: list[tuple[float, int, str, str]] = []
    seen: set[tuple[float, ...]] = set()
    for g, _key, _j, _i, c2, n, es in _entries(seeds, recorded):
        once = tuple(e.value for e in es)   # one estimate read by several rules: once
        if once in seen:
            continue
        seen.add(once)
        chi2 += c2
        dof += n - 1
        each.append((c2 / (n - 1), g, es[0].label, es[0].source))
    if not dof:
        return {}
    each.sort(reverse=True)
    return {"chi2_per_dof": round(chi2 / dof, 4), "dof": dof, "estimates": len(each),
            "seeds": len(seeds),
            "worst": [{"row": g + 1, "estimate": lab, "source": src, "chi2_per_dof":
                       round(c, 2)} for c, g, lab, src in each[:8]]}


#: chi^2 / dof of honest SEs estimated from 8 replicas (E[nu / chi^2_nu], nu = 7).
HONEST_R8 = 7.0 / 5.0
#: Seeds from which a point's spread is trusted to widen its stated SE (:func:`widening`).
WIDEN_MIN = 8


def widening(seeds: Sequence[int], recorded: dict[int, Recorder]) -> dict[tuple, float]:
    """(check key, call, index) -> sqrt(chi^2 / dof) of the seeds' spread against their
    stated SEs, where it exceeds 1 on at least :data:`WIDEN_MIN` seeds: the factor by
    which an estimate's stated SE is too small (the audit of :mod:`herman2019.settle`).
    Taken against 1, not :data:`HONEST_R8`: conservative by up to sqrt(1.4) for replica
    SEs."""
    out = {}
    for _g, key, j, i, c2, n, _es in _entries(seeds, recorded):
        if n >= WIDEN_MIN and c2 > n - 1:
            out[key, j, i] = math.sqrt(c2 / (n - 1))
    return out
