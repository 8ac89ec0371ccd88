"""The measurements behind the compact-zone rule's defaults (floewave.results.compact_zones).

    herman2019 numbers --out paper                    # the paper-figure stores (or any)
    python benchmarks/zone_rule.py paper/fig2.h5 paper/fig5.h5 paper/fig6a.h5 \
        paper/fig6b.h5 paper/periods.h5

From the stored mean-gap profiles of every point, with the raw threshold rule (a pair is
compact if its phase-averaged gap is below gap_threshold = 0.1 mm), prints:

- interruptions: runs of non-compact pairs with compact pairs on both sides — their length
  in pairs and largest gap (these decide ``compact_bridge`` and ``compact_bridge_gap``);
- the transition: the gaps of the four pairs before the first sustained zone (what a bridge
  must *not* swallow);
- the zones the default rule finds (bridges included) and the compact runs it leaves out:
  pairs and metres, and whether they reach the far end (``compact_min_pairs``,
  ``compact_min_length``);
- the layouts the default rule gives, with W_c.
"""
from __future__ import annotations

import sys
from collections import Counter

import numpy as np

import sweep
from floewave import ModelConfig
from floewave.collision_stats import zone_of
from floewave.results import _runs
from sweep.analysis.stats import RESULT_STATUSES


def main(paths: list[str]) -> int:
    cfg = ModelConfig()
    thr = cfg.gap_threshold
    interruptions, transitions, runs, layouts = [], [], [], Counter()
    for path in paths:
        df = sweep.load(path)
        for _, row in df[df["status"].isin(RESULT_STATUSES)].iterrows():
            p = sweep.load_profile(path, row["hash"])
            x, g = p["x_mean"].values, p["gap_mean"].values
            gaps = g[:-1]
            compact = gaps < thr
            for i0, i1 in _runs(~compact):
                if i0 > 0 and i1 < len(gaps):
                    interruptions.append((i1 - i0, float(gaps[i0:i1].max())))
            z = zone_of(cfg.replace(L_x=float(row["L_x"])), x, g)
            # the rule's own result: zones (bridges included) and the raw compact runs it
            # left out
            for i0, i1 in _runs(z.compact):
                runs.append((i1 - i0, (i1 - i0) * row["L_x"], i1 == len(gaps), True))
            for i0, i1 in _runs(compact & ~z.compact):
                runs.append((i1 - i0, (i1 - i0) * row["L_x"], i1 == len(gaps), False))
            if z.layout != "none":
                i0 = z.first[0]
                transitions.append(np.round(gaps[max(i0 - 4, 0):i0] * 1e3, 3).tolist())
            layouts[z.layout] += 1
    print(f"points: {sum(layouts.values())}; defaults: gap_threshold {thr * 1e3:g} mm,"
          f" compact_bridge {cfg.compact_bridge}, compact_bridge_gap"
          f" {cfg.compact_bridge_gap * 1e3:g} mm, compact_min_pairs {cfg.compact_min_pairs},"
          f" compact_min_length {cfg.compact_min_length:g} m")
    print("interruptions inside compact ice (pairs, largest gap [mm]):",
          sorted((n, round(v * 1e3, 3)) for n, v in interruptions))
    print("the four pairs before each zone [mm]:", transitions)
    iso = sorted((n, m) for n, m, _, zone in runs if not zone)
    zones = sorted((n, m, end) for n, m, end, zone in runs if zone)
    print("compact runs left out of the zones (pairs, m):", iso)
    print("zones (pairs, m, reaches the far end):", zones)
    print("layouts:", dict(layouts))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
