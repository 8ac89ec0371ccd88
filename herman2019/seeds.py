"""``herman2019 check --seeds``: the paper's claims checked on independent ensembles, a
verdict reported only where the seeds agree; and the runs of a settling's seeds.

Every stored number of an ensemble is a statistic of chaotic runs: another ``seed`` gives
other trajectories, and a claim decided at the edge of its rule can hold with one seed and
be inconclusive with another. The seeds are a campaign dimension: each shipped paper
campaign is run (or resumed) as one campaign with ``[sweep] seed = [S1, S2, ...]``
(:func:`seeded_text`; its files in ``<stores>/configs/``) into one store
``<stores>/<name>.h5``, by sweep's one executor (:func:`run_seeds`: in-process, or
``sweep run`` under ``mpiexec`` with ``jobs`` workers), growing by ``--extend`` as seeds
are added. The checks of :mod:`herman2019.check` run on each seed's rows of the stores,
and the claim's verdict across seeds is the common one when every seed gives it, else
:data:`SEED_DEPENDENT`.
"""
from __future__ import annotations

import json
import re
import resource
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from herman2019.check import (
    PaperReport,
    campaign_files,
    check_stores,
    default_configs,
    load_tables,
)
from herman2019.claims import PAPER_CAMPAIGNS
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE
from sweep.analysis.load import load, store_attrs
from sweep.config import load_campaign
from sweep.errors import ConfigError, StoreError
from sweep.run.compute import DEFAULT_COMPUTE
from sweep.run.launch import run_campaign

__all__ = ["SEED_DEPENDENT", "seeded_text", "seeded_configs", "stored_seeds", "run_seeds",
           "across_seeds", "check_seeds", "format_seed_table"]

#: the verdict of a claim whose seeds disagree
SEED_DEPENDENT = "seed-dependent"

_SEED_LINE = re.compile(r"^seed\s*=\s*\d+\s*$", re.MULTILINE)


def seeded_text(path: Path, seeds: Sequence[int]) -> str:
    """The campaign file ``path`` with its ``[base] seed = N`` line removed and
    ``seed = [seeds]`` swept. A campaign file whose ``[base]`` has not exactly one
    ``seed = N`` line is a :class:`ConfigError` (the shipped files write every field out)."""
    if not path.is_file():
        raise ConfigError(f"{path}: no such campaign file (--configs)")
    text = path.read_text(encoding="utf-8")
    base, sep, rest = text.partition("\n[sweep]")
    if len(_SEED_LINE.findall(base)) != 1 or not sep:
        raise ConfigError(f"{path}: [base] needs exactly one 'seed = N' line for --seeds")
    body, run_sep, run = rest.partition("\n[run]")
    swept = f"seed = [{', '.join(str(s) for s in seeds)}]"
    return (_SEED_LINE.sub("# seed: swept below", base) + sep + body.rstrip("\n") + "\n"
            + swept + "\n" + ("\n" + run_sep.lstrip("\n") + run if run_sep else ""))


def seeded_configs(configs: Path, seeds: Sequence[int], out: Path,
                   names: Sequence[str] = PAPER_CAMPAIGNS) -> dict[str, Path]:
    """Write the campaign files of ``names`` with ``seeds`` swept (:func:`seeded_text`)
    into ``out``; returns name -> file."""
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    for name in names:
        files[name] = out / f"{name}.toml"
        files[name].write_text(seeded_text(configs / f"{name}.toml", seeds), encoding="utf-8")
    return files


def stored_seeds(path: Path) -> tuple[int, ...]:
    """The seeds a store's campaign sweeps (empty: no store, or no seed swept)."""
    if not path.exists():
        return ()
    try:
        sweep_ = json.loads(store_attrs(path).get("campaign_json") or "{}").get("sweep", {})
    except (StoreError, ValueError):
        return ()
    return tuple(int(s) for s in sweep_.get("seed", ()))


def _seed_counts(paths: Sequence[Path]) -> dict[int, int]:
    counts: dict[int, int] = {}
    for p in paths:
        if p.exists():
            for s, n in load(p)["seed"].value_counts().items():
                counts[int(s)] = counts.get(int(s), 0) + int(n)
    return counts


def _mpi_run(file: Path, store: Path, compute: str, jobs: int, command: str) -> None:
    """``sweep run FILE --store STORE --extend`` under ``mpiexec -n jobs + 1`` (a master
    and ``jobs`` workers)."""
    mpiexec = shutil.which("mpiexec")
    if mpiexec is None:
        raise ConfigError(f"--jobs {jobs}: no mpiexec on PATH (the seeds run under MPI;"
                          " --jobs 1 runs them in this process)")
    proc = subprocess.run([mpiexec, "-n", str(jobs + 1), sys.executable, "-m", "sweep", "run",
                           str(file), "--store", str(store), "--extend", "--compute",
                           compute, "--no-bar"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise StoreError(f"{command}: sweep run {file} --store {store} failed (exit status"
                         f" {proc.returncode}):\n{proc.stderr[-4000:]}")


def run_seeds(stores: Path, configs: Path, seeds: Sequence[int], names: Sequence[str],
              compute: str | None = None, log: Callable[[str], None] | None = None,
              jobs: int = 1, command: str = "herman2019 check --settle") -> dict[str, Any]:
    """Run (or resume) each of ``names`` with ``seeds`` swept into ``<stores>/<name>.h5``
    (the seeds its store already sweeps kept: the campaign grows by ``--extend``), by
    :func:`sweep.run_campaign` in this process or, with ``jobs`` > 1, ``sweep run`` under
    ``mpiexec`` with ``jobs`` workers. Returns the seeds and campaigns run, the points
    added per seed (``per_seed``) and in all, and the CPU and wall time."""
    campaign_files(configs, names)                   # all there, before anything runs
    stores.mkdir(parents=True, exist_ok=True)
    paths = [stores / f"{n}.h5" for n in names]
    before = _seed_counts(paths)
    cpu, wall = time.process_time(), time.monotonic()
    child = resource.getrusage(resource.RUSAGE_CHILDREN)
    files = {}
    for name, path in zip(names, paths, strict=True):
        every = sorted(set(stored_seeds(path)) | set(seeds))
        files[name] = seeded_configs(configs, every, stores / "configs", [name])[name]
    campaigns = {name: load_campaign(f) for name, f in files.items()}   # all valid first
    for name, path in zip(names, paths, strict=True):
        if log:
            log(f"running {name} (seeds {seeds[0]}-{seeds[-1]}) into {path}")
        if jobs > 1:
            _mpi_run(files[name], path, compute or DEFAULT_COMPUTE, jobs, command)
        else:
            run_campaign(campaigns[name], str(path), compute=compute or DEFAULT_COMPUTE,
                         progress_bar=False, extend=True, command=f"{command} ({name})")
    after = _seed_counts(paths)
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    added = {s: after.get(s, 0) - before.get(s, 0) for s in seeds}
    return {"seeds": list(seeds), "campaigns": list(names), "per_seed": added,
            "points": sum(added.values()),
            "cpu_s": round(time.process_time() - cpu + used.ru_utime - child.ru_utime
                           + used.ru_stime - child.ru_stime, 2),
            "wall_s": round(time.monotonic() - wall, 2)}


def across_seeds(verdicts: Sequence[str]) -> str:
    """The verdict of a claim across seeds: the common one, else :data:`SEED_DEPENDENT`."""
    first = verdicts[0]
    return first if all(v == first for v in verdicts) else SEED_DEPENDENT


def check_seeds(stores: Path, seeds: Sequence[int], *, run: bool = False,
                configs: Path | None = None, compute: str | None = None,
                log: Callable[[str], None] | None = None) -> dict[int, PaperReport]:
    """:func:`herman2019.check.check_stores` on each seed S's rows of ``<stores>/<name>.h5``
    (with ``run``, the campaigns are first run with the seeds swept: :func:`run_seeds`)."""
    if len(set(seeds)) < 2:
        raise ConfigError(f"--seeds {' '.join(map(str, seeds))}: give at least two different"
                          " seeds")
    configs = Path(configs) if configs is not None else default_configs()
    stores = Path(stores)
    if run:
        run_seeds(stores, configs, sorted(set(seeds)), list(PAPER_CAMPAIGNS), compute, log,
                  command="herman2019 check --seeds")
    elif not stores.is_dir():
        raise ConfigError(f"--stores {stores}: no such directory (run with --run)")
    tables = load_tables({name: stores / f"{name}.h5" for name in PAPER_CAMPAIGNS})
    return {seed: check_stores(stores, seed=seed, tables=tables) for seed in seeds}


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
