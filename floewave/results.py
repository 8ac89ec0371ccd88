"""Per-point results (docs/model.md §6): profiles, collision-zone width and attenuation fits."""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import outputs

__all__ = ["PointResult", "PROFILE_FIELDS", "SCALAR_FIELDS", "REPLICA_FIELDS", "LAYOUTS", "Zones",
           "point_result_type", "compact_zones", "fit_zone", "zone_fits", "fit_inverse",
           "fit_exponential", "power_law", "power_law_weighted"]

#: Per-floe (length N_f) or per-pair (length N_f - 1, padded to N_f with NaN) profiles.
PROFILE_FIELDS = tuple(o.name for o in outputs.profiles())
#: Scalar results and diagnostics.
SCALAR_FIELDS = tuple(o.name for o in outputs.scalars())
#: Per-replica results: (R,) scalars per replica and (R, N_f) profiles per replica.
REPLICA_FIELDS = tuple(o.name for o in outputs.replica_outputs())

STATUSES = ("converged", "converged_noisy", "not_converged")

_DOC = """Everything one model point reports: one field per :data:`floewave.outputs.OUTPUTS`
entry (its meaning, unit and dims are declared there), and ``a0`` [m] the incident
amplitude of the configuration (for :attr:`a_rel`).

Profiles are numpy arrays of length N_f (per-pair quantities have N_f - 1 values and a
trailing NaN so every profile has the same length); ``residual_history`` holds
max_i |a_new-a|/a per iteration. The collision-zone scalars come from
:func:`compact_zones` (layouts :data:`LAYOUTS`); the ensemble's estimates and standard
errors are described in :mod:`floewave.outputs`.

Fields:

"""


def _array_default(dims: tuple[str, ...]) -> Callable[[], np.ndarray]:
    return lambda: np.zeros((0,) * len(dims))


def point_result_type(declared: tuple[outputs.Output, ...] = outputs.OUTPUTS,
                      name: str = "PointResult") -> type:
    """The result dataclass of ``declared`` outputs: their fields in their order (the
    required ones, then ``a0``, then those with a default), :attr:`a_rel` and
    :meth:`to_dict`."""
    required: list[Any] = []
    optional: list[Any] = []
    for o in declared:
        kind = "np.ndarray" if o.dims else o.kind
        if o.default == outputs.REQUIRED:
            required.append((o.name, kind))
        elif o.dims:
            optional.append((o.name, kind, field(default_factory=_array_default(o.dims))))
        else:
            optional.append((o.name, kind, field(default=o.default)))

    def a_rel(self: Any) -> np.ndarray:
        """a / a0 per floe."""
        return self.a / self.a0

    def to_dict(self: Any) -> dict[str, Any]:
        """All fields; arrays stay numpy arrays."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    lines = [f"{o.name} [{o.unit or 'text'}]{' (' + ', '.join(o.dims) + ')' if o.dims else ''}:"
             f" {o.long_name}" for o in declared]
    cls = dataclasses.make_dataclass(
        name, [*required, ("a0", "float"), *optional],
        namespace={"a_rel": property(a_rel), "to_dict": to_dict,
                   "__doc__": _DOC + "\n".join(lines), "__module__": __name__})
    cls.__qualname__ = name
    return cls


#: The result of :func:`floewave.run_point` (built from :data:`floewave.outputs.OUTPUTS`).
PointResult = point_result_type()


#: Layouts of the compact zone (``PointResult.compact_zone``), see :func:`compact_zones`.
LAYOUTS = tuple(outputs.LAYOUT_MEANINGS)  # ("edge", "compact", "inverted", "patchy", "none")


@dataclass(frozen=True)
class Zones:
    """Where the ice is compact: the result of :func:`compact_zones`.

    layout : ``"edge"`` (the paper's: collisional at the ice edge, one compact zone from
        W_c to the far end), ``"compact"`` (compact from the first pair to the far end: no
        collisional zone, W_c = 0), ``"inverted"`` (compact from the ice edge, collisional
        further in to the far end), ``"patchy"`` (anything else with a compact zone: a
        compact band with collisional ice on both sides, or several compact zones),
        ``"none"`` (no sustained compact zone: the whole ice is collisional).
    W_c : [m] distance from the ice edge to the start of the first compact zone (the
        paper's dot: the right end of the first compact pair's left floe; 0 if the first
        pair is compact); NaN for ``"none"``.
    compact_end : [m] where that compact zone ends (the ice extent when it reaches the far
        end); NaN for ``"none"``.
    ice_extent : [m] the far end of the ice, last floe's mean centre + L_x / 2.
    compact : bool per pair: in a sustained compact zone (bridged pairs included).
    first : (i0, i1) pair indices [i0, i1) of the first compact zone, (0, 0) if none.
    n_zones : number of sustained compact zones.
    """

    layout: str
    W_c: float
    compact_end: float
    ice_extent: float
    compact: np.ndarray
    first: tuple[int, int]
    n_zones: int


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs [i0, i1) of True in ``flags``."""
    f = np.concatenate([[False], np.asarray(flags, dtype=bool), [False]])
    d = np.flatnonzero(f[1:] != f[:-1])
    return [(int(a), int(b)) for a, b in zip(d[::2], d[1::2], strict=True)]


def compact_zones(x_mean: np.ndarray, gap_mean: np.ndarray, L_x: float, *,
                  gap_threshold: float, min_pairs: int, min_length: float, bridge: int,
                  bridge_gap: float) -> Zones:
    """The compact zone(s) of a chain from its phase-averaged gaps (docs/model.md §6).

    The paper's dots (Figs. 2, 3a) mark where the phase-averaged floe-floe distance drops
    below ``gap_threshold`` (1e-4 m): the boundary between the collisional zone at the ice
    edge and the compact zone downwave. A single pair must not decide that boundary: in
    the compact zone the mean gaps scatter around the threshold, and isolated compact
    pairs occur inside collisional ice. So, per pair (i, i+1), sitting at
    ``x_mean[i] + L_x / 2``:

    1. a pair is compact if its mean gap is below ``gap_threshold``;
    2. bridging: a run of at most ``bridge`` non-compact pairs with compact pairs on both
       sides, each with a mean gap below ``bridge_gap`` (marginal, not colliding), counts
       as compact — but a bridged zone must begin and end with ``min_pairs`` compact pairs
       in a row, so a bridge never attaches an isolated compact pair to a zone;
    3. a run of compact pairs is a compact *zone* only if it is sustained: at least
       ``min_pairs`` pairs spanning at least ``min_length`` metres (L_x per pair) —
       shorter runs are isolated compact pairs in collisional ice;
    4. W_c is the position of the first pair of the first compact zone;
    5. the layout (:class:`Zones`): the non-compact stretches before the first zone (at
       the ice edge) and after the last (at the far end) count as collisional zones only
       when they are sustained by the same rule — a stretch shorter than that next to
       the far-end spring (the "beach") does not make the layout patchy.
    """
    x = np.asarray(x_mean, dtype=float)
    n_pairs = max(len(x) - 1, 0)
    gaps = np.asarray(gap_mean, dtype=float)[:n_pairs]
    ice_extent = float(x[-1] + 0.5 * L_x) if len(x) else math.nan
    with np.errstate(invalid="ignore"):
        compact = gaps < gap_threshold
        marginal = gaps < bridge_gap

    def sustained(i0: int, i1: int) -> bool:
        return i1 - i0 >= min_pairs and (i1 - i0) * L_x >= min_length - 1e-9

    # 2. bridge short marginal interruptions between runs of compact pairs; a bridged zone
    # must begin and end with a run of at least min_pairs compact pairs, so that a bridge
    # never attaches an isolated compact pair to a zone (and so moves W_c)
    groups: list[list[tuple[int, int]]] = []
    for run in _runs(compact):
        prev = groups[-1][-1] if groups else None
        if (prev is not None and bridge > 0 and run[0] - prev[1] <= bridge
                and marginal[prev[1]:run[0]].all()):
            groups[-1].append(run)
        else:
            groups.append([run])
    # 3. keep the sustained runs only
    zones = []
    for g in groups:
        while g and g[0][1] - g[0][0] < min_pairs:
            g = g[1:]
        while g and g[-1][1] - g[-1][0] < min_pairs:
            g = g[:-1]
        if g and sustained(g[0][0], g[-1][1]):
            zones.append((g[0][0], g[-1][1]))
    keep = np.zeros(n_pairs, dtype=bool)
    for i0, i1 in zones:
        keep[i0:i1] = True
    if not zones:
        return Zones("none", math.nan, math.nan, ice_extent, keep, (0, 0), 0)
    i0, i1 = zones[0]
    lead = sustained(0, i0)                        # a collisional zone at the ice edge
    tail = sustained(zones[-1][1], n_pairs)        # a collisional zone at the far end
    # W_c: the right end of floe i0; 0 when the first pair is already compact
    W_c = float(x[i0] + 0.5 * L_x) if i0 > 0 else 0.0
    end = ice_extent if (len(zones) == 1 and not tail) else float(x[i1 - 1] + 0.5 * L_x)
    if len(zones) > 1 or (lead and tail):
        layout = "patchy"
    elif tail:
        layout = "inverted"
    elif i0 == 0:
        layout = "compact"
    else:
        layout = "edge"
    return Zones(layout, W_c, end, ice_extent, keep, (i0, i1), len(zones))


def zone_fits(x: np.ndarray, a: np.ndarray, a0: float, zones: Zones, *, min_floes: int,
              min_length: float) -> tuple[float, float, float, float]:
    """(alpha_edge, its residual, alpha_inner, its residual): 1/a fits of the collisional
    zone at the ice edge and of the compact zone (docs/model.md §6, the paper's dashed lines).

    Edge zone: the floes whose centres lie before W_c (floes 0 ... i0 for the first
    compact zone's pairs [i0, i1); W_c is the right end of floe i0); with no compact zone,
    every floe (the whole ice is collisional). Inner zone: the floes after W_c in the first
    compact zone (floes i0 + 1 ... i1); none without a compact zone. A zone is
    fitted only if it has at least ``min_floes`` floes spanning at least ``min_length``
    metres (centre to centre); otherwise NaN.
    """
    nan = (math.nan, math.nan)

    def fit(sel: np.ndarray) -> tuple[float, float]:
        if sel.sum() < max(min_floes, 3):
            return nan
        xs = x[sel]
        if xs.max() - xs.min() < min_length - 1e-9:
            return nan
        return fit_inverse(xs, a[sel], a0)

    n = len(x)
    if zones.layout == "none":
        return (*fit(np.ones(n, dtype=bool)), *nan)
    i0, i1 = zones.first
    edge = np.zeros(n, dtype=bool)
    inner = np.zeros(n, dtype=bool)
    if zones.W_c > 0:
        edge[:i0 + 1] = True        # centres before W_c = x[i0] + L_x / 2
        inner[i0 + 1:i1 + 1] = True  # the right floes of the zone's pairs
    else:
        inner[:i1 + 1] = True       # compact from the first floe (W_c = 0): no edge zone
    return (*fit(edge), *fit(inner))


def fit_zone(x: np.ndarray, L_x: float, layout: str, W_c: float, end: float,
             ice_extent: float) -> Zones:
    """A :class:`Zones` for fitting from an ensemble's mean bounds: the compact zone runs
    from the pair nearest W_c to the pair nearest its end (pairs sit at x_i + L_x / 2)."""
    n = len(x)
    keep = np.zeros(max(n - 1, 0), dtype=bool)
    if layout == "none" or not math.isfinite(W_c):
        return Zones("none", math.nan, math.nan, ice_extent, keep, (0, 0), 0)
    right = x[:-1] + 0.5 * L_x
    i0 = 0 if W_c <= 0 else int(np.argmin(np.abs(right - W_c)))
    i1 = n - 1 if end >= ice_extent - 1e-9 else int(np.argmin(np.abs(right - end))) + 1
    i1 = max(i1, i0 + 1)
    keep[i0:i1] = True
    return Zones(layout, W_c, end, ice_extent, keep, (i0, i1), 1)


def _linfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    A = np.vstack([x, np.ones_like(x)]).T
    (slope, intercept), *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(slope), float(intercept), slope * x + intercept


def power_law(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares power law y = c x^m in log-log: (m, c, standard error of m, RMS of
    ln y - fit). The standard error is NaN with fewer than 3 points. Used for alpha(omega)
    (the paper's m): :func:`floewave.figures.fit_power_law`, :func:`sweep.alpha_omega`."""
    lx, ly = np.log(np.asarray(x, dtype=float)), np.log(np.asarray(y, dtype=float))
    m, lc, fit = _linfit(lx, ly)
    resid = ly - fit
    n = len(lx)
    sxx = float(((lx - lx.mean()) ** 2).sum())
    m_se = math.sqrt(float(resid @ resid) / (n - 2) / sxx) if n > 2 and sxx > 0 else math.nan
    return m, math.exp(lc), m_se, float(np.sqrt(np.mean(resid**2)))


def power_law_weighted(x: np.ndarray, y: np.ndarray,
                       y_se: np.ndarray) -> tuple[float, float, float, float]:
    """Weighted least-squares power law y = c x^m in log-log, each point weighted by
    1 / sigma_i^2 with sigma_i = y_se_i / y_i (the standard error of ln y_i, first order):
    (m, c, standard error of m, chi^2 per degree of freedom). The standard error of m is
    the weighted fit's, multiplied by sqrt(chi^2 / dof) when that exceeds 1 (scatter
    beyond the error bars: the law does not describe the points to within them), so it is
    never smaller than the error bars alone imply. Needs >= 2 points (the standard error
    and chi^2 >= 3); NaN otherwise."""
    x, y, se = (np.asarray(v, dtype=float) for v in (x, y, y_se))
    n = len(x)
    if n < 2:
        return math.nan, math.nan, math.nan, math.nan
    lx, ly = np.log(x), np.log(y)
    w = (y / se) ** 2
    W = w.sum()
    mx, my = (w * lx).sum() / W, (w * ly).sum() / W
    sxx = float((w * (lx - mx) ** 2).sum())
    if sxx <= 0:
        return math.nan, math.nan, math.nan, math.nan
    m = float((w * (lx - mx) * (ly - my)).sum() / sxx)
    lc = my - m * mx
    if n < 3:
        return m, math.exp(lc), math.nan, math.nan
    chi2 = float((w * (ly - lc - m * lx) ** 2).sum()) / (n - 2)
    return m, math.exp(lc), math.sqrt(max(chi2, 1.0) / sxx), chi2


def fit_inverse(x: np.ndarray, a: np.ndarray, a0: float) -> tuple[float, float]:
    """Slope alpha [m^-2] of 1/a = c + alpha x (free intercept) and the RMS misfit.

    The misfit is RMS((a_fit - a) / a0) over the fitted floes, the same measure as
    :func:`fit_exponential` so the two laws can be compared. NaN with < 3 floes.
    """
    ok = a > 0
    if ok.sum() < 3:
        return float("nan"), float("nan")
    slope, _, fit = _linfit(x[ok], 1.0 / a[ok])
    with np.errstate(divide="ignore"):
        resid = np.sqrt(np.mean(((1.0 / fit) - a[ok]) ** 2)) / a0
    return slope, float(resid)


def fit_exponential(x: np.ndarray, a: np.ndarray, a0: float) -> tuple[float, float]:
    """Rate alpha_exp [m^-1] of ln a = c - alpha_exp x and RMS((a_fit - a) / a0)."""
    ok = a > 0
    if ok.sum() < 3:
        return float("nan"), float("nan")
    slope, _, fit = _linfit(x[ok], np.log(a[ok]))
    resid = np.sqrt(np.mean((np.exp(fit) - a[ok]) ** 2)) / a0
    return -slope, float(resid)
