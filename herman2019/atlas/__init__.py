"""The atlas of the paper's grid: what the whole campaign says, from its shipped table.

    herman2019 atlas [results/herman2019] [--out docs] [--bootstrap 200]

Reads the per-point table (``sweep.load`` of ``results/herman2019``: the shards present)
and writes ``OUT/atlas.md`` with its figures in ``OUT/atlas/``:

- headlines, computed from what follows;
- the points read: the converged ones (``not_converged`` counted and left out), their
  standard errors calibrated (:func:`herman2019.factors.calibrated`) when the table is
  of the calibration's model version;
- where a compact zone forms: the share of points whose layout is not ``none`` by each
  parameter, over the pairs T x a0, C_sd x eps and d_f x L_x, and the layouts;
- the collisional zone under both rules (layout and gap), and W_c over every point (the
  ice extent where no compact zone forms), :mod:`.edge`;
- near the edge: a(x)/a0 at 2, 5 and 10 m from the profiles beside the table
  (``profiles/*.nc``), :mod:`.edge`;
- W_c, alpha_inner / alpha_c, alpha_all and a_end / a0: the marginal mean over the grid at
  each value of each of the 7 parameters, and a variance decomposition (the share of the
  variance over the grid that the 7 main effects explain, and what each pairwise
  interaction adds: least squares with categorical factors);
- a power law for W_c in physically motivated groups (wave steepness a0 k, drag time over
  period tau_d / T, eps; ``floewave.transient.drag_time``), with its residuals;
- the paper's trend statements of §4.2 and §5 tested on every pair of grid points that
  differ in one parameter alone (``paired``), with where the contradictions concentrate;
- the grid's cost: the wall-time distribution and why the slowest 1 % are slow;
- the three dispersion relations side by side.

Error bars. A point's values are ensemble means with jackknife standard errors (stochastic:
docs/convergence.md); a marginal mean over n points has the stochastic SE sqrt(sum se_i^2)
/ n. While only some shards are present the points are a uniform random sample of the
grid (a shard is the points whose hash is K mod 8), so a mean also has a sampling error:
the SE quoted is the larger of the two, the sampling one by a bootstrap over points
(``--bootstrap`` draws, seed 0). Every number in the page is printed by this command.

:mod:`.stats` (the statistics and the paired test), :mod:`.page` (the page and its
opening), :mod:`.grid`, :mod:`.trends` and :mod:`.summary` (the sections, in order).
"""
from __future__ import annotations

from pathlib import Path

from herman2019.atlas.edge import near_edge, zone_rules
from herman2019.atlas.grid import compact_zones, marginal_effects, variance, wc_law
from herman2019.atlas.page import start_page
from herman2019.atlas.stats import CHANCE, REVERSAL, paired, verdict, where_contra
from herman2019.atlas.summary import cost, dispersions, headlines
from herman2019.atlas.trends import trend_statements

__all__ = ["make_atlas", "COMMAND", "paired", "verdict", "where_contra", "CHANCE", "REVERSAL"]

#: The command named on the page as the one that made it.
COMMAND = "herman2019 atlas"

#: The sections in the page's order (each reads what the earlier ones left on the page).
SECTIONS = (compact_zones, zone_rules, marginal_effects, variance, wc_law, near_edge,
            trend_statements, cost, dispersions, headlines)


def make_atlas(table: str | Path, out: str | Path, *, bootstrap: int = 200,
               command: str = COMMAND) -> str:
    """Write ``out/atlas.md`` and its figures in ``out/atlas/`` from the per-point table
    ``table`` (a shipped table's directory, a store, any file ``sweep.load`` reads), with
    ``bootstrap`` draws for a mean's sampling error; returns the page's text."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import sweep

    out = Path(out)
    df = sweep.load(table)
    profiles = None
    folder = Path(table) / "profiles"
    if folder.is_dir() and any(folder.glob("*.nc")):
        profiles = sweep.load_profiles(folder)
    figdir = out / "atlas"
    figdir.mkdir(parents=True, exist_ok=True)
    root = Path(__file__).resolve().parents[2]
    try:
        source = str(Path(table).resolve().relative_to(root))
    except ValueError:
        source = str(table)
    if source != "results/herman2019" and command == COMMAND:
        command = f"{COMMAND} {source}"
    page = start_page(df, figdir, bootstrap, plt, command=command, profiles=profiles,
                      source=source)
    for section in SECTIONS:
        section(page)
    text = "\n".join(page.lines)
    (out / "atlas.md").write_text(text + "\n")
    return text
