"""The ``herman2019`` command (also ``python -m herman2019``): the study of Herman, Cheng &
Shen (2019) on floewave campaigns run by sweep.

- ``check``: the paper's qualitative claims checked on the stores of the shipped paper
  campaigns (``--run`` runs them; ``--seeds``, ``--settle``: across independent ensembles;
  docs/paper-check.md);
- ``report``: ``sweep report`` of a store with the paper-check table of a directory of stores;
- ``atlas``: docs/atlas.md and its figures from the shipped table ``results/herman2019``;
- ``numbers``: the record of every number the docs quote (docs/numbers.txt);
- ``record``: one shard's table and provenance into ``results/herman2019``;
- ``calibrate``: the error bars calibrated on the grid's own points over several seeds
  (:mod:`herman2019.calibration`);
- ``surrogate``: the released grid as a function with an error bar, anywhere in its box
  (:mod:`herman2019.surrogate`; docs/surrogate.md).

Exit statuses are those of :mod:`sweep.errors` (0 ok, 1 internal error, 2 bad input,
3 store problem, 6 interrupted but resumable); a claim's verdict never sets it.
"""
from __future__ import annotations

import argparse
import json
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path

from herman2019 import calibration, factors, numbers, record
from herman2019 import report as study_report
from herman2019.atlas import make_atlas
from herman2019.check import check_stores, format_table
from herman2019.outcomes import classify, format_outcomes
from herman2019.seeds import across_seeds, check_seeds, format_seed_table
from herman2019.settle import settle
from herman2019.settled import format_settled, settled_json
from herman2019.surrogate import command as surrogate_command
from sweep.errors import EXIT_INTERNAL, EXIT_OK, EXIT_STORE, ConfigError, command_status, report

__all__ = ["main", "build_parser"]

#: The repository's root (the default places of the shipped table and docs).
ROOT = Path(__file__).resolve().parents[1]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (documented in docs/paper-check.md and docs/guide.md)."""
    p = argparse.ArgumentParser(prog="herman2019", description="The Herman et al. (2019)"
                                " study: its claims checked on floewave campaigns, the atlas"
                                " of its grid, the numbers the docs quote.")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    pc = sub.add_parser("check", help="check the paper's qualitative claims on the stores"
                        " of the shipped paper campaigns (one table)")
    pc.add_argument("--stores", type=Path, default=Path("paper"), metavar="DIR",
                    help="directory of the stores <name>.h5 (default: paper)")
    pc.add_argument("--run", action="store_true", help="first run (or resume) the campaigns"
                    " into DIR, in-process")
    pc.add_argument("--configs", type=Path, default=None, metavar="DIR",
                    help="campaign files <name>.toml for --run (default: this checkout's"
                    " configs/)")
    pc.add_argument("--compute", default=None, metavar="MODULE:FUNC",
                    help="compute function for --run (tests; default floewave:run_point)")
    pc.add_argument("--json", action="store_true", help="machine-readable output")
    pc.add_argument("--seeds", type=int, nargs="+", default=None, metavar="S",
                    help="check independent ensembles: each seed S's rows of DIR/<name>.h5,"
                    " the campaigns with the seeds swept (run with --run); a verdict stands"
                    " only where every seed gives it")
    pc.add_argument("--settle", action="store_true", help="settle every row: pool seeds"
                    " 0, 1, ... (swept in DIR/<name>.h5), added in looks of 4, 8, ... seeds"
                    " (with --run: run as needed, each campaign extended by the look's"
                    " seeds) read group-sequentially (docs/paper-check.md)")
    pc.add_argument("--max-seeds", type=int, default=None, metavar="N",
                    help="--settle: the last look's seeds (4 x a power of 2; default 64)")
    pc.add_argument("--first-seed", type=int, default=None, metavar="S",
                    help="--settle: pool seeds S, S+1, ... (default 0; a settling on fresh"
                    " seeds is independent of one run before)")
    pc.add_argument("--floor", type=float, default=None, metavar="M",
                    help="--settle: stop adding seeds to a chain of a/a0 whose undecided"
                    " steps all lie within +-M of a0 (off by default; docs/paper-check.md)")
    pc.add_argument("--settled", type=Path, default=None, metavar="FILE",
                    help="read a settled table (check --settle --json, e.g."
                    " results/paper-settle/settled.json) and print each row against the"
                    " paper: its sentence, reading, resolution and outcome (holds,"
                    " contradicted, below the paper's resolution; docs/paper-check.md)")
    pc.add_argument("--jobs", type=int, default=None, metavar="N",
                    help="--settle --run: run a look's seeds with sweep run under mpiexec,"
                    " N workers (default 1: in this process)")

    rp = sub.add_parser("report", help="sweep report of a store with the paper-check table"
                        " of the stores in DIR")
    rp.add_argument("store", type=Path)
    rp.add_argument("--out", type=Path, required=True, help="HTML file to write")
    rp.add_argument("--stores", type=Path, required=True, metavar="DIR",
                    help="directory of the paper campaigns' stores <name>.h5")
    rp.add_argument("--max", type=int, default=3, metavar="N", help="at most N figures per"
                    " kind (default 3)")

    at = sub.add_parser("atlas", help="the atlas of the paper's grid (docs/atlas.md) from its"
                        " shipped table")
    at.add_argument("table", nargs="?", default=str(ROOT / "results" / "herman2019"),
                    help="the per-point table (default: results/herman2019)")
    at.add_argument("--out", type=Path, default=ROOT / "docs",
                    help="writes OUT/atlas.md and OUT/atlas/*.png (default: docs)")
    at.add_argument("--bootstrap", type=int, default=200, metavar="N",
                    help="bootstrap draws for a mean's sampling error (default 200)")

    nu = sub.add_parser("numbers", help="run the campaigns the docs quote and print every"
                        " number (docs/numbers.txt)")
    nu.add_argument("--out", type=Path, default=None, metavar="DIR",
                    help="the stores' directory (default: a new temporary one)")
    nu.add_argument("--skip-runs", action="store_true", help="reuse the stores in --out")
    nu.add_argument("--record", type=Path, default=None, metavar="FILE",
                    help="also write the output to FILE under the record's header")
    nu.add_argument("--timings", action="store_true",
                    help="also time the compile, the cost projection and check --seeds")
    nu.add_argument("--settle", action="store_true", help="with --timings: also the settled"
                    " table (check --settle on the seed stores; ~25 min more)")
    nu.add_argument("--settle-only", action="store_true", help="print only the settled"
                    " table's section, on --out's seed stores (to append to a record)")

    ca = sub.add_parser("calibrate", help="the error bars calibrated on the grid: a"
                        " stratified sample of its points on several seeds, RMS z per"
                        " quantity and stratum (docs/convergence.md)")
    ca.add_argument("--out", type=Path, default=ROOT / "results" / "calibration",
                    help="the runs' directory, OUT/runs.csv.gz (default: results/calibration)")
    ca.add_argument("--table", action="store_true", help="only the table of the stored runs")
    ca.add_argument("--factors", action="store_true", help="fit the calibrated standard"
                    " errors' factors to the stored runs, write OUT/factors.csv and print"
                    " them with their cross-validated check")
    ca.add_argument("--grid", default=str(ROOT / "results" / "herman2019-v8"),
                    help="the table the sample is drawn from (default: results/herman2019-v8,"
                    " model version 8's grid, which the shipped calibration's sample was"
                    " drawn from)")
    ca.add_argument("--n-zone", type=int, default=200, help="points with a compact zone")
    ca.add_argument("--n-none", type=int, default=100, help="points without one")
    ca.add_argument("--n-nc", type=int, default=40, help="points the table ended"
                    " not_converged")
    ca.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ca.add_argument("--sample-seed", type=int, default=47)
    ca.add_argument("--jobs", type=int, default=1, help="processes (default 1)")

    su = sub.add_parser("surrogate", help="the released grid as a function: alpha, a_end/a0,"
                        " p_zone and W_c anywhere in its box with a standard error"
                        " (docs/surrogate.md)")
    surrogate_command.add_arguments(su)

    rc = sub.add_parser("record", help="ship a campaign shard's result without its store:"
                        " its table and provenance")
    rc.add_argument("store", type=Path, nargs="?")
    rc.add_argument("--shard", help="K/N")
    rc.add_argument("--plan", type=Path, help="the log of `sweep plan` before the run: its"
                    " projection goes into provenance.json")
    rc.add_argument("--summary", action="store_true", help="print the run's summary of"
                    " --out's provenance.json (a Markdown table) and nothing else")
    rc.add_argument("--log", action="append", default=[], type=Path,
                    help="the log of each sweep run on the store, oldest first")
    rc.add_argument("--out", type=Path, default=record.RESULTS,
                    help="default: results/herman2019")
    for parser in (p, *sub.choices.values()):
        parser.allow_abbrev = False
    return p


def _err(message: str | BaseException) -> None:
    """Report an error on stderr (``herman2019: error:``; a stop: ``herman2019: stopped:``)."""
    report(message, "herman2019")


# ---------------------------------------------------------------------- commands
def cmd_check(args: argparse.Namespace) -> int:
    """Exit status 0 whatever the verdicts; 3 if a store is missing or unreadable (the
    table is printed all the same, those claims inconclusive)."""
    def log(msg: str) -> None:
        print(f"herman2019: {msg}", file=sys.stderr)

    if args.settled is not None:
        for flag, on in (("--settle", args.settle), ("--seeds", args.seeds),
                         ("--run", args.run)):
            if on:
                raise ConfigError(f"--settled and {flag}: --settled reads a settled table")
        return _print_outcomes(args.settled, as_json=args.json)
    if args.settle:
        if args.seeds:
            raise ConfigError("--settle and --seeds: give one (--settle chooses its seeds)")
        most = 64 if args.max_seeds is None else args.max_seeds
        first = 0 if args.first_seed is None else args.first_seed
        jobs = 1 if args.jobs is None else args.jobs
        if first < 0:
            raise ConfigError(f"--first-seed {first}: a seed is >= 0")
        if args.floor is not None and not 0.0 < args.floor < 1.0:
            raise ConfigError(f"--floor {args.floor}: a fraction of a0 in (0, 1), e.g. 0.01")
        if jobs < 1:
            raise ConfigError(f"--jobs {jobs}: at least 1")
        if args.jobs is not None and not args.run:
            raise ConfigError("--jobs: only with --run (it says how many MPI workers run seeds)")
        settled = settle(args.stores, max_seeds=most, first_seed=first, run=args.run,
                         configs=args.configs, compute=args.compute, log=log, jobs=jobs,
                         floor=args.floor)
        print(settled_json(settled) if args.json else format_settled(settled))
        for name, problem in settled.problems.items():
            _err(f"{name}: {problem}")
        return EXIT_STORE if settled.problems else EXIT_OK
    for flag, value in (("--max-seeds", args.max_seeds), ("--first-seed", args.first_seed),
                        ("--jobs", args.jobs), ("--floor", args.floor)):
        if value is not None:
            raise ConfigError(f"{flag} {value}: only with --settle")
    if args.seeds:
        reports = check_seeds(args.stores, args.seeds, run=args.run, configs=args.configs,
                              compute=args.compute, log=log)
        if args.json:
            first = next(iter(reports.values())).checks
            across = [across_seeds([r.checks[i].verdict for r in reports.values()])
                      for i in range(len(first))]
            print(json.dumps({"seeds": {str(s): r.to_dict() for s, r in reports.items()},
                              "across_seeds": across}, indent=2))
        else:
            print(format_seed_table(reports))
        problems = {f"seed {s}: {name}": p for s, r in reports.items()
                    for name, p in r.problems.items()}
    else:
        report = check_stores(args.stores, run=args.run, configs=args.configs,
                              compute=args.compute, log=log)
        print(report.to_json() if args.json else format_table(report.checks))
        problems = report.problems
    for name, problem in problems.items():
        _err(f"{name}: {problem}")
    return EXIT_STORE if problems else EXIT_OK


def _print_outcomes(path: Path, *, as_json: bool) -> int:
    """``check --settled FILE``: the outcomes of :mod:`herman2019.outcomes`."""
    try:
        settled = json.loads(path.read_text())
        found = classify(settled)
    except FileNotFoundError:
        raise ConfigError(f"--settled {path}: no such file") from None
    except (json.JSONDecodeError, KeyError, TypeError) as exc:
        raise ConfigError(f"--settled {path}: not a settled table ({exc})") from None
    if as_json:
        print(json.dumps([{"row": o.row, "claim": o.check.claim, "outcome": o.outcome,
                           "verdict": o.check.verdict, "note": o.note,
                           "resolution": o.reading.resolution.value if o.reading else None,
                           "effects": [vars(e) for e in o.effects]} for o in found],
                         indent=2))
    else:
        print(format_outcomes(found))
    return EXIT_OK


def cmd_calibrate(args: argparse.Namespace) -> int:
    """``--factors``: the calibrated SEs' factors (:mod:`herman2019.factors`); else the
    calibration's runs and table (:mod:`herman2019.calibration`)."""
    return (factors.command if args.factors else calibration.command)(args)


def cmd_atlas(args: argparse.Namespace) -> int:
    """Status 0; 2 for a bad argument, 3 for a missing table."""
    if args.bootstrap < 0:
        raise ConfigError(f"--bootstrap {args.bootstrap}: at least 0")
    print(make_atlas(args.table, args.out, bootstrap=args.bootstrap))
    return EXIT_OK


_COMMANDS = {"check": cmd_check, "report": study_report.command, "atlas": cmd_atlas,
             "numbers": numbers.command, "record": record.command,
             "calibrate": cmd_calibrate, "surrogate": surrogate_command.command}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``herman2019`` console script; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # argparse's --help (0) or usage error (2)
        code = exc.code
        return code if isinstance(code, int) else (EXIT_OK if code is None else 2)
    try:
        return command_status(_COMMANDS[args.command], args, "herman2019")
    except Exception:  # noqa: BLE001 - a bug: show it
        traceback.print_exc()
        return EXIT_INTERNAL
