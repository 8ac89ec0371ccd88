"""floewave: run one model point (floewave run) or draw the analytic figures (floewave figures).

``floewave run --set L_x=1.5 --set T=1.4 ... [--json out.json] [--plot out.png]`` runs one
point and prints a summary; ``floewave run --help`` lists every field with its default and
units (read from :class:`floewave.ModelConfig`, so the list follows the code). Before the
point it says on stderr that the kernels are being compiled (or loaded from numba's cache)
and compiles them on a shrunken copy of the point (:func:`warm_up`), so that the wall time
and floe-steps/s it reports are the point's alone.

``floewave figures --out DIR`` writes the analytic figures (DIR/fig1_dispersion.png, the
paper's Fig. 1; :mod:`floewave.figures`) and prints the paths and fitted tail exponents.

Exit statuses: 0 success; 2 bad input (unknown field, bad value, physically invalid point;
for ``figures``: matplotlib missing or the output directory cannot be created / written);
3 the point failed numerically.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from . import MODEL_VERSION, __version__
from .config import FloewaveError, InvalidPointError, ModelConfig
from .figures import FIG1_NAME, figure1, figure4
from .help import did_you_mean, fields_help
from .paths import output_file_problem, quiet_stdout

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_FAILED = 3
EXIT_HELP = ("exit statuses: 0 success; 2 bad input (unknown field, bad value, physically"
             " invalid point,\n  an output path that cannot be written, matplotlib missing"
             " for --plot or figures);\n  3 the point failed numerically")


def _parse_value(name: str, text: str) -> Any:
    types = {f.name: f.type for f in fields(ModelConfig)}
    if name not in types:
        raise FloewaveError(f"--set {name}={text}: unknown field {name!r}{did_you_mean(name)};"
                            f" the fields are {', '.join(types)} ('floewave run --help'"
                            " gives defaults and units)")
    t = types[name] if isinstance(types[name], str) else types[name].__name__
    try:
        if t == "bool":
            low = text.strip().lower()
            if low not in ("true", "false", "1", "0", "yes", "no"):
                raise ValueError(text)
            return low in ("true", "1", "yes")
        if t == "int":
            return int(text)
        if t == "float":
            return float(text)
    except ValueError:
        raise FloewaveError(f"--set {name}={text}: expected {t}") from None
    return text


def _distances(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected distances in metres, e.g."
                                         " 3,12,30") from None
    if not values or any(not (v >= 0) for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: expected distances >= 0 m, e.g. 3,12,30")
    return values


def config_from_sets(sets: list[str]) -> ModelConfig:
    """Build a :class:`ModelConfig` from ``NAME=VALUE`` strings on top of the defaults."""
    kw: dict[str, Any] = {}
    for item in sets:
        if "=" not in item:
            raise FloewaveError(f"--set {item!r}: expected NAME=VALUE")
        name, text = item.split("=", 1)
        kw[name.strip()] = _parse_value(name.strip(), text.strip())
    return ModelConfig(**kw)


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return [None if (isinstance(x, float) and not np.isfinite(x)) else x for x in v.tolist()]
    if isinstance(v, (np.floating, float)):
        return float(v) if np.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    return v


#: Said on stderr before the kernels of the first point are compiled (or loaded from numba's
#: cache). Measured here (2 shared cores, 2026-12-02): 9.8-11.5 s with an empty cache
#: (``NUMBA_CACHE_DIR`` fresh), 0.24 s from the cache; a user reported 35 s on a laptop.
COMPILING = ("floewave: compiling the numba kernels, or loading them from the cache (the first"
             " run on a machine compiles: about 10-40 s; later runs: about 1 s)...")


def warm_up_config(cfg: ModelConfig) -> ModelConfig:
    """A shrunken copy of ``cfg`` with the same kernels: four floes, one spin-up and one
    averaging period, one iteration, one replica (as ``sweep``'s warm-up)."""
    return cfg.replace(L_sheet=4 * cfg.L_x, n0=1, n0_warm=0, nT=1, max_iterations=1,
                       replicas=1)


def warm_up(cfg: ModelConfig) -> float:
    """Compile (or load from numba's cache) the kernels of ``cfg`` by running
    :func:`warm_up_config`, so that the point's wall time and floe-steps/s exclude the
    compilation; return the seconds it took. A failure of the shrunken point is left to
    the point itself to report."""
    from .model import run_point  # lazy: numba and the kernels, 0.4 s; not for --help

    t0 = time.perf_counter()
    try:
        run_point(warm_up_config(cfg))
    except (FloewaveError, ValueError):
        pass
    return time.perf_counter() - t0


def summary(cfg: ModelConfig, r, compile_time: float | None = None) -> str:
    """A few lines: iterations, status, W_c, alpha fits, wall time, floe-steps/s (of the
    point alone: the kernels' compilation, ``compile_time`` [s], came before it)."""
    rate = r.floe_steps / r.wall_time if r.wall_time > 0 else float("nan")
    compiled = ("" if compile_time is None else
                f" (kernels compiled or loaded before the point in {compile_time:.1f} s,"
                " not included)")
    return "\n".join([
        f"point: L_x={cfg.L_x} T={cfg.T} a0={cfg.a0} C_sd={cfg.C_sd} eps={cfg.eps} "
        f"d_f={cfg.d_f} dispersion={cfg.dispersion}  (N_f={r.n_floes}, {r.kernel_mode})",
        f"status: {r.status} after {r.iterations} iterations (final residual {r.residual:.3g},"
        f" noise {r.noise:.3g})",
        f"a/a0 at far end: {r.a_end / cfg.a0:.4f} +- {r.a_stderr[-1] / cfg.a0:.4f}",
        (f"compact zone ({r.compact_zone}) from W_c = {r.W_c:.2f} m to {r.compact_end:.2f} m;"
         if r.compact_zone != "none" else
         "no compact zone (the whole ice collides): no W_c, no alpha_inner;")
        + f" ice extent {r.ice_extent:.2f} m",
        f"alpha_all = {r.alpha_all:.4g} 1/m^2, alpha_edge = {r.alpha_edge:.4g},"
        f" alpha_inner = {r.alpha_inner:.4g}, alpha_c (eq. 24) = {r.alpha_c:.4g};"
        f" alpha_exp = {r.alpha_exp:.4g} 1/m",
        f"wall time {r.wall_time:.2f} s, {r.floe_steps:.3g} floe-steps,"
        f" {rate / 1e6:.1f} M floe-steps/s{compiled}",
    ])


def plot(cfg: ModelConfig, r, path: Path) -> None:
    """a/a0 (with standard error) versus x, and the eq. 25 curve with alpha_c (eq. 24)."""
    import matplotlib  # lazy: optional (plot extra): its absence is reported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    fig, ax = plt.subplots(figsize=(6, 3.5))
    x = r.x_mean
    ax.errorbar(x, r.a / cfg.a0, yerr=r.a_stderr / cfg.a0, fmt=".-", ms=3, lw=1,
                label=f"DEM, eps={cfg.eps}, {cfg.dispersion}")
    xx = np.linspace(0, cfg.L_sheet, 200)
    ax.plot(xx, 1.0 / (cfg.a0 * r.alpha_c * xx + 1.0), "k-", lw=1, label="eq. 25 (confined)")
    if r.W_c < cfg.L_sheet:
        ax.axvline(r.W_c, color="0.6", ls=":", label="W_c")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("a / a0")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse an output that cannot be written before the point runs (and is lost)."""
    for option, path in (("--json", args.json), ("--plot", args.plot),
                         ("--trace-plot", args.trace_plot)):
        problem = output_file_problem(path, option) if path is not None else None
        if problem:
            raise FloewaveError(problem)
    if args.trace_plot is not None and args.trace is None:
        raise FloewaveError("--trace-plot needs --trace X[,X...] (the floes to trace)")
    if args.trace is not None and args.trace_every < 1:
        raise FloewaveError(f"--trace-every {args.trace_every}: must be at least 1")
    if args.trace is not None and args.trace_periods is not None and args.trace_periods < 1:
        raise FloewaveError(f"--trace-periods {args.trace_periods}: must be at least 1")
    if args.plot is not None or args.trace_plot is not None:
        try:
            import matplotlib  # noqa: F401 - lazy: optional (plot extra): its absence is reported
        except ImportError:
            raise FloewaveError("--plot and --trace-plot need matplotlib:"
                                " pip install 'floewave[plot]'") from None


def main_parser() -> argparse.ArgumentParser:
    """The ``floewave`` argument parser (``run`` and ``figures``)."""
    parser = argparse.ArgumentParser(prog="floewave", description=__doc__.splitlines()[0],
                                     epilog=EXIT_HELP,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version",
                        version=f"floewave {__version__} (model version {MODEL_VERSION})")
    sub = parser.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser("run", help="run one model point and print a summary",
                         description="Run one model point (the attenuation iteration of"
                         " docs/model.md §4) with the defaults below changed by --set, and print"
                         " a summary.",
                         epilog=fields_help() + "\n\n" + EXIT_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                     help="override a ModelConfig field (repeatable)")
    run.add_argument("--json", type=Path, help="write all results to this JSON file")
    run.add_argument("--plot", type=Path, help="save a/a0 versus x to this PNG file")
    tr = run.add_argument_group(
        "trace (the paper's Fig. 4; off by default)",
        "after the point converges, rerun the floe chain with the converged a(x) fixed and"
        " record selected floes (position, velocity, instantaneous S_sd, contact force)"
        " over --trace-periods periods after n0 spin-up periods (floewave.trace)")
    tr.add_argument("--trace", type=_distances, metavar="X[,X...]",
                    help="trace the floes nearest to these distances from the ice edge [m],"
                         " e.g. 3,12,30 (the paper's)")
    tr.add_argument("--trace-every", type=int, default=10, metavar="STEPS",
                    help="time steps between samples (default 10: 10 ms at dt = 1e-3 s)")
    tr.add_argument("--trace-periods", type=int, default=None, metavar="N",
                    help="recorded wave periods (default: nT)")
    tr.add_argument("--trace-plot", type=Path, metavar="PNG",
                    help="draw Fig. 4 (|S_sd| versus time per traced floe) to this file")
    figs = sub.add_parser("figures", help="write the analytic figures (paper's Fig. 1)")
    figs.add_argument("--out", type=Path, required=True, metavar="DIR",
                      help="output directory (created if missing)")
    for p in (parser, run, figs):  # `--jso out.json` is refused, not taken for `--json`
        p.allow_abbrev = False
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``floewave`` console script; returns the exit status. A reader
    that stops early (``floewave figures --out figs | head -1``) ends the output quietly,
    with status 0: it has what it wanted."""
    try:
        status = _main(argv)
        sys.stdout.flush()
    except BrokenPipeError:
        quiet_stdout()
        return EXIT_OK
    return status


def _say(text: str) -> None:
    """Print a result line; when stdout's reader has gone, go on quietly (the point's
    ``--json``/``--plot`` files are still written)."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        quiet_stdout()


def _main(argv: list[str] | None) -> int:
    args = main_parser().parse_args(argv)
    if args.cmd == "figures":
        return figures_main(args.out)
    from .model import run_point  # lazy: numba and the kernels, 0.4 s; not for --help

    try:
        cfg = config_from_sets(args.set)
        cfg.check_physics()
        _check_outputs(args)
        if args.trace is not None and cfg.confined:
            raise ValueError("--trace: a confined point has no floe motion to trace")
    except (FloewaveError, ValueError) as exc:
        print(f"floewave: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT

    def progress(it: int, res: float, phase: str) -> None:
        print(f"  iteration {it:3d}  residual {res:.4g}  ({phase})", file=sys.stderr)

    print(COMPILING, file=sys.stderr, flush=True)
    compile_time = warm_up(cfg)
    print(f"floewave: kernels ready in {compile_time:.1f} s; running the point",
          file=sys.stderr, flush=True)
    try:
        r = run_point(cfg, progress=progress)
    except InvalidPointError as exc:
        print(f"floewave: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except FloewaveError as exc:
        print(f"floewave: point failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    _say(summary(cfg, r, compile_time))
    trace = None
    if args.trace is not None:
        from .trace import trace_point  # lazy: as .model (numba), 0.5 s

        try:
            trace = trace_point(cfg, r, distances=args.trace, every=args.trace_every,
                                periods=args.trace_periods)
        except FloewaveError as exc:
            print(f"floewave: trace failed: {exc}", file=sys.stderr)
            _write_outputs(args, cfg, r, None)      # the point itself is kept
            return EXIT_FAILED
        _say(f"trace: floes {', '.join(str(int(i) + 1) for i in trace.floes)} at x ="
              f" {', '.join(f'{d:.1f}' for d in trace.distance)} m, {len(trace.t)} samples"
              f" every {trace.every} steps; max |S_sd| ="
              f" {', '.join(f'{v:.3g}' for v in np.abs(trace.S_sd).max(axis=0))} W m-2")
    _write_outputs(args, cfg, r, trace)
    if args.trace_plot:
        figure4(trace, cfg, args.trace_plot)
    return EXIT_OK


def _write_outputs(args: argparse.Namespace, cfg: ModelConfig, r: Any, trace: Any) -> None:
    """The ``--json`` and ``--plot`` outputs of a computed point."""
    if args.json:
        out = {"config": cfg.to_dict(), "result": {k: _jsonable(v)
                                                   for k, v in r.to_dict().items()}}
        if trace is not None:
            out["trace"] = trace.to_dict()
        args.json.write_text(json.dumps(out, indent=1))
    if args.plot:
        plot(cfg, r, args.plot)


def figures_main(out: Path) -> int:
    """``floewave figures --out DIR``: write DIR/fig1_dispersion.png, print path and fits."""
    try:
        import matplotlib  # noqa: F401 - lazy: optional (plot extra): its absence is reported
    except ImportError:
        print("floewave: error: 'floewave figures' needs matplotlib (pip install matplotlib)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if out.exists() and not out.is_dir():
        print(f"floewave: error: cannot create output directory {str(out)!r}: it exists and"
              " is not a directory", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f"floewave: error: cannot create output directory {str(out)!r}:"
              f" {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    path = out / FIG1_NAME
    try:
        fits = figure1(path)
    except OSError as exc:
        print(f"floewave: error: cannot write {str(path)!r}: {exc.strerror or exc}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    _say(str(path))
    _say("high-frequency tail exponents m of omega^3/(c_g tanh^3 kh) = c omega^m"
         " (paper: ep lab 1.994, field 2.397):")
    for (case, disp), (m, _c, fmin, fmax) in fits.items():
        _say(f"  {case:5s} {disp}: m = {m:.3f}  (fit {fmin:.4g}-{fmax:.4g} Hz)")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
