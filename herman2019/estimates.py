"""Estimates with standard errors, and the rules that turn them into verdicts.

The verdicts: holds, fails, inconclusive.

Every quantity is an :class:`Estimate`: a value and its standard error (SE). Where the SE
comes from, in order of preference:

1. the ensemble columns of schema v3 stores (``a_end_stderr``, ``W_c_stderr``,
   ``alpha_inner_stderr``, ...: the standard error over R replicas), when present and
   finite;
2. the per-floe profile ``a_stderr`` (the iteration noise of a single trajectory; for a(x)
   it was measured to be honest: RMS z 0.63 between rounding-level reruns);
3. for a power-law exponent, the least-squares fit (weighted by the alphas' SEs when they
   exist, then inflated by sqrt(chi^2 / dof) when that exceeds 1 — the Birge ratio; else
   the unweighted fit's residual SE); either way the SE is judged with the Student-t value
   for n - 2 degrees of freedom, whatever chi^2 / dof is (one rule for every fit);
4. otherwise a stated **floor** (:data:`herman2019.claims.FLOORS`): the noise a single
   trajectory is known (or assumed, where so marked) to carry. A quantity with no SE and
   no floor keeps a NaN SE and can only be ``inconclusive``. So a quantity without an
   error bar can only hold or fail when the effect is large against its floor.

The critical value is z_c = 2 (two standard errors); the SE of a fitted exponent (n
periods, nu = n - 2 degrees of freedom) uses the Student-t value with the same tail
probability (t_nu at 97.7 %: 4.5 for nu = 2, 2.5 for nu = 6, 2.4 for nu = 8) instead.

- **Ordering along a chain** (``higher eps -> lower a/a0`` over eps = 0.2 ... 0.8): the
  required differences are the consecutive steps, each with
  z = (x2 - x1) / sqrt(se1^2 + se2^2) signed so that the claim is z > 0. The claim
  *fails* if a step, or the end-to-end difference (first versus last point), has the
  wrong sign with |z| >= z_c; it *holds* if every step has the claimed sign and the
  end-to-end difference has z >= z_c; otherwise it is *inconclusive*.
- **Independent pairs** (``ep`` attenuates less than ``ml`` at each eps): each pair's z as
  above; combined evidence is Stouffer's z = sum(z_i) / sqrt(n). *Fails* if a pair has
  z <= -z_c or the combined z <= -z_c; *holds* if every pair has the claimed sign and the
  combined z >= z_c; otherwise *inconclusive*.
- **The same order at two places** (Fig. 6a, T = 1.8 s: the d_f ordering of a/a0 at 5 m
  is the far end's): each step of the chain at both places; the claim *fails* if a step
  (or the ends) has opposite signs at the two places, each with |z| >= z_c (a flip); it
  *holds* if every step has the same sign at both and the ends differ at both with
  |z| >= z_c; otherwise it is *inconclusive*.
- **A value in a range** (alpha_inner / alpha_c in [0.8, 1.25], an exponent in [3.5, 4.5]):
  z_lo = (x - lo) / se, z_hi = (hi - x) / se. A point holds if both are >= z_c (the whole
  +-z_c se interval inside the range) and fails if either is <= -z_c (the interval wholly
  outside); over several points the claim holds if every point holds, fails if any fails,
  and is otherwise inconclusive.

Points without a value (failed, no compact zone for W_c, a fit too short) are left out and
named in the evidence; fewer than two points (one for a range) leave the claim
inconclusive. Claims whose campaign has no store are inconclusive ("no store"). The
verdicts never change the exit status of ``herman2019 check`` (0 whatever they are; 2 bad
input, 3 a store missing or unreadable — the table is still printed).
"""
from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, replace
from functools import cache
from typing import Any

import numpy as np

__all__ = ["Estimate", "Diff", "Z_CRIT", "HOLDS", "FAILS", "INCONCLUSIVE", "z_critical",
           "chain_diffs", "pair_diffs", "ordering", "pairs", "same_order", "in_range",
           "power_exponent", "critical", "hooked", "observing", "current_hook"]

HOLDS, FAILS, INCONCLUSIVE = "holds", "fails", "inconclusive"

#: Critical |z| of every rule (two standard errors).
Z_CRIT = 2.0


# ---------------------------------------------------------------------- estimates
@dataclass(frozen=True)
class Estimate:
    """A value with its standard error.

    ``se`` is NaN when unknown; ``source`` says where it came from (``replicas``,
    ``profile``, ``fit``, ``floor``, ``combined`` (a difference of estimates with different
    sources), ``exact`` (an analytic value, SE 0) or ``none``); ``dof`` the degrees of freedom
    of an SE estimated from residuals (``inf``: known); ``label`` names the point.
    """

    label: str
    value: float
    se: float = math.nan
    source: str = "none"
    dof: float = math.inf

    def floored(self, floor: float | None) -> Estimate:
        """This estimate, with ``floor`` as its SE if it has none (source ``floor``)."""
        if math.isfinite(self.se) or floor is None:
            return self
        return replace(self, se=float(floor), source="floor", dof=math.inf)

    def text(self) -> str:
        """``label: value ± se`` (``(floor)`` marks an assumed SE, ``no SE`` a missing one)."""
        if not math.isfinite(self.value):
            return f"{self.label}: n/a"
        if not math.isfinite(self.se):
            return f"{self.label}: {self.value:.4g} (no SE)"
        if self.source == "exact":
            return f"{self.label}: {self.value:.4g} (exact)"
        digits = max(0, 1 - math.floor(math.log10(self.se))) if self.se > 0 else 4
        mark = " (floor)" if self.source == "floor" else ""
        return f"{self.label}: {self.value:.{digits}f} ± {self.se:.{digits}f}{mark}"


#: The critical |z| in force (:data:`Z_CRIT`; a look's boundary inside :func:`critical`).
_Z: ContextVar[float] = ContextVar("z_crit", default=Z_CRIT)
#: Who sees every estimate a rule or a check is given (:func:`observing`).
_HOOK: ContextVar[Any] = ContextVar("estimate_hook", default=None)


@contextmanager
def critical(z: float) -> Iterator[None]:
    """Every rule inside reads its z's against ``z`` instead of :data:`Z_CRIT` (a look's
    boundary of :mod:`herman2019.sequential`)."""
    token = _Z.set(float(z))
    try:
        yield
    finally:
        _Z.reset(token)


@contextmanager
def observing(hook: Any) -> Iterator[None]:
    """Inside, every rule and every check hands its estimates to ``hook.estimates(tuple)``
    and uses what it returns; every check made is handed to ``hook.created(check)``
    (:mod:`herman2019.settle` records the estimates of each seed this way, and pools them)."""
    token = _HOOK.set(hook)
    try:
        yield
    finally:
        _HOOK.reset(token)


def current_hook() -> Any:
    """The hook of the innermost :func:`observing` (None outside one)."""
    return _HOOK.get()


def hooked(estimates: Sequence[Estimate]) -> tuple[Estimate, ...]:
    """``estimates`` as the hook of :func:`observing` returns them (unchanged without one)."""
    hook = _HOOK.get()
    return tuple(estimates) if hook is None else tuple(hook.estimates(tuple(estimates)))


def z_critical(dof: float) -> float:
    """The critical |z|: :data:`Z_CRIT` (or the boundary in force, :func:`critical`) for a
    known SE, the Student-t value with the same one-sided tail probability for an SE
    estimated with ``dof`` degrees of freedom."""
    return _z_critical(dof, _Z.get())


@cache
def _z_critical(dof: float, z: float) -> float:
    if not math.isfinite(dof):
        return z
    if dof < 1:
        return math.inf
    from scipy import stats

    return float(stats.t.ppf(stats.norm.cdf(z), dof))


@dataclass(frozen=True)
class Diff:
    """A difference the claim says is positive: ``d`` with its SE, the degrees of freedom
    of that SE, and which points it joins (``label``)."""

    d: float
    se: float
    dof: float
    label: str = ""

    @property
    def z(self) -> float:
        if not math.isfinite(self.se):
            return math.nan
        if self.se == 0:
            return math.copysign(math.inf, self.d) if self.d != 0 else 0.0
        return self.d / self.se

    @property
    def zc(self) -> float:
        """The critical |z| it is read with (:func:`z_critical` of its dof)."""
        return z_critical(self.dof)


def _diff(lo: Estimate, hi: Estimate) -> Diff:
    """hi - lo (the claim is that it is positive) with its combined SE."""
    return Diff(hi.value - lo.value, math.hypot(lo.se, hi.se), min(lo.dof, hi.dof),
                f"{lo.label} -> {hi.label}")


def _zs(z: float) -> str:
    return "n/a" if math.isnan(z) else f"{z + 0.0:+.1f}"        # + 0.0: no "-0.0"


def _valued(estimates: Sequence[Estimate]) -> tuple[list[Estimate], str]:
    ok = [e for e in estimates if math.isfinite(e.value)]
    gone = [e.label for e in estimates if not math.isfinite(e.value)]
    return ok, (f"; left out (no value): {', '.join(gone)}" if gone else "")


def _no_se(estimates: Sequence[Estimate]) -> str:
    missing = [e.label for e in estimates if not math.isfinite(e.se)]
    return f"; no error bar: {', '.join(missing)}" if missing else ""


def chain_diffs(points: Sequence[Estimate], *, increasing: bool
                ) -> tuple[list[Diff], Diff]:
    """The consecutive steps and the end-to-end difference of a chain (points with a
    value, at least two), each signed so that the claim ("increases" when ``increasing``,
    else "decreases") says it is positive."""
    sign = 1.0 if increasing else -1.0

    def claimed(a: Estimate, b: Estimate) -> Diff:
        raw = _diff(a, b)
        return Diff(sign * raw.d, raw.se, raw.dof, raw.label)

    steps = [claimed(a, b) for a, b in zip(points[:-1], points[1:], strict=True)]
    return steps, claimed(points[0], points[-1])


def pair_diffs(pair_list: Sequence[tuple[Estimate, Estimate]]) -> list[Diff]:
    """Second minus first of each pair with both values (the claim: positive)."""
    return [_diff(a, b) for a, b in pair_list
            if math.isfinite(a.value) and math.isfinite(b.value)]


# ---------------------------------------------------------------------- the rules
def ordering(estimates: Sequence[Estimate], *, increasing: bool) -> tuple[str, str]:
    """Verdict and evidence for "the value increases (``increasing``) / decreases along
    ``estimates``" (the chain rule of the module docstring)."""
    pts, gone = _valued(hooked(estimates))
    if len(pts) < 2:
        return INCONCLUSIVE, f"fewer than 2 points with a value{gone}"
    steps, ends = chain_diffs(pts, increasing=increasing)
    zc = ends.zc
    evidence = (f"steps z = {', '.join(_zs(s.z) for s in steps)}; ends z = {_zs(ends.z)}"
                f" (z_c {zc:.2g}){gone}{_no_se(pts)}")
    if any(s.z <= -s.zc for s in steps + [ends]):
        return FAILS, evidence
    if all(s.d > 0 for s in steps) and ends.z >= zc:
        return HOLDS, evidence
    return INCONCLUSIVE, evidence


def pairs(pair_list: Sequence[tuple[Estimate, Estimate]]) -> tuple[str, str]:
    """Verdict and evidence for "the second of each pair is above the first" (independent
    pairs, Stouffer's combined z)."""
    flat = hooked([e for p in pair_list for e in p])
    pair_list = list(zip(flat[0::2], flat[1::2], strict=True))
    valid = [(a, b) for a, b in pair_list
             if math.isfinite(a.value) and math.isfinite(b.value)]
    gone = [f"{a.label}/{b.label}" for a, b in pair_list
            if not (math.isfinite(a.value) and math.isfinite(b.value))]
    gone_txt = f"; left out (no value): {', '.join(gone)}" if gone else ""
    if not valid:
        return INCONCLUSIVE, f"no pair with values{gone_txt}"
    diffs = pair_diffs(valid)
    zs = [d.z for d in diffs]
    # an exact pair (SE 0) has z = +-inf; inf - inf (or a missing SE) leaves no combined z
    comb = sum(zs) / math.sqrt(len(zs)) if not any(math.isnan(z) for z in zs) else math.nan
    zc = z_critical(min(d.dof for d in diffs))
    evidence = (f"pair z = {', '.join(_zs(z) for z in zs)}; combined z = {_zs(comb)}"
                f" (z_c {zc:.2g}){gone_txt}"
                f"{_no_se([e for p in valid for e in p])}")
    if any(d.z <= -d.zc for d in diffs) or comb <= -zc:
        return FAILS, evidence
    if all(d.d > 0 for d in diffs) and comb >= zc:
        return HOLDS, evidence
    return INCONCLUSIVE, evidence


def same_order(near: Sequence[Estimate], far: Sequence[Estimate]) -> tuple[str, str]:
    """Verdict and evidence for "the points are in the same order at both places": the
    same chain (``near[i]`` and ``far[i]`` the same point) read at two places, e.g. a/a0 at
    5 m and at the far end along d_f. Step i *flips* when its differences at the two
    places have opposite signs, each with |z| >= z_c. The claim *fails* if a step or the
    ends flip; it *holds* if every step has the same sign at both places and the ends
    differ at both with |z| >= z_c, the same sign; otherwise it is *inconclusive*. Points
    without a value at either place are left out."""
    both = hooked([*near, *far])
    near, far = both[:len(near)], both[len(near):]
    kept = [(a, b) for a, b in zip(near, far, strict=True)
            if math.isfinite(a.value) and math.isfinite(b.value)]
    gone = [a.label for a, b in zip(near, far, strict=True)
            if not (math.isfinite(a.value) and math.isfinite(b.value))]
    gone_txt = f"; left out (no value): {', '.join(gone)}" if gone else ""
    if len(kept) < 2:
        return INCONCLUSIVE, f"fewer than 2 points with a value at both places{gone_txt}"
    n_steps, n_ends = chain_diffs([a for a, _ in kept], increasing=True)
    f_steps, f_ends = chain_diffs([b for _, b in kept], increasing=True)
    pairs_ = list(zip([*n_steps, n_ends], [*f_steps, f_ends], strict=True))

    def flips(n: Diff, f: Diff) -> bool:
        return n.d * f.d < 0 and abs(n.z) >= n.zc and abs(f.z) >= f.zc

    zc = min(n_ends.zc, f_ends.zc)
    steps = ", ".join(f"{_zs(n.z)} / {_zs(f.z)}" for n, f in pairs_[:-1])
    evidence = (f"steps z (near / far) = {steps};"
                f" ends z = {_zs(n_ends.z)} / {_zs(f_ends.z)} (z_c {zc:.2g}){gone_txt}"
                f"{_no_se([e for p in kept for e in p])}")
    flipped = [n.label for n, f in pairs_ if flips(n, f)]
    if flipped:
        return FAILS, evidence + f"; flips: {', '.join(flipped)}"
    if all(n.d * f.d > 0 for n, f in pairs_[:-1]) and n_ends.d * f_ends.d > 0 \
            and abs(n_ends.z) >= n_ends.zc and abs(f_ends.z) >= f_ends.zc:
        return HOLDS, evidence
    return INCONCLUSIVE, evidence


def in_range(estimates: Sequence[Estimate], lo: float, hi: float) -> tuple[str, str]:
    """Verdict and evidence for "every value lies in [lo, hi]" (``math.inf`` for an open
    end)."""
    pts, gone = _valued(hooked(estimates))
    if not pts:
        return INCONCLUSIVE, f"no point with a value{gone}"
    held, failed, parts = [], [], []
    for e in pts:
        if math.isfinite(e.se) and e.se > 0:
            z_lo = (e.value - lo) / e.se if math.isfinite(lo) else math.inf
            z_hi = (hi - e.value) / e.se if math.isfinite(hi) else math.inf
        elif math.isfinite(e.se):                      # exact (se = 0)
            inside = lo <= e.value <= hi
            z_lo = z_hi = math.inf if inside else -math.inf
        else:
            z_lo = z_hi = math.nan
        zc = z_critical(e.dof)
        held.append(min(z_lo, z_hi) >= zc)
        failed.append(min(z_lo, z_hi) <= -zc)
        parts.append(_zs(min(z_lo, z_hi)))
    evidence = (f"z to the nearer bound = {', '.join(parts)} (z_c"
                f" {z_critical(min(e.dof for e in pts)):.2g}){gone}{_no_se(pts)}")
    if any(failed):
        return FAILS, evidence
    if all(held):
        return HOLDS, evidence
    return INCONCLUSIVE, evidence


def power_exponent(omega: np.ndarray, alpha: np.ndarray, alpha_se: np.ndarray | None = None,
                   *, label: str = "m", min_periods: int = 3) -> Estimate:
    """The exponent m of alpha = c omega^m (least squares in log-log) with its SE.

    Weighted by se(ln alpha) = alpha_se / alpha when every fitted alpha has a finite,
    positive SE (the SE then from the weights, times sqrt(chi^2/dof) when that exceeds 1);
    else unweighted, its SE from the residuals. Either way ``dof`` = n - 2: the SE is
    judged with the Student-t value whatever chi^2/dof is (one rule, so that a verdict
    does not jump with a noise fluctuation of chi^2/dof, and conservative where the
    Birge ratio estimated the SE from the residuals). Points with alpha NaN or <= 0 are
    left out; fewer than ``min_periods`` distinct omegas give NaN.
    """
    om = np.asarray(omega, dtype=float)
    al = np.asarray(alpha, dtype=float)
    ok = np.isfinite(al) & (al > 0) & np.isfinite(om) & (om > 0)
    if len(np.unique(om[ok])) < min_periods:
        return Estimate(label, math.nan)
    lx, ly = np.log(om[ok]), np.log(al[ok])
    n = int(ok.sum())
    se = None if alpha_se is None else np.asarray(alpha_se, dtype=float)[ok]
    if se is not None and np.all(np.isfinite(se)) and np.all(se > 0):
        w = (al[ok] / se) ** 2
        xm = float(np.sum(w * lx) / np.sum(w))
        ym = float(np.sum(w * ly) / np.sum(w))
        sxx = float(np.sum(w * (lx - xm) ** 2))
        m = float(np.sum(w * (lx - xm) * (ly - ym)) / sxx)
        resid = ly - (ym + m * (lx - xm))
        m_se = math.sqrt(1.0 / sxx)
        if n > 2:
            # the Birge ratio: inflated when the power law does not fit within the error
            # bars. The critical value is t_(n-2) whatever chi^2/dof is: switching between
            # z_c 2 (chi^2/dof <= 1) and Student-t (above), as model version 6 did, made
            # one claim fail with one seed (chi^2/dof 0.30) and be inconclusive with
            # another (2.0); treating the inflated SE as known (z_c 2) was too liberal:
            # the inflation is an estimate from n - 2 residuals.
            red = float(np.sum(w * resid ** 2)) / (n - 2)
            m_se *= math.sqrt(max(red, 1.0))
        return Estimate(label, m, m_se, "fit", float(n - 2))
    from floewave.results import power_law

    m, _, m_se, _ = power_law(om[ok], al[ok])
    return Estimate(label, float(m), float(m_se), "fit", float(n - 2))


