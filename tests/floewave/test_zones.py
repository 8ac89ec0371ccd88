"""The collision-zone width W_c and the compact-zone layout (docs/model.md §6, issue *trust*).

Hand-built gap profiles for every layout, the failure modes of the old rule (W_c = the
first pair below the threshold), and gap profiles measured on the paper's Fig. 2, 5 and 6
points (tests/data/measured_gaps.json).
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from floewave import ModelConfig
from floewave.results import LAYOUTS, compact_zones, fit_inverse, zone_fits

CFG = ModelConfig()
RULE = dict(gap_threshold=CFG.gap_threshold, min_pairs=CFG.compact_min_pairs,
            min_length=CFG.compact_min_length, bridge=CFG.compact_bridge,
            bridge_gap=CFG.compact_bridge_gap)
FIT = dict(min_floes=CFG.fit_min_floes, min_length=CFG.fit_min_length)
DATA = json.loads((Path(__file__).resolve().parents[1] / "data" / "measured_gaps.json").read_text())

COLL = 3e-3       # a colliding pair's mean gap [m]
COMP = -5e-5      # a compact pair's
MARG = 1.1e-4     # marginal: just above the 1e-4 m threshold


def chain(pattern, L_x=0.5, d_f=0.005):
    """x_mean, gap_mean (NaN-padded) of a chain whose pair i has the gap ``pattern[i]``
    (``.`` colliding, ``#`` compact, ``+`` marginal, ``o`` 0.2 mm, or a number)."""
    code = {".": COLL, "#": COMP, "+": MARG, "o": 2e-4}
    gaps = np.array([code[c] if isinstance(c, str) else c for c in pattern], dtype=float)
    x = L_x / 2 + np.concatenate([[0.0], np.cumsum(L_x + gaps)])
    return x, np.concatenate([gaps, [np.nan]])


def zones(pattern, L_x=0.5, **kw):
    x, g = chain(pattern, L_x)
    return x, compact_zones(x, g, L_x, **{**RULE, **kw})


def pair_x(x, i, L_x=0.5):
    return x[i] + L_x / 2


def test_edge_layout_the_papers():
    x, z = zones("." * 30 + "#" * 53)
    assert z.layout == "edge" and z.n_zones == 1
    assert z.W_c == pair_x(x, 30)
    assert z.compact_end == z.ice_extent == x[-1] + 0.25
    assert z.compact.sum() == 53 and not z.compact[:30].any()


def test_marginal_pairs_inside_compact_ice_do_not_split_it():
    """The measured case: two pairs at 0.103 and 0.110 mm inside compact ice that starts at
    15.9 m; the old rule was fine here but W_c hinged on single pairs elsewhere."""
    pattern = list("." * 31 + "#" * 25) + [1.03e-4, 1.10e-4] + list("#" * 25)
    x, z = zones(pattern)
    assert z.layout == "edge" and z.n_zones == 1 and z.W_c == pair_x(x, 31)
    assert z.compact[56] and z.compact[57]
    # three in a row are more than the bridge allows: two zones, patchy
    x, z3 = zones(list("." * 31 + "#" * 25) + [1.03e-4] * 3 + list("#" * 24))
    assert z3.layout == "patchy" and z3.n_zones == 2 and z3.W_c == z.W_c
    # a colliding pair (gap above compact_bridge_gap) is never bridged
    x, zc = zones(list("." * 31 + "#" * 25) + [COLL] + list("#" * 26))
    assert zc.n_zones == 2 and not zc.compact[56]


def test_isolated_compact_pairs_do_not_start_the_zone():
    """The old rule's failure: one pair below the threshold decided W_c."""
    x, z = zones("." * 10 + "#" + "." * 19 + "#" * 53)
    old = pair_x(x, 10)
    assert z.W_c == pair_x(x, 30) and z.W_c > old + 9
    assert z.layout == "edge" and not z.compact[10]


@pytest.mark.parametrize("L_x", [0.5, 3.0])
@pytest.mark.parametrize("lead", ["#+", "#++", "##+", "#+#+"])
def test_a_bridge_never_attaches_an_isolated_pair(L_x, lead):
    """Isolated compact pairs a marginal pair or two ahead of a zone are not bridged into
    it: W_c is where min_pairs compact pairs in a row begin (review finding: a 3 m chain's
    W_c moved from 18 to 9 m by one such pair)."""
    n = 13 if L_x == 3.0 else 83
    rest = n - 3 - len(lead) - 6
    x, z = zones("..." + lead + "#" * 6 + "." * 0 + "#" * rest, L_x=L_x)
    assert z.W_c == pair_x(x, 3 + len(lead), L_x)
    assert not z.compact[3:3 + len(lead)].any()


def test_no_compact_zone_gives_no_boundary():
    """A few compact pairs near the far end (the periods.toml ep T 1.5 case: a 3-floe
    'inner zone') or none at all: W_c is NaN, not a number that reads as a boundary."""
    for pattern in ("." * 83, "." * 79 + "#" * 2 + "..", "." * 77 + "o#+oo."):
        x, z = zones(pattern)
        assert z.layout == "none" and math.isnan(z.W_c) and math.isnan(z.compact_end)
        assert not z.compact.any()
    # the ice extends beyond the sheet when gaps open: 84 floes of 0.5 m, 42 m of ice
    assert z.ice_extent > 42.0 + 80 * 2e-4


def test_inverted_layout():
    """Compact from the ice edge, collisional further in (Fig. 5's 1.5 m ep point as
    measured before this change: compact at 0-20 m, collisional at 23-31 m)."""
    x, z = zones("#" * 13 + "." * 14, L_x=1.5)
    assert z.layout == "inverted" and z.W_c == 0.0      # no collisional zone at the edge
    assert z.compact_end == pair_x(x, 12, 1.5)
    x, z = zones(".." + "#" * 11 + "." * 14, L_x=1.5)    # a short one: still inverted
    assert z.layout == "inverted" and z.W_c == pair_x(x, 2, 1.5)


def test_compact_everywhere():
    """Compact from the first pair to the far end: no collisional zone, W_c = 0, every
    floe in the inner fit (a confined chain without gaps looks like this)."""
    x, z = zones("#" * 83)
    assert z.layout == "compact" and z.W_c == 0.0 and z.compact_end == z.ice_extent
    a0, alpha = 0.0125, 2e-3
    e, _, i, _ = zone_fits(x, 1 / (1 / a0 + alpha * x), a0, z, **FIT)
    assert math.isnan(e) and i == pytest.approx(alpha, rel=1e-9)


def test_patchy_layouts():
    x, z = zones("." * 5 + "#" * 13 + "." * 9, L_x=1.5)      # a compact band
    assert z.layout == "patchy" and z.W_c == pair_x(x, 5, 1.5)
    assert z.compact_end == pair_x(x, 17, 1.5)
    x, z = zones("." * 20 + "#" * 20 + "." * 10 + "#" * 33)    # two zones
    assert z.layout == "patchy" and z.n_zones == 2 and z.W_c == pair_x(x, 20)


def test_short_collisional_tail_at_the_far_end_is_not_a_zone():
    """Next to the far-end spring the last pairs may open (Fig. 5's 1.5 m ml point): a
    stretch shorter than a zone does not make the layout patchy."""
    x, z = zones("." * 9 + "#" * 16 + "..", L_x=1.5)
    assert z.layout == "edge" and z.compact_end == z.ice_extent
    x, z = zones("." * 9 + "#" * 15 + "...", L_x=1.5)          # 3 pairs, 4.5 m: a zone
    assert z.layout == "patchy"


def test_min_length_and_pairs_scale_with_floe_size():
    # 5 compact pairs of 0.5 m (2.5 m) are not sustained, 6 (3 m) are
    assert zones("." * 70 + "#" * 5 + "." * 8)[1].layout == "none"
    assert zones("." * 70 + "#" * 6 + "." * 7)[1].layout == "patchy"
    # 3 m floes: one pair is 3 m long but not 3 pairs
    assert zones("." * 10 + "###", L_x=3.0)[1].layout == "edge"
    assert zones("." * 11 + "##", L_x=3.0)[1].layout == "none"


def test_zone_fits_only_over_zones_long_enough():
    a0 = 0.0125
    x, z = zones("." * 30 + "#" * 53)
    alpha_e, alpha_i = 4e-3, 1e-3
    W = z.W_c
    inv = np.where(x < W, 1 / a0 + alpha_e * x, 1 / a0 + alpha_e * W + alpha_i * (x - W))
    a = 1 / inv
    e, re, i, ri = zone_fits(x, a, a0, z, **FIT)
    assert e == pytest.approx(alpha_e, rel=1e-9) and i == pytest.approx(alpha_i, rel=1e-9)
    # no compact zone: the edge fit is over the whole (collisional) ice, no inner fit
    x, zn = zones("." * 83)
    e, _, i, _ = zone_fits(x, 1 / (1 / a0 + alpha_e * x), a0, zn, **FIT)
    assert e == pytest.approx(alpha_e, rel=1e-9) and math.isnan(i)
    assert e == pytest.approx(fit_inverse(x, 1 / (1 / a0 + alpha_e * x), a0)[0])
    # inverted: nothing before the zone to fit
    x, zi = zones("#" * 13 + "." * 14, L_x=1.5)
    e, _, i, _ = zone_fits(x, 1 / (1 / a0 + alpha_i * x), a0, zi, **FIT)
    assert math.isnan(e) and i == pytest.approx(alpha_i, rel=1e-9)
    # a zone of 3 floes after W_c is not fitted, nor one shorter than fit_min_length
    x, z4 = zones("." * 6 + "#" * 3 + "." * 4, L_x=3.0)      # 3 pairs = 4 floes
    assert math.isnan(zone_fits(x, np.full(len(x), a0), a0, z4, **FIT)[2])
    x, z5 = zones("." * 20 + "#" * 16, L_x=0.2)             # 16 floes over 3 m
    assert not math.isnan(zone_fits(x, np.full(len(x), a0), a0, z5, **FIT)[2])
    assert math.isnan(zone_fits(x, np.full(len(x), a0), a0, z5, min_floes=5,
                                min_length=5.0)[2])


EXPECTED = [
    # (layout, W_c [m] or None, note)
    ("edge", 16.9, "ml eps 0.8: two marginal pairs (0.10-0.12 mm) inside compact ice"),
    ("none", None, "ep eps 0.2: one compact pair at 40.9 m (the old W_c) in colliding ice"),
    ("patchy", 9.0, "1.5 m ep T 1.4: a compact band, colliding ice beyond 27 m"),
    ("edge", 16.6, "1.5 m ml T 1.4: compact to the far end but for its last two pairs"),
    ("none", None, "3 m ml T 1.4: no compact pair (the old W_c: L_sheet)"),
    ("none", None, "ml T 1.8 a0 0.025: one compact pair at 39.9 m"),
]


@pytest.mark.parametrize("case, expected", list(zip(DATA, EXPECTED, strict=True)),
                         ids=[e[2][:24] for e in EXPECTED])
def test_measured_gap_profiles(case, expected):
    x = np.array(case["x_mean"])
    g = np.array([np.nan if v is None else v for v in case["gap_mean"]])
    z = compact_zones(x, g, case["L_x"], **RULE)
    layout, W_c, _ = expected
    assert z.layout == layout and z.layout in LAYOUTS
    if W_c is None:
        assert math.isnan(z.W_c)
    else:
        assert z.W_c == pytest.approx(W_c, abs=0.05)
    # the old rule (first pair below the threshold) for contrast: these differ where a
    # single pair decided it
    first = np.flatnonzero(g[:-1] < CFG.gap_threshold)
    if layout == "none" and first.size:
        assert x[first[0]] + case["L_x"] / 2 > 35.0
