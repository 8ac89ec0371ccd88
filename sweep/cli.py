"""The ``sweep`` command: plan, run, status, export, validate, merge, figures, report.

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
from sweep.errors import (
    EXIT_INTERNAL,
    EXIT_OK,
    EXIT_STORE,
    ConfigError,
    Interrupted,
    SweepError,
    command_status,
    report,
)
from sweep.run import guard, startup
from sweep.run.mpi import check_launch, mpi_world
from sweep.system import STOP_SIGNALS

__all__ = ["main", "build_parser"]


def _version() -> str:
    """``sweep (floewave 1.0.0, model version 9, store schema 5)``."""
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

    e = sub.add_parser("export", help="write the per-point table as CSV or Parquet, and"
                       " the profiles as netCDF")
    e.add_argument("store", type=Path)
    e.add_argument("--output", "--out", "-o", type=Path, dest="output",
                   help="file ending in .csv, .csv.gz or .parquet (Parquet needs the"
                   " 'parquet' extra); sweep.load reads it back, bit for bit")
    e.add_argument("--profiles", type=Path, metavar="FILE.nc",
                   help="also (or only) write every point's profiles along the ice (a/a0"
                   " and its SE, x, mean gap, contact fraction; float32, CF attributes) to"
                   " this netCDF-4 file: xarray.open_dataset reads it without sweep,"
                   " sweep.load_profiles(FILE.nc) too")

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

    rp = sub.add_parser("report", help="one self-contained HTML page of a campaign: what ran,"
                        " status, failures, figures, collision-zone statistics")
    rp.add_argument("store", type=Path)
    rp.add_argument("--out", type=Path, required=True, help="HTML file to write")
    rp.add_argument("--max", type=int, default=3, metavar="N", help="at most N figures per"
                    " kind (default 3)")

    m = sub.add_parser("merge", help="combine shard stores of one campaign (dedup by hash)")
    m.add_argument("output", type=Path, help="merged store (created or extended)")
    m.add_argument("inputs", type=Path, nargs="+", help="shard stores")
    for parser in (p, *sub.choices.values()):  # `--stor x.h5` is refused, not `--store`
        parser.allow_abbrev = False
    return p


def _err(message: str | BaseException) -> None:
    """Report an error on stderr (:func:`sweep.errors.report`: ``sweep: error:``, a stop
    ``sweep: stopped:``)."""
    report(message)


# ---------------------------------------------------------------------- commands
def cmd_run(args: argparse.Namespace) -> int:
    from sweep.config import load_campaign  # lazy: after the stop handlers (module docstring)
    from sweep.run.launch import run_campaign  # lazy: as sweep.config
    from sweep.run.worker import stop_workers, worker_loop  # lazy: as sweep.config

    comm = mpi_world()
    rank = comm.Get_rank() if comm is not None else 0
    size = comm.Get_size() if comm is not None else 1
    try:
        if not args.ignore_slurm_ntasks:
            check_launch(size)
        if rank != 0:  # a worker computes what rank 0 sends it: no campaign to read
            worker_loop(comm, args.compute)
            return EXIT_OK
        try:
            campaign = load_campaign(args.config)
            if args.shard:
                campaign = campaign.shard(*args.shard)
        except BaseException:
            if size > 1:  # the workers wait for rank 0's first word
                stop_workers(comm)
            raise
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
    from sweep.analysis.export import export_profiles  # lazy: as export_table
    from sweep.analysis.profiles_file import check_profiles_output

    if args.output is None and args.profiles is None:
        raise ConfigError("sweep export: give --output FILE (the table), --profiles FILE.nc,"
                          " or both")
    if args.profiles is not None:       # before anything is written
        check_profiles_output(args.profiles)
    if args.profiles is not None:       # first: the one that can refuse a store
        n = export_profiles(args.store, args.profiles)
        print(f"sweep: wrote the profiles of {plural(n, 'point')} to {args.profiles}")
    if args.output is not None:
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


def cmd_report(args: argparse.Namespace) -> int:
    from sweep.report import command  # lazy: 0.3 s (pandas)

    return command(args)


_COMMANDS = {"run": cmd_run, "plan": cmd_plan, "status": cmd_status, "export": cmd_export,
             "validate": cmd_validate, "merge": cmd_merge, "figures": cmd_figures,
             "report": cmd_report}


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
        return command_status(_COMMANDS[args.command], args)
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
