"""``herman2019 check --seeds``: the paper's claims checked on independent ensembles, a
verdict reported only where the seeds agree.

Every stored number of an ensemble is a statistic of chaotic runs: another ``seed`` gives
other trajectories, and a claim decided at the edge of its rule can hold with one seed and
be inconclusive with another. With ``--seeds S1 S2 ...`` each shipped paper campaign is run
(or resumed) once per seed, its ``[base] seed`` set to S, into ``<stores>/seed<S>/``; the
checks of :mod:`herman2019.check` run on each set of stores, and the claim's verdict across
seeds is the common one when every seed gives it, else :data:`SEED_DEPENDENT`.
"""
from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from pathlib import Path

from herman2019.check import PaperReport, check_stores, default_configs
from herman2019.claims import PAPER_CAMPAIGNS
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE
from sweep.errors import ConfigError

__all__ = ["SEED_DEPENDENT", "seeded_configs", "across_seeds", "check_seeds",
           "format_seed_table"]

#: the verdict of a claim whose seeds disagree
SEED_DEPENDENT = "seed-dependent"

_SEED_LINE = re.compile(r"^seed\s*=\s*\d+\s*$", re.MULTILINE)


def seeded_configs(configs: Path, seed: int, out: Path) -> Path:
    """Write the paper campaigns' files with ``[base] seed = seed`` into ``out``; returns
    ``out``. A campaign file whose ``[base]`` has not exactly one ``seed = N`` line is a
    :class:`ConfigError` (the shipped files write every field out)."""
    out.mkdir(parents=True, exist_ok=True)
    for name in PAPER_CAMPAIGNS:
        path = configs / f"{name}.toml"
        if not path.is_file():
            raise ConfigError(f"{path}: no such campaign file (--configs)")
        text = path.read_text(encoding="utf-8")
        base, sep, rest = text.partition("\n[sweep]")
        if len(_SEED_LINE.findall(base)) != 1:
            raise ConfigError(f"{path}: [base] needs exactly one 'seed = N' line for --seeds")
        (out / f"{name}.toml").write_text(_SEED_LINE.sub(f"seed = {seed}", base) + sep + rest,
                                          encoding="utf-8")
    return out


def across_seeds(verdicts: Sequence[str]) -> str:
    """The verdict of a claim across seeds: the common one, else :data:`SEED_DEPENDENT`."""
    first = verdicts[0]
    return first if all(v == first for v in verdicts) else SEED_DEPENDENT


def check_seeds(stores: Path, seeds: Sequence[int], *, run: bool = False,
                configs: Path | None = None, compute: str | None = None,
                log: Callable[[str], None] | None = None) -> dict[int, PaperReport]:
    """:func:`herman2019.check.check_stores` on ``<stores>/seed<S>/`` for every seed S
    (with ``run``, the campaigns are first run with that seed)."""
    if len(set(seeds)) < 2:
        raise ConfigError(f"--seeds {' '.join(map(str, seeds))}: give at least two different"
                          " seeds")
    configs = Path(configs) if configs is not None else default_configs()
    reports = {}
    for seed in seeds:
        where = Path(stores) / f"seed{seed}"
        cfgs = seeded_configs(configs, seed, where / "configs") if run else None
        reports[seed] = check_stores(where, run=run, configs=cfgs, compute=compute, log=log)
    return reports


def format_seed_table(reports: dict[int, PaperReport]) -> str:
    """One row per claim: its verdict with every seed, and across the seeds."""
    seeds = list(reports)
    first = reports[seeds[0]].checks
    head = ("| # | claim (paper) | campaign: points | "
            + " | ".join(f"seed {s}" for s in seeds) + " | across seeds |")
    lines = [head, "|" + "---|" * (4 + len(seeds))]
    counts = {HOLDS: 0, FAILS: 0, INCONCLUSIVE: 0, SEED_DEPENDENT: 0}
    for i, check in enumerate(first):
        verdicts = [reports[s].checks[i].verdict for s in seeds]
        both = across_seeds(verdicts)
        counts[both] += 1
        lines.append(f"| {i + 1} | {check.claim} ({check.source}) | {check.campaign}:"
                     f" {check.points} | " + " | ".join(verdicts) + f" | {both} |")
    lines.append("")
    lines.append(f"across seeds {', '.join(map(str, seeds))}: {counts[HOLDS]} hold,"
                 f" {counts[FAILS]} fail, {counts[INCONCLUSIVE]} inconclusive,"
                 f" {counts[SEED_DEPENDENT]} {SEED_DEPENDENT} (a verdict stands only where"
                 " every seed gives it)")
    return "\n".join(lines)
