"""``herman2019 check``: the paper campaigns' stores read or run, their claims checked.

``herman2019 check`` reads the stores of the shipped paper campaigns (``configs/fig2``,
``fig5``, ``fig6a``, ``fig6b``, ``periods``; by default ``paper/<name>.h5``, where
``herman2019 numbers --out paper`` writes them), or runs the missing ones
with ``--run``, and prints one table: each claim, the campaign and points that test it,
the quantity, its values with error bars, and a verdict. The claims are
:mod:`herman2019.claims`, the statistical rule :mod:`herman2019.estimates`;
:func:`check_stores` reads (and optionally runs) the stores.
"""
from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from herman2019.claims import FLOORS, PAPER_CAMPAIGNS, X_NEAR, Check, paper_checks
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE, Z_CRIT
from sweep.analysis.load import load, load_profile
from sweep.config import load_campaign
from sweep.errors import ConfigError, StoreError
from sweep.run.compute import DEFAULT_COMPUTE
from sweep.run.launch import run_campaign

__all__ = ["PaperReport", "default_configs", "campaign_files", "run_campaigns", "check_stores",
           "seed_rows", "load_tables", "format_table", "markdown_cell"]


# ---------------------------------------------------------------------- stores and output
@dataclass
class PaperReport:
    """What :func:`check_stores` found: the checks, the stores used, and store problems
    (campaign -> message; any problem makes ``herman2019 check`` exit with status 3)."""

    checks: list[Check]
    stores: dict[str, str]
    problems: dict[str, str] = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        return {v: sum(c.verdict == v for c in self.checks)
                for v in (HOLDS, FAILS, INCONCLUSIVE)}

    def to_dict(self) -> dict[str, Any]:
        return {"stores": self.stores, "problems": self.problems, "counts": self.counts(),
                "z_crit": Z_CRIT, "floors": FLOORS, "x_near": X_NEAR,
                "checks": [c.to_dict() for c in self.checks]}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)


def default_configs() -> Path:
    """The shipped ``configs/`` directory of this checkout."""
    return Path(__file__).resolve().parents[1] / "configs"


def campaign_files(configs: Path, names: Sequence[str] = PAPER_CAMPAIGNS) -> dict[str, Path]:
    """``<configs>/<name>.toml`` for each of ``names``; a missing one is a
    :class:`ConfigError` (checked for all before anything runs)."""
    files = {name: Path(configs) / f"{name}.toml" for name in names}
    for path in files.values():
        if not path.is_file():
            raise ConfigError(f"{path}: no such campaign file (--configs)")
    return files


def run_campaigns(stores: Path, files: Mapping[str, Path], *, compute: str | None = None,
                  log: Callable[[str], None] | None = None, command: str) -> None:
    """Run (or resume) each campaign file into ``<stores>/<name>.h5``, in-process, in the
    order given (every file parsed first: an invalid one stops the run before it starts)."""
    campaigns = {name: load_campaign(path) for name, path in files.items()}
    for name, campaign in campaigns.items():
        path = Path(stores) / f"{name}.h5"
        if log:
            log(f"running {name} into {path}")
        run_campaign(campaign, str(path), compute=compute or DEFAULT_COMPUTE,
                     progress_bar=False, command=f"{command} ({name})")


def seed_rows(df: pd.DataFrame, seed: int | None, path: Path) -> pd.DataFrame | str:
    """The rows of seed ``seed`` of a store's table, indexed as a store of that seed
    alone (``seed`` None: the table, if it holds one seed); a message when there are none,
    or when ``seed`` is None and the store holds several seeds (a settling's store: its
    seeds are never mixed)."""
    seeds = sorted(set(df["seed"])) if "seed" in df else []
    if seed is None:
        if len(seeds) > 1:
            return (f"{path} holds {len(seeds)} seeds (a settling's store): check it with"
                    " --settle or --seeds")
        return df
    rows = df[df["seed"] == seed]
    if rows.empty:
        return f"no store rows of seed {seed} in {path} (run it with --run)"
    return rows.reset_index(drop=True)


def check_stores(stores: str | Path = "paper", *, run: bool = False,
                 configs: str | Path | None = None, compute: str | None = None,
                 log: Callable[[str], None] | None = None, seed: int | None = None,
                 tables: Mapping[str, Any] | None = None) -> PaperReport:
    """Check the paper's claims on ``<stores>/<name>.h5`` for each of
    :data:`PAPER_CAMPAIGNS`: on its rows of ensemble seed ``seed`` when given (a store
    that sweeps the seed: :mod:`herman2019.seeds`); ``tables``: those stores' tables
    already loaded (``None`` for a missing one).

    With ``run``, each campaign ``<configs>/<name>.toml`` is first run (or resumed: a
    complete store is left as it is) into its store, in-process. A store that is missing
    (without ``run``) or unreadable is reported in ``problems`` and its claims are
    inconclusive.

    Raises
    ------
    ConfigError
        ``stores`` is not a directory (without ``run``), or with ``run`` a campaign file
        is missing or invalid.
    """
    stores = Path(stores)
    configs = Path(configs) if configs is not None else default_configs()
    if run:
        stores.mkdir(parents=True, exist_ok=True)
    elif not stores.is_dir():
        raise ConfigError(f"--stores {stores}: no such directory (run the campaigns into it"
                          " with --run, or see docs/paper-check.md)")
    paths = {name: stores / f"{name}.h5" for name in PAPER_CAMPAIGNS}
    if run:
        run_campaigns(stores, campaign_files(configs), compute=compute, log=log,
                      command="herman2019 check --run")
    loaded = dict(tables) if tables is not None else load_tables(paths)
    tables = {}
    problems: dict[str, str] = {}
    for name, path in paths.items():
        df = loaded.get(name)
        if isinstance(df, str) or df is None:
            problems[name] = df or f"no store {path} (run it with --run)"
            tables[name] = None
            continue
        rows = seed_rows(df, seed, path)
        if isinstance(rows, str):
            problems[name] = rows
            tables[name] = None
        else:
            tables[name] = rows

    cache: dict[tuple[str, str], Any] = {}

    def profile(name: str, h: str) -> Mapping[str, Any]:
        if (name, h) not in cache:
            try:
                cache[name, h] = load_profile(paths[name], h)
            except StoreError as exc:
                raise KeyError(str(exc)) from None
        return cache[name, h]

    checks = paper_checks(tables, profile, missing=problems)
    return PaperReport(checks, {k: str(v) for k, v in paths.items()}, problems)


def load_tables(paths: Mapping[str, Path]) -> dict[str, pd.DataFrame | str | None]:
    """Each store's table (:func:`sweep.load`): ``None`` for a missing store, the problem
    for an unreadable one."""
    out: dict[str, pd.DataFrame | str | None] = {}
    for name, path in paths.items():
        if not path.exists():
            out[name] = None
            continue
        try:
            out[name] = load(path)
        except StoreError as exc:
            out[name] = f"cannot read {path}: {exc}"
    return out


def markdown_cell(text: str) -> str:
    """``text`` as one cell of a Markdown table (pipes escaped, one line)."""
    return text.replace("|", "\\|").replace("\n", " ")


def format_table(checks: Sequence[Check]) -> str:
    """The checks as one Markdown table (pasteable into docs/paper-check.md), with a count
    line."""
    lines = ["| # | claim (paper) | campaign: points | quantity | value ± SE | rule: evidence"
             " | verdict |", "|---|---|---|---|---|---|---|"]
    for i, c in enumerate(checks, 1):
        values = "; ".join(e.text() for e in c.estimates) or "—"
        lines.append("| " + " | ".join(markdown_cell(s) for s in (
            str(i), f"{c.claim} ({c.source})", f"{c.campaign}: {c.points}", c.quantity, values,
            f"{c.rule}: {c.evidence}" if c.rule else c.evidence, c.verdict)) + " |")
    counts = {v: sum(c.verdict == v for c in checks) for v in (HOLDS, FAILS, INCONCLUSIVE)}
    failing = [str(i) for i, c in enumerate(checks, 1) if c.verdict == FAILS]
    lines.append("")
    lines.append(f"{counts[HOLDS]} hold, {counts[FAILS]} fail"
                 f"{' (#' + ', #'.join(failing) + ')' if failing else ''},"
                 f" {counts[INCONCLUSIVE]} inconclusive. Rule: |z| >= {Z_CRIT:g} (Student-t"
                 " with n - 2 degrees of freedom for fitted exponents); '(exact)': an"
                 " analytic value; '(floor)': no stored SE, the stated floor used instead"
                 " (herman2019.claims.FLOORS).")
    return "\n".join(lines)

