"""The ``sweep`` command: plan, run, status, export, validate, merge, figures, paper-check,
report.

Exit statuses are those of :mod:`sweep.errors` (0 ok, 1 internal error, 2 bad input,
3 store problem, 4 MPI launch problem, 5 worker failure, 6 interrupted but resumable).

Each command imports its own modules when it runs (each such import says ``# lazy``):
``import sweep.cli`` takes 0.01 s, so ``main`` installs the stop handlers of ``sweep run``
(:mod:`sweep.run.startup`) in the process's first instants; with every command's modules
at the top it took 0.6 s (measured: a timed ``import``), and every command paid for all.
"""
from __future__ import annotations

import argparse
import json
import signal
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path

from sweep.arguments import count, kind_list, plural, positive_number, seconds, shard
from sweep.errors import EXIT_INTERNAL, EXIT_OK, EXIT_STORE, ConfigError, Interrupted, SweepError
from sweep.run import guard, startup
from sweep.run.mpi import check_launch, mpi_world
from sweep.system import STOP_SIGNALS

__all__ = ["main", "build_parser"]


def _version() -> str:
    """``sweep (floewave 0.1.0, model version 3, store schema 2)``."""
    import floewave  # lazy: 0.1 s (numpy), after the stop handlers
    from sweep.store.schema import SCHEMA_VERSION  # lazy: as floewave

    return (f"sweep (floewave {floewave.__version__}, model version {floewave.MODEL_VERSION},"
            f" store schema {SCHEMA_VERSION})")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (documented in sweep/README.md)."""
    from sweep.run.launch import DEFAULT_COMPUTE  # lazy: 0.2 s (h5py, numba), after the handlers

    p = argparse.ArgumentParser(prog="sweep", description="Run and analyse floewave"
                                " parameter campaigns (MPI master/worker, one HDF5 store).")
    p.add_argument("--version", action="version", version=_version())
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    r = sub.add_parser("run", help="run or resume a campaign into a store")
    r.add_argument("config", type=Path, help="campaign TOML file")
    r.add_argument("--store", type=Path, required=True, help="HDF5 store (created if missing)")
    r.add_argument("--retry-failed", action="store_true", help="recompute points stored as"
                   " failed")
    r.add_argument("--extend", action="store_true", help="accept a store of this campaign"
                   " with fewer grid values (the new values are added)")
    r.add_argument("--shard", type=shard, metavar="K/N", help="compute only shard K of N"
                   " (points whose hash mod N is K), for Slurm job arrays")
    r.add_argument("--compute", default=DEFAULT_COMPUTE, metavar="MODULE:FUNC",
                   help="compute function (tests/benchmarks; default floewave:run_point)")
    r.add_argument("--point-timeout", type=seconds, metavar="SECONDS",
                   help="store a point that runs longer as 'timeout' (overrides [run]"
                   " point_timeout; 0: no limit)")
    r.add_argument("--verify", action="store_true", help="on opening, compare the store"
                   " with the journal's checksummed records (as validate --deep) and rebuild"
                   " it from the journal if a value differs")
    r.add_argument("--no-bar", action="store_true", help="log lines even on a terminal")
    r.add_argument("--ignore-slurm-ntasks", action="store_true",
                   help="skip the check that the MPI size equals SLURM_NTASKS")

    pl = sub.add_parser("plan", help="count points and estimate the cost; writes nothing")
    pl.add_argument("config", type=Path)
    pl.add_argument("--rate", type=positive_number, metavar="FLOE_STEPS_PER_S",
                    help="kernel speed to assume instead of a calibration run")
    pl.add_argument("--json", action="store_true", help="machine-readable output")

    s = sub.add_parser("status", help="counts by status, failures, slowest points")
    s.add_argument("store", type=Path)
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.add_argument("--slowest", type=count, default=5, metavar="N")

    e = sub.add_parser("export", help="write the per-point table as CSV or Parquet")
    e.add_argument("store", type=Path)
    e.add_argument("--output", "--out", "-o", type=Path, required=True, dest="output",
                   help="file ending in .csv, .csv.gz or .parquet (Parquet needs the"
                   " 'parquet' extra); sweep.load reads it back, bit for bit")

    v = sub.add_parser("validate", help="check a store against results_schema")
    v.add_argument("store", type=Path)
    v.add_argument("--deep", action="store_true", help="also compare every stored value"
                   " and profile with the journal's checksummed records (bit rot)")

    fg = sub.add_parser("figures", help="the paper's figures (Figs. 2, 3, 5, 6, W_c, "
                        "alpha(omega)) as PNG")
    fg.add_argument("store", type=Path)
    fg.add_argument("--out", type=Path, required=True, help="output directory")
    fg.add_argument("--max", type=int, default=20, metavar="N",
                    help="at most N figures per kind (default 20; groups closest to the "
                         "paper's setup first)")
    fg.add_argument("--only", type=kind_list, action="extend", metavar="KIND[,KIND]",
                    default=None, help="only these kinds, comma-separated or repeated:"
                    " fig2,fig3,fig5,fig6,summary (default all)")

    pc = sub.add_parser("paper-check", help="check the paper's qualitative claims on the"
                        " stores of the shipped paper campaigns (one table)")
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
                    help="check independent ensembles: the campaigns with [base] seed = S"
                    " in DIR/seed<S>/ (run with --run); a verdict stands only where every"
                    " seed gives it")
    pc.add_argument("--settle", action="store_true", help="settle every row: pool seeds"
                    " 0, 1, ... in DIR/seed<S>/, added in looks of 4, 8, ... seeds (with"
                    " --run: run as needed) read group-sequentially (docs/paper-check.md)")
    pc.add_argument("--max-seeds", type=int, default=None, metavar="N",
                    help="--settle: the last look's seeds (4 x a power of 2; default 64)")
    pc.add_argument("--first-seed", type=int, default=None, metavar="S",
                    help="--settle: pool seeds S, S+1, ... (default 0; a settling on fresh"
                    " seeds is independent of one run before)")
    pc.add_argument("--floor", type=float, default=None, metavar="M",
                    help="--settle: stop adding seeds to a chain of a/a0 whose undecided"
                    " steps all lie within +-M of a0 (off by default; docs/paper-check.md)")
    pc.add_argument("--jobs", type=int, default=None, metavar="N",
                    help="--settle --run: run a look's seeds in N processes (default 1)")

    rp = sub.add_parser("report", help="one self-contained HTML page of a campaign: what ran,"
                        " status, failures, figures, collision-zone statistics")
    rp.add_argument("store", type=Path)
    rp.add_argument("--out", type=Path, required=True, help="HTML file to write")
    rp.add_argument("--paper-check", type=Path, default=None, metavar="DIR",
                    help="add the paper-check table of the stores in DIR")
    rp.add_argument("--max", type=int, default=3, metavar="N", help="at most N figures per"
                    " kind (default 3)")

    m = sub.add_parser("merge", help="combine shard stores of one campaign (dedup by hash)")
    m.add_argument("output", type=Path, help="merged store (created or extended)")
    m.add_argument("inputs", type=Path, nargs="+", help="shard stores")
    for parser in (p, *sub.choices.values()):  # `--stor x.h5` is refused, not `--store`
        parser.allow_abbrev = False
    return p


def _err(message: str | BaseException) -> None:
    """Report an error on stderr; a requested stop (:class:`Interrupted`) is not an error
    and says ``sweep: stopped:`` instead."""
    prefix = "sweep: stopped:" if isinstance(message, Interrupted) else "sweep: error:"
    for line in str(message).splitlines() or [""]:
        print(f"{prefix} {line}", file=sys.stderr)


# ---------------------------------------------------------------------- commands
def cmd_run(args: argparse.Namespace) -> int:
    from sweep.config import load_campaign  # lazy: after the stop handlers (module docstring)
    from sweep.run.launch import run_campaign  # lazy: as sweep.config

    comm = mpi_world()
    rank = comm.Get_rank() if comm is not None else 0
    size = comm.Get_size() if comm is not None else 1
    try:
        if not args.ignore_slurm_ntasks:
            check_launch(size)
        campaign = load_campaign(args.config)
        if args.shard:
            campaign = campaign.shard(*args.shard)
        summary = run_campaign(campaign, str(args.store), compute=args.compute,
                               retry_failed=args.retry_failed, extend=args.extend, comm=comm,
                               progress_bar=False if args.no_bar else None,
                               command=" ".join(sys.argv), point_timeout=args.point_timeout,
                               verify=args.verify)
    except SweepError as exc:
        if rank == 0:
            _err(exc)
        return exc.exit_status
    if rank == 0 and summary is not None:
        try:
            print(f"sweep: {summary}; store {args.store}", flush=True)
        except (OSError, ValueError):  # stdout closed (by a point, or the reader)
            print(f"sweep: {summary}; store {args.store}", file=sys.stderr)
        missing = summary.total - summary.skipped - summary.computed
        if missing > 0:  # never 0 with grid points missing
            _err(Interrupted(f"{plural(missing, 'grid point')} of {summary.total} not"
                             " stored; the campaign is resumable: run the same command"
                             " again"))
            return Interrupted.exit_status
    return EXIT_OK


def cmd_plan(args: argparse.Namespace) -> int:
    from sweep.config import (  # lazy: per command (module docstring)
        DEFAULT_EXPECTED_ITERATIONS,
        EXTRA_WINDOWS,
        load_campaign,
    )
    from sweep.run.plan import plan  # lazy: per command (module docstring)

    campaign = load_campaign(args.config)  # a SweepError is reported by main
    points = campaign.points()
    projected = plan(points, args.rate)
    invalid, cost, how = projected.invalid_points, projected.floe_steps, projected.calibration
    hours, mean_rate = projected.core_hours, projected.floe_steps_per_s
    assumed = campaign.run.expected_iterations or (
        f"stationary protocol: each point's transient + n_average + {EXTRA_WINDOWS}; else"
        f" min(max_iterations, {DEFAULT_EXPECTED_ITERATIONS})")
    out = {"config": str(args.config), "points": len(points), "invalid_points": invalid,
           "swept": {k: list(v) for k, v in campaign.sweep.items()},
           "floe_steps": cost, "floe_steps_per_s": mean_rate, "core_hours": hours,
           "calibration": how, "assumed_iterations": assumed}
    if args.json:
        print(json.dumps(out, indent=2))
        return EXIT_OK
    dims = " x ".join(f"{k}[{len(v)}]" for k, v in campaign.sweep.items())
    print(f"{args.config}: {len(points)} points ({dims}), {invalid} physically invalid")
    print(f"cost: {cost:.4g} floe-steps (iterations assumed per point: {assumed})")
    print(f"kernel: {mean_rate:.4g} floe-steps/s per core on average ({how})")
    print(f"projected: {hours:.4g} core-hours; nothing was written")
    return EXIT_OK


def cmd_status(args: argparse.Namespace) -> int:
    from sweep.analysis.status import status_report, status_text  # lazy: 0.2 s (pandas)

    rep = status_report(args.store, args.slowest)
    print(json.dumps(rep, indent=2, default=str) if args.json else status_text(rep))
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    from sweep.analysis.export import export_table  # lazy: 0.25 s (pandas)

    n = export_table(args.store, args.output)
    print(f"sweep: wrote {plural(n, 'row')} to {args.output}")
    return EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    from sweep.store.validate import validate  # lazy: per command (module docstring)

    problems = validate(args.store)
    if args.deep and not any("not a readable HDF5 file" in p for p in problems):
        from sweep.store.verify import compare_with_journal  # lazy: per command

        try:
            deep = compare_with_journal(args.store)
        except Exception as exc:  # noqa: BLE001 - a damaged file: say so, no traceback
            deep = [f"{args.store}: cannot be compared with its journal:"
                    f" {type(exc).__name__}: {exc}"]
        if deep:
            deep.append("the journal is the checksummed truth: `sweep run --verify` with"
                        " the store's campaign rebuilds the file from it (the file is"
                        " kept aside)")
        problems += deep
    for p in problems:
        _err(p)
    if problems:
        return EXIT_STORE
    print(f"sweep: {args.store} is a valid store"
          + (" and every stored value is its journal's" if args.deep else ""))
    return EXIT_OK


def cmd_merge(args: argparse.Namespace) -> int:
    from sweep.store.merge import merge  # lazy: per command (module docstring)

    report = merge(args.output, args.inputs)  # a SweepError is reported by main
    print(f"sweep: {report}")
    return EXIT_OK


def cmd_figures(args: argparse.Namespace) -> int:
    from sweep.analysis.figures import KINDS, make_figures  # lazy: 0.3 s (pandas)

    if args.max < 1:
        raise ConfigError(f"--max {args.max}: must be at least 1")
    from floewave.paths import output_dir_problem  # lazy: as floewave (_version)

    problem = output_dir_problem(args.out, "--out")
    if problem:
        raise ConfigError(problem)
    if not args.store.exists():
        raise FileNotFoundError(f"{args.store}: no such store")
    files = make_figures(args.store, args.out, max_figures=args.max,
                         kinds=args.only or KINDS)
    for f in files:
        print(f)
    print(f"sweep: wrote {plural(len(files), 'figure')} to {args.out}")
    return EXIT_OK


def cmd_paper_check(args: argparse.Namespace) -> int:
    """Exit status 0 whatever the verdicts; 3 if a store is missing or unreadable (the
    table is printed all the same, those claims inconclusive)."""
    from sweep.paper.check import check_stores, format_table

    def log(msg: str) -> None:
        print(f"sweep: {msg}", file=sys.stderr)

    if args.settle:
        if args.seeds:
            raise ConfigError("--settle and --seeds: give one (--settle chooses its seeds)")
        from sweep.paper.settle import settle
        from sweep.paper.settled import format_settled, settled_json

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
            raise ConfigError("--jobs: only with --run (it says how many processes run seeds)")
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
        from sweep.paper.seeds import across_seeds, check_seeds, format_seed_table

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


def cmd_report(args: argparse.Namespace) -> int:
    from sweep.report import command  # lazy: 0.3 s (pandas)

    return command(args)


_COMMANDS = {"run": cmd_run, "plan": cmd_plan, "status": cmd_status, "export": cmd_export,
             "validate": cmd_validate, "merge": cmd_merge, "figures": cmd_figures,
             "paper-check": cmd_paper_check, "report": cmd_report}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sweep`` console script; returns the exit status.

    From the command line (``argv`` None), ``sweep run`` runs under its guard
    (:mod:`sweep.run.guard`): a parent process that turns an exit with status 0 before the
    campaign finished (``exit(0)`` in a compute function) into status 6."""
    args_ = list(sys.argv[1:] if argv is None else argv)
    startup.catch(args_, argv is None)  # first: a stop from the first instants is status 6
    try:
        child = argv is None and bool(args_) and args_[0] == "run" and guard.guarded()
        guard.unblock()
        try:
            status = _main(argv)
        except SystemExit as exc:  # argparse's --help (0) or usage error (2)
            code = exc.code
            status = code if isinstance(code, int) else (EXIT_OK if code is None else 2)
    except Interrupted as exc:  # before _main's own handling
        _err(exc)
        status = exc.exit_status
        child = False
    if startup.FIRST and status not in (EXIT_OK, Interrupted.exit_status):
        # a stop raised inside an import can surface as another error (an ImportError,
        # a --compute that "cannot be imported"): it was the stop
        _err(Interrupted(f"stopped by {signal.Signals(startup.FIRST[0]).name} during"
                         " start-up; the campaign is resumable: run the same command"
                         " again"))
        status = Interrupted.exit_status
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        from floewave.paths import quiet_stdout  # lazy: as floewave (_version)
        quiet_stdout()
    except (OSError, ValueError):
        pass
    if argv is None:  # the command line: a stop from now on cannot kill the exit
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)
    else:  # in-process: the caller's handlers back, its later stops not this command's
        startup.release()
    if startup.LATE and status == EXIT_OK:
        print(f"sweep: {signal.Signals(startup.LATE[0]).name} arrived after the campaign had"
              " finished: nothing was left to stop", file=sys.stderr)
    if child:
        guard.report_status(status)
    return status


def _main(argv: Sequence[str] | None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SweepError as exc:  # a stop during the parser's imports
        _err(exc)
        return exc.exit_status
    except Exception:  # the stop wrapped by an import (a dataclass's __set_name__ makes
        if startup.FIRST:  # it a RuntimeError): main says "stopped" and returns 6
            return EXIT_INTERNAL
        raise
    try:
        return _COMMANDS[args.command](args)
    except SweepError as exc:  # ConfigError, StoreError, ...: each carries its exit status
        _err(exc)
        return exc.exit_status
    except (KeyError, FileNotFoundError) as exc:
        _err(str(exc))
        return EXIT_STORE
    except BrokenPipeError:  # `sweep status S.h5 | head -1`: the reader has what it wanted
        from floewave.paths import quiet_stdout  # lazy: as floewave (_version)
        quiet_stdout()
        return EXIT_OK
    except Exception:  # noqa: BLE001 - a bug: show it
        if startup.FIRST:  # an import cut short by the stop, not a bug
            return EXIT_INTERNAL  # main says "stopped" and returns 6
        traceback.print_exc()
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
