"""``herman2019 check --settle``: every claim's verdict settled by pooling independent
seeds, looked at group-sequentially.

A claim that is inconclusive, or that holds with one seed and not another, is usually one
whose error bar is too wide for its margin. Settling buys precision where it is needed:

1. **Seeds.** The seeds are a campaign dimension: each paper campaign is one campaign with
   ``[sweep] seed = [...]`` and one store ``<stores>/<name>.h5``, run by sweep's one
   executor and grown by ``--extend`` as a look adds seeds
   (:func:`herman2019.seeds.run_seeds`, as ``--seeds`` does). A seed is an independent
   ensemble of the same points, the same cost again, so pooling S seeds divides the SE by
   sqrt(S) at S times the cost (``benchmarks/settle_cost.py`` compares more replicas and
   longer averaging). The stores resume: a point already stored is never recomputed.
2. **Pooling.** The checks are run on each seed's rows of the stores
   (:func:`herman2019.check.check_stores` with ``seed``), and every estimate a rule reads
   is recorded (:func:`herman2019.estimates.observing`). The pooled table is the checks run
   once more, each rule reading the estimates pooled over the seeds (:func:`pool`): the
   mean of the seeds' values, with the SE of that mean: sqrt(sum se_s^2) / S from the
   seeds' own error bars (replicas, profiles, fits), or, for a quantity whose error bar is
   a floor (no stored SE), the seeds' spread sd / sqrt(S) with S - 1 degrees of freedom.
   The spread also bounds a stated SE from below: where sd / sqrt(S) is larger, it is
   used (S - 1 dof). So an error bar that is too small (some are: :func:`calibration`)
   cannot decide a row. Text in the evidence that is not a rule's (notes, detail) is the
   first seed's.
3. **Looks.** The seeds are added in looks (:data:`FIRST_LOOK` = 4, 8, 16, ... up to
   ``max_seeds``, 4 seeds at the first look so that the spread exists); at look k
   every rule reads its z's against the boundary c_k of :mod:`herman2019.sequential`
   (Pocock-type alpha spending, one-sided alpha = 2.28 % per z: the one-look rule's rate).
   A row is decided at the first look where it holds or fails, and keeps that verdict;
   only the campaigns of undecided rows get the next look's seeds. A row still undecided
   at the last look (or one no seed can change: an analytic value) is inconclusive.
4. **The resolution floor** (``floor``, ``--floor M``; off by default). A chain of a / a0
   whose undecided steps are all resolved to lie within +-M (|step| + z_c SE at most M)
   gets no more seeds (:func:`below_floor`): the settling stops buying the sign of a
   difference smaller than M. It stays inconclusive, with that reason. Stopping for
   futility never makes a verdict, so it cannot raise the false-verdict rate. It does
   change what a row can say: the chain rule reads signs, so a row whose reversal below M
   was decided at an early look (as #10 and #37 are) fails, while one the floor stopped
   stays inconclusive. So the shipped table runs without it.

Seeds ``first_seed``, ``first_seed + 1``, ... are pooled (``--first-seed``): a settling on
fresh seeds is independent of one already run (the uniform campaign's replica 0 aside, the
same chain for every seed). ``jobs`` > 1 runs a look's campaigns with ``sweep run`` under
``mpiexec``, ``jobs`` workers (a point's result does not depend on who runs it).

The error bars being pooled must be honest for the rate to hold: :func:`calibration`
compares the seeds' spread with their stated SEs over every pooled estimate.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from herman2019.check import campaign_files, check_stores, default_configs, load_tables
from herman2019.claims import PAPER_CAMPAIGNS
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE, critical, observing, z_critical
from herman2019.points import NO_EFFECT, Check
from herman2019.pooling import (
    EMPIRICAL_MIN,
    Pooler,
    Recorder,
    calibration,
    campaigns_of,
    widening,
)
from herman2019.seeds import run_seeds
from herman2019.sequential import boundaries
from sweep.errors import ConfigError

__all__ = ["FIRST_LOOK", "RESOLUTION_FLOOR", "Settled", "SettleReport", "below_floor",
           "looks_for", "pooled_checks", "settle", "stored_cost"]

#: Seeds pooled at the first look: enough for the spread to check the stated SEs.
FIRST_LOOK = EMPIRICAL_MIN


#: The resolution floor [a0] of ``--floor`` (off by default): 1 % of a0, the table's "no
#: visible effect".
RESOLUTION_FLOOR = NO_EFFECT
#: The largest seed a campaign takes (``[base] seed`` is a 63-bit integer).
MAX_SEED = 2 ** 63 - 1


def open_steps(check: Check, c: float) -> list[tuple[float, float, str, str, float]]:
    """The consecutive steps (difference, SE, labels, the critical |z| the rule reads
    it with at boundary ``c``: Student-t where an SE has finite dof) between a chain
    row's estimates with a value (as the rule takes them), that the rule leaves
    undecided: |z| below that critical value, or no SE."""
    est = [e for e in check.estimates if math.isfinite(e.value)]
    out = []
    with critical(c):
        for a, b in zip(est[:-1], est[1:], strict=False):
            d, se = b.value - a.value, math.hypot(a.se, b.se)
            zc = z_critical(min(a.dof, b.dof))
            if not (se > 0 and abs(d) / se >= zc):        # a NaN SE leaves it open
                out.append((d, se, a.label, b.label, zc))
    return out


def below_floor(check: Check, c: float, floor: float = RESOLUTION_FLOOR) -> bool:
    """Whether an undecided chain of a / a0 (``/a0`` in its quantity) has every undecided
    step (:func:`open_steps`) inside +-``floor``: |d| + z_c SE at most ``floor``, z_c the
    critical value its rule reads the step with (a step with no SE is never inside)."""
    if check.verdict != INCONCLUSIVE or not check.rule.startswith("chain") \
            or "/a0" not in check.quantity:
        return False
    steps = open_steps(check, c)
    return bool(steps) and all(abs(d) + zc * se <= floor for d, se, _, _, zc in steps)


def looks_for(max_seeds: int) -> tuple[int, ...]:
    """The looks' seed counts: :data:`FIRST_LOOK`, then doubling up to ``max_seeds``."""
    looks = [FIRST_LOOK]
    while looks[-1] < max_seeds:
        looks.append(looks[-1] * 2)
    if looks[-1] != max_seeds:
        raise ConfigError(f"--max-seeds {max_seeds}: {FIRST_LOOK} times a power of 2 (the"
                          f" looks double the seeds: {FIRST_LOOK}, {2 * FIRST_LOOK}, ...)")
    return tuple(looks)


def _tables(stores: Path) -> dict[str, Any]:
    return load_tables({name: stores / f"{name}.h5" for name in PAPER_CAMPAIGNS})


def _has_rows(tables: dict[str, Any], seed: int) -> bool:
    return any(hasattr(df, "columns") and "seed" in df and bool((df["seed"] == seed).any())
               for df in tables.values())


def pooled_checks(stores: Path, seeds: Sequence[int], z: float,
                  recorded: dict[int, Recorder], widen: dict[tuple, float] | None = None
                  ) -> tuple[list[Check], list[int]]:
    """The checks on each seed's rows of ``<stores>/<name>.h5`` pooled over ``seeds``
    (each seed's :class:`Recorder` in ``recorded``, made here if missing) and read against
    ``z``; with the number of seeds pooled per row."""
    tables = _tables(stores)
    for s in seeds:
        if s not in recorded:
            rec = Recorder()
            if _has_rows(tables, s) or s == seeds[0]:   # the carrier's absence is an error
                with observing(rec):
                    report = check_stores(stores, seed=s, tables=tables)
                rec.problems = {name: p for name, p in report.problems.items()
                                if not p.startswith("no store")}
            recorded[s] = rec
    pooler = Pooler([recorded[s] for s in seeds], widen)
    with observing(pooler), critical(z):
        report = check_stores(stores, seed=seeds[0], tables=tables)
    return report.checks, pooler.used


@dataclass
class Settled:
    """One row of the settled table: its pooled check at the look that decided it (or the
    last), the look (1-based), the seeds pooled and the boundary read against."""

    check: Check
    look: int
    seeds: int
    boundary: float
    extendable: bool = True
    audited: str = ""
    audited_look: int = 0
    #: stopped at the resolution floor (:func:`below_floor`)
    floored: bool = False


@dataclass
class SettleReport:
    rows: list[Settled]
    looks: tuple[int, ...]
    boundaries: tuple[float, ...]
    seeds: tuple[int, ...]
    runs: list[dict[str, Any]] = field(default_factory=list)
    calibration: dict[str, float] = field(default_factory=dict)
    stored: dict[str, float] = field(default_factory=dict)
    #: "seed S: campaign" -> a store that exists but cannot be read (exit status 3)
    problems: dict[str, str] = field(default_factory=dict)
    #: MPI workers that ran the seeds (``jobs``; 1: in-process)
    jobs: int = 1
    #: the settling's wall time [s], running and reading
    elapsed_s: float = 0.0
    #: the resolution floor [a0] in force (None: off)
    floor: float | None = None

    @property
    def pooled_up_to(self) -> int:
        """The last seed any row pooled."""
        return self.seeds[max((r.seeds for r in self.rows), default=1) - 1]

    def counts(self, audited: bool = False) -> dict[str, int]:
        return {v: sum((r.audited if audited else r.check.verdict) == v for r in self.rows)
                for v in (HOLDS, FAILS, INCONCLUSIVE)}

    def cost(self) -> dict[str, float]:
        """Points run and their CPU [s] in this invocation (seed stores that were complete
        cost nothing), and what the table rests on: the points in the pooled seeds' stores
        and their summed ``wall_time`` (one core each)."""
        return {"points_added": sum(r["points"] for r in self.runs),
                "cpu_s": sum(r["cpu_s"] for r in self.runs),
                "wall_s": sum(r["wall_s"] for r in self.runs),
                "elapsed_s": round(self.elapsed_s), **self.stored}


def _extendable(check: Check) -> bool:
    """Whether more seeds can move the row: not an analytic value, and on a campaign."""
    return bool(campaigns_of(check)) and not (
        check.estimates and all(e.source == "exact" for e in check.estimates))


def settle(stores: str | Path, *, max_seeds: int = 64, first_seed: int = 0,
           run: bool = False, configs: str | Path | None = None, compute: str | None = None,
           log: Callable[[str], None] | None = None, jobs: int = 1,
           floor: float | None = None) -> SettleReport:
    """Settle every row (the module docstring). ``run``: run (or resume) the seeds'
    campaigns as the looks need them; without it only stores already there are read. A
    row is read at a look only if every seed of that look has its stores; else it stops at
    its last look (undecided there, if it was)."""
    started = time.monotonic()
    stores = Path(stores)
    configs = Path(configs) if configs is not None else default_configs()
    looks = looks_for(max_seeds)
    if not 0 <= first_seed <= MAX_SEED - looks[-1] + 1:
        raise ConfigError(f"--first-seed {first_seed}: the seeds {first_seed} to"
                          f" {first_seed + looks[-1] - 1} must lie in 0 to {MAX_SEED}")
    if floor is not None and not 0.0 < floor < 1.0:
        raise ConfigError(f"--floor {floor}: a fraction of a0 in (0, 1), e.g. 0.01")
    if run:
        campaign_files(configs)             # all there, before anything is written
    cs = boundaries([s / looks[-1] for s in looks])
    seeds = tuple(range(first_seed, first_seed + looks[-1]))
    decided: dict[int, Settled] = {}
    recorded: dict[int, Recorder] = {}
    runs: list[dict[str, Any]] = []
    rows: list[Check] = []
    used: list[int] = []
    last: dict[int, Settled] = {}
    stopped: set[int] = set()        # rows no later look can read: analytic, or seeds missing
    performed = 0
    for k, (n, c) in enumerate(zip(looks, cs, strict=True)):
        if k == 0:
            names = list(PAPER_CAMPAIGNS)
        else:
            open_rows = [i for i in range(len(rows)) if i not in decided and i not in stopped]
            if not open_rows:
                break
            names = [nm for nm in PAPER_CAMPAIGNS
                     if any(nm in campaigns_of(rows[i]) for i in open_rows)]
        if run:
            r = run_seeds(stores, configs, seeds[:n], names, compute, log, jobs)
            if r["points"]:
                runs.append(r)
            for s, added in r["per_seed"].items():
                if added:
                    recorded.pop(s, None)
        elif not stores.is_dir():
            raise ConfigError(f"--stores {stores}: no such directory (run with --run)")
        if log:
            log(f"look {k + 1}: {n} seeds pooled, boundary |z| >= {c:.3f}")
        rows, used = pooled_checks(stores, seeds[:n], c, recorded)
        performed = k + 1
        for i, row in enumerate(rows):
            if i in decided or i in stopped:
                continue
            if k > 0 and used[i] < n:     # this look's seeds are not all there: no reading
                stopped.add(i)
                continue
            last[i] = Settled(row, k + 1, used[i], c, _extendable(row))
            if row.verdict in (HOLDS, FAILS):
                decided[i] = last[i]
            elif not _extendable(row):
                stopped.add(i)
            elif floor is not None and below_floor(row, c, floor):
                last[i].floored = True
                stopped.add(i)
    out = [decided.get(i, last[i]) for i in range(len(rows))]
    report = SettleReport(out, looks, cs, seeds, runs, jobs=jobs, floor=floor)
    have = [s for s in seeds if s in recorded]
    report.calibration = calibration(have, recorded)
    _audit(stores, out, looks[:performed], cs[:performed], seeds, recorded,
           widening(have, recorded), floor)
    report.problems = {f"seed {s}: {name}": p for s in have
                       for name, p in recorded[s].problems.items()}
    report.stored = stored_cost(stores, [s for s in seeds if s in recorded])
    report.elapsed_s = time.monotonic() - started
    return report


def _audit(stores: Path, rows: list[Settled], looks: Sequence[int], cs: Sequence[float],
           seeds: Sequence[int], recorded: dict[int, Recorder],
           widen: dict[tuple, float], floor: float | None = None) -> None:
    """The looks once more on the stored seeds, every stated SE widened by the factor all
    the stored seeds' spread shows it to be too small
    (:func:`herman2019.pooling.widening`; the means at each look are its seeds' only):
    ``Settled.audited`` is the verdict at the first look where the row holds or fails so
    read, ``audited_look`` that look (a row whose look lacks its seeds stops there)."""
    done: set[int] = set()
    for k, (n, c) in enumerate(zip(looks, cs, strict=True), 1):
        checks, used = pooled_checks(stores, seeds[:n], c, recorded, widen)
        for i, r in enumerate(rows):
            if i in done:
                continue
            if k > 1 and used[i] < n:          # this look's seeds were never run for it
                done.add(i)
                continue
            r.audited, r.audited_look = checks[i].verdict, k
            if checks[i].verdict in (HOLDS, FAILS) or not r.extendable \
                    or (floor is not None and below_floor(checks[i], c, floor)):
                done.add(i)


def stored_cost(stores: Path, seeds: Sequence[int]) -> dict[str, float]:
    """The points of the seeds in the stores and their summed point ``wall_time`` [s];
    those of seeds 0 and 1 (what ``--seeds 0 1`` runs) apart."""
    n = {True: 0, False: 0}
    cpu = {True: 0.0, False: 0.0}
    tables = [df for df in _tables(stores).values() if hasattr(df, "columns")]
    for s in seeds:
        for df in tables:
            rows = df[df["seed"] == s]
            first = s < 2
            n[first] += len(rows)
            cpu[first] += float(rows["wall_time"].sum()) if "wall_time" in rows else 0.0
    return {"stored_points": n[True] + n[False], "stored_core_s": round(cpu[True] + cpu[False]),
            "stored_points_seeds_2_up": n[False], "stored_core_s_seeds_2_up": round(cpu[False])}
