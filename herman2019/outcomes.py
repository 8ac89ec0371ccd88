"""Each settled row read against the paper's resolution: holds, contradicted, or below what
the paper could show (``herman2019 check --settled FILE``).

A row's verdict is its rule's (:mod:`herman2019.estimates`) on the pooled estimates of the
look that decided it, at that look's boundary (``results/paper-settle/settled.json``).
A row that *fails* does so on differences the wrong way (a step, a pair, a value beyond a
bound, a flipped step), each with its SE and critical value z_c. Against the row's
resolution r (:mod:`herman2019.readings`), each such effect |d| lies in
[|d| - z_c se, |d| + z_c se]:

- **contradicted**: some effect exceeds r beyond its error bar (|d| - z_c se >= r): the
  opposite of the sentence, larger than its figure or text could show;
- **below the paper's resolution**: every effect lies within r with its error bar
  (|d| + z_c se <= r): the wrong sign, smaller than the paper could show;
- otherwise (an effect that straddles r) **inconclusive**.

A row that holds *holds*; an inconclusive one stays *inconclusive*, or *not testable*
where the paper does not fix the value. The rows of the v8 settling whose reading was
rewritten since (:data:`herman2019.readings.REWRITTEN`) are re-read from its pooled
estimates with the new rule at the same look's boundary, and marked as awaiting the
re-settle (which reads them look by look); two v8 rows that read one sentence twice are
shown as merged and not counted.
"""
from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from herman2019.check import markdown_cell
from herman2019.claims import NO_REVERSAL_Q, NO_REVERSAL_RULE
from herman2019.estimates import (
    FAILS,
    HOLDS,
    INCONCLUSIVE,
    Estimate,
    chain_diffs,
    critical,
    in_range,
    pair_diffs,
    same_order,
    z_critical,
)
from herman2019.points import A_RESOLUTION, Check, range_bounds
from herman2019.readings import REWRITTEN, Reading, reading_of
from herman2019.variants import no_effect_quantity, spring_claim
from herman2019.zones import BALANCE, BALANCE_DECADES, BALANCE_Q

__all__ = ["CONTRADICTED", "BELOW", "NOT_TESTABLE", "MERGED", "OUTCOMES", "Effect", "Outcome",
           "check_of", "wrong_way", "outcome_of", "classify", "counts", "format_outcomes",
           "settled_outcomes"]

CONTRADICTED = "contradicted"
BELOW = "below the paper's resolution"
NOT_TESTABLE = "not testable"
MERGED = "merged"
#: The outcomes counted, in the table's order.
OUTCOMES = (HOLDS, CONTRADICTED, BELOW, INCONCLUSIVE, NOT_TESTABLE)
#: The note of a v8 row re-read with its rewritten rule.
AWAITS = "re-read from the v8 pools; awaits the re-settle"


@dataclass(frozen=True)
class Effect:
    """A difference the wrong way: its size |d| [the quantity's unit] and the interval
    [|d| - z_c se, |d| + z_c se] its error bar allows (``lo``, ``hi``)."""

    label: str
    size: float
    lo: float
    hi: float

    def text(self) -> str:
        return f"{self.label}: {self.size:.2g} (within {max(self.lo, 0.0):.2g}-{self.hi:.2g})"


@dataclass(frozen=True)
class Outcome:
    """One row: its number in the settled table, the check as read, its reading, the
    outcome, the effects the wrong way (failing rows) and a note."""

    row: int
    check: Check
    reading: Reading | None
    outcome: str
    effects: tuple[Effect, ...] = ()
    note: str = ""


def check_of(row: Mapping[str, Any]) -> Check:
    """A row of a settled JSON (:func:`herman2019.settled.settled_dict`) as a :class:`Check`
    (a missing value or SE is NaN, missing dof infinite)."""
    def num(v: Any, default: float) -> float:
        return default if v is None else float(v)

    est = tuple(Estimate(e["label"], num(e["value"], math.nan), num(e["se"], math.nan),
                         e["source"], num(e["dof"], math.inf)) for e in row["estimates"])
    return Check(row["claim"], row["source"], row["campaign"], row["points"],
                 row["quantity"], row["rule"], est, row["verdict"], row["evidence"])


def _interval(label: str, d: float, se: float, zc: float) -> Effect:
    size = abs(d)
    half = zc * se if se > 0 else 0.0
    return Effect(label, size, size - half, size + half)


def rule_estimates(check: Check) -> list[Estimate]:
    """The estimates a range rule read: the differences of an equivalence row, the last of
    a fitted exponent's (m - m_c), the first of a single-value row (the others context),
    all of an every-point row."""
    est = list(check.estimates)
    if check.rule.startswith("range (equivalence)"):
        return [e for e in est if e.label.startswith("difference")]
    if check.rule.startswith("range (fit"):
        return est[-1:]
    if check.rule.startswith("range, every point"):
        return est
    return est[:1]


def wrong_way(check: Check) -> list[Effect]:
    """The differences the wrong way on which the row's rule fails (read at the critical
    value in force: :func:`herman2019.estimates.critical`)."""
    rule = check.rule
    valued = [e for e in check.estimates if math.isfinite(e.value)]
    if rule.startswith("chain"):
        increasing = rule.split(",")[1].strip().startswith("increasing")
        if len(valued) < 2:
            return []
        steps, ends = chain_diffs(valued, increasing=increasing)
        return [_interval(s.label, s.d, s.se, s.zc) for s in [*steps, ends] if s.z <= -s.zc]
    if rule.startswith("pair"):
        flat = list(check.estimates)
        diffs = pair_diffs(list(zip(flat[0::2], flat[1::2], strict=True)))
        return [_interval(s.label, s.d, s.se, s.zc) for s in diffs if s.d < 0
                and (s.z <= -s.zc or check.verdict == FAILS)]
    if rule.startswith("same order"):
        half = len(check.estimates) // 2
        near = [e for e, f in zip(check.estimates[:half], check.estimates[half:], strict=True)
                if math.isfinite(e.value) and math.isfinite(f.value)]
        far = [f for e, f in zip(check.estimates[:half], check.estimates[half:], strict=True)
               if math.isfinite(e.value) and math.isfinite(f.value)]
        if len(near) < 2:
            return []
        ns, ne = chain_diffs(near, increasing=True)
        fs, fe = chain_diffs(far, increasing=True)
        out = []
        for n, f in zip([*ns, ne], [*fs, fe], strict=True):
            if n.d * f.d < 0 and abs(n.z) >= n.zc and abs(f.z) >= f.zc:
                a, b = _interval(n.label, n.d, n.se, n.zc), _interval(f.label, f.d, f.se, f.zc)
                # a flip shows only where both orders show: the smaller side decides
                out.append(Effect(f"{n.label} (near) / far", min(a.size, b.size),
                                  min(a.lo, b.lo), min(a.hi, b.hi)))
        return out
    bounds = range_bounds(check.quantity)
    if rule.startswith("range") and bounds is not None:
        lo, hi = bounds
        # "no effect": the effect is the difference itself; a bound of "close to": the
        # excess beyond it (the figure cannot show less than its resolution either way)
        equivalence = rule.startswith("range (equivalence)")
        out = []
        for e in rule_estimates(check):
            if not math.isfinite(e.value):
                continue
            beyond = max(lo - e.value, e.value - hi)
            zc = z_critical(e.dof)
            if beyond > 0 and (e.se == 0 or (math.isfinite(e.se) and beyond / e.se >= zc)):
                out.append(_interval(e.label, abs(e.value) if equivalence else beyond,
                                     e.se, zc))
        return out
    return []


def outcome_of(check: Check, reading: Reading | None, boundary: float
               ) -> tuple[str, tuple[Effect, ...]]:
    """The row's outcome (the module docstring) and its effects the wrong way, read at
    ``boundary`` (the look's critical |z|)."""
    if check.verdict == HOLDS:
        return HOLDS, ()
    if check.verdict != FAILS:
        return (NOT_TESTABLE if reading is not None and not reading.testable
                else INCONCLUSIVE), ()
    with critical(boundary):
        effects = tuple(wrong_way(check))
    if reading is None or not effects:
        return INCONCLUSIVE, effects
    r = reading.resolution.value
    if any(e.lo >= r for e in effects):
        return CONTRADICTED, effects
    if all(e.hi <= r for e in effects):
        return BELOW, effects
    return INCONCLUSIVE, effects


# ---------------------------------------------------------------------- the v8 rows re-read
def _relabel(est: Sequence[Estimate], prefix: str) -> list[Estimate]:
    return [Estimate(f"{prefix} {e.label}", e.value, e.se, e.source, e.dof) for e in est]


def _reread(row: Mapping[str, Any], rows: Sequence[Mapping[str, Any]], new_claim: str
            ) -> Check | None:
    """The v8 row ``row`` read with the rule of ``new_claim`` (None: its estimates are not
    in the settled table)."""
    old = check_of(row)
    if new_claim.startswith("Fig. 6a: no reversal"):
        T = old.points.split(",")[0]                               # "T 1.8 s"
        near = [r for r in rows if r["claim"] == "smaller d_f attenuates more near the edge"
                and r["campaign"] == old.campaign and r["points"].split(",")[0] == T]
        if len(near) != 1 or near[0]["seeds"] != row["seeds"]:
            return None                                            # not the same seeds
        n_est = _relabel(check_of(near[0]).estimates, "5 m")
        f_est = _relabel(old.estimates, "far end")
        verdict = same_order(n_est, f_est)
        return Check(new_claim, old.source, old.campaign, f"{T}, d_f 0.005-0.05 m, x = 5 m"
                     " and far end", NO_REVERSAL_Q, NO_REVERSAL_RULE, (*n_est, *f_est),
                     *verdict)
    if new_claim == BALANCE:
        verdict, evidence = in_range(list(old.estimates), -BALANCE_DECADES, BALANCE_DECADES)
        return Check(new_claim, old.source, old.campaign, old.points, BALANCE_Q, old.rule,
                     old.estimates, verdict, evidence)
    spring = {spring_claim(w): w for w in ("k_s / 10", "k_s x 10")}
    if new_claim in spring:
        what = spring[new_claim]
        diffs = [e for e in old.estimates if e.label.startswith("difference")]
        verdict, evidence = in_range(diffs, -A_RESOLUTION, A_RESOLUTION)
        return Check(new_claim, old.source, old.campaign, old.points,
                     no_effect_quantity(what, A_RESOLUTION), old.rule, old.estimates,
                     verdict, evidence)
    return None


def classify(settled: Mapping[str, Any]) -> list[Outcome]:
    """Every row of a settled JSON (``herman2019 check --settle --json``) with its outcome."""
    rows = settled["rows"]
    claims = [r["claim"] for r in rows]
    out = []
    for i, row in enumerate(rows, 1):
        check = check_of(row)
        new_claim, how = REWRITTEN.get(row["claim"], (row["claim"], ""))
        reading = reading_of(row["claim"])
        note = ""
        if how == "merged":
            target = claims.index(new_claim) + 1 if new_claim in claims else 0
            out.append(Outcome(i, check, reading, MERGED, (), "one reading with"
                               f" #{target}: the sentence is read once"))
            continue
        if how == "re-read":
            with critical(row["boundary"]):
                again = _reread(row, rows, new_claim)
            if again is None:
                out.append(Outcome(i, check, reading, INCONCLUSIVE, (),
                                   "awaits the re-settle (its quantity is not in the table)"))
                continue
            check, note = again, AWAITS
        outcome, effects = outcome_of(check, reading, row["boundary"])
        out.append(Outcome(i, check, reading, outcome, effects, note))
    return out


def counts(outcomes: Sequence[Outcome]) -> dict[str, int]:
    """How many rows have each outcome (merged rows not counted)."""
    return {o: sum(x.outcome == o for x in outcomes) for o in OUTCOMES}


def _outcome_cell(o: Outcome) -> str:
    text = o.outcome
    if o.effects:
        worst = max(o.effects, key=lambda e: e.size)
        r = o.reading.resolution.text() if o.reading else "?"
        text += f" (largest the wrong way: {worst.text()}; resolution {r})"
    return text + (f"; {o.note}" if o.note else "")


def format_outcomes(outcomes: Sequence[Outcome]) -> str:
    """The outcomes as one Markdown table with a count line (docs/paper-check.md)."""
    lines = ["| # | the paper (quoted) | reading | resolution | outcome |",
             "|---|---|---|---|---|"]
    for o in outcomes:
        rd = o.reading
        paper = f"\"{rd.quote}\" ({rd.where})" if rd else o.check.claim
        lines.append("| " + " | ".join(markdown_cell(s) for s in (
            str(o.row), paper, f"{o.check.claim}: {rd.reading if rd else o.check.quantity}",
            rd.resolution.text() if rd else "—", _outcome_cell(o))) + " |")
    c = counts(outcomes)
    merged = [f"#{o.row}" for o in outcomes if o.outcome == MERGED]
    waiting = [f"#{o.row}" for o in outcomes if o.note == AWAITS]
    lines += ["", f"{c[HOLDS]} hold, {c[CONTRADICTED]} contradicted, {c[BELOW]} below the"
              f" paper's resolution, {c[INCONCLUSIVE]} inconclusive, {c[NOT_TESTABLE]} not"
              f" testable ({sum(c.values())} readings"
              + (f"; {', '.join(merged)} merged into the row that reads the same sentence"
                 if merged else "") + ")."
              + (f" Re-read from the v8 pools with their rewritten rule, awaiting the"
                 f" re-settle: {', '.join(waiting)}." if waiting else "")]
    return "\n".join(lines)


def settled_outcomes(path: str | Path) -> str:
    """The Markdown table of :func:`format_outcomes` for the settled JSON at ``path``."""
    return format_outcomes(classify(json.loads(Path(path).read_text())))
