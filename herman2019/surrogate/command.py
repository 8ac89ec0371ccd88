"""``herman2019 surrogate``: predict, build, validate.

    herman2019 surrogate --L_x 1.0 --T 1.3 --a0 0.02 --C_sd 0.05 --eps 0.5 --d_f 0.01 \\
        --dispersion ml                          # one point (each option takes several
                                                 # values, broadcast as numpy does)
    herman2019 surrogate --csv points.csv [--out predictions.csv]
    herman2019 surrogate --build [--grid TABLE ...] [--dir results/surrogate] --jobs 2
    herman2019 surrogate --validate [--dir results/surrogate] --jobs 2 [--docs docs]

``--build``: the node arrays from the grid's tables read together (:mod:`.build`; the
paper's grid and its extensions in L_x), the calibration sets' points run (resumable,
``DIR/<set>/runs.csv.gz`` for each set of :func:`.validate.set_names`'s "calibration":
``calibration``, ``validation`` and their axes sets, ``<name>_axes`` or, for a grid with
n levels of L_x other than three, ``<name>_axes_lx<n>``), the interpolation error's model
fitted on them (:func:`.validate.fit_scale`), ``DIR/surrogate.npz`` written.
``--validate``: the validation sets' points run (``DIR/blind/``,
``DIR/blind_axes[_lx<n>]/``), compared with the surrogate
(``DIR/validation.csv.gz``: every point's model values beside the surrogate's), the error
tables printed and, with ``--docs``, ``DOCS/surrogate.md`` and its figure written. Exit
status 0; 2 for a bad argument, a bad CSV or a point outside the box; 3 for a missing
file.
"""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd

from herman2019.surrogate.grid import AXES, OutsideBox
from herman2019.surrogate.model import QUANTITIES, SHIPPED, Surrogate

__all__ = ["command", "add_arguments", "DIR"]

ROOT = Path(__file__).resolve().parents[2]
#: The shipped surrogate's directory.
#: The tables the shipped surrogate is built from: the released grid (three floe
#: lengths) and its extensions to eight (configs/herman2019_lx*.toml).
GRIDS = ("herman2019", "herman2019-lx", "herman2019-lx125", "herman2019-lx25")
DIR = SHIPPED.parent


def add_arguments(p) -> None:
    for a in AXES:
        p.add_argument(f"--{a}", type=float, nargs="+", metavar="X")
    p.add_argument("--dispersion", nargs="+", metavar="NAME")
    p.add_argument("--csv", type=Path, help="points to predict: a CSV with columns"
                   f" {', '.join(AXES)}, dispersion")
    p.add_argument("--out", type=Path, help="write the predictions as CSV here")
    p.add_argument("--detail", action="store_true", help="also each SE's two parts")
    p.add_argument("--file", type=Path, help="the surrogate (default: the shipped one,"
                   " results/surrogate/surrogate.npz)")
    p.add_argument("--build", action="store_true", help="build it from --grid")
    p.add_argument("--validate", action="store_true", help="run and compare the"
                   " validation set")
    p.add_argument("--grid", nargs="+", default=[str(ROOT / "results" / g) for g in GRIDS],
                   help="the grid's tables, read together (default: the paper's grid and"
                   f" its extensions in floe length, {', '.join(GRIDS)} under results/)")
    p.add_argument("--dir", type=Path, default=DIR, help="where the surrogate, its runs"
                   " and its validation go (default: results/surrogate)")
    p.add_argument("--docs", type=Path, help="with --validate: write DOCS/surrogate.md")
    p.add_argument("--jobs", type=int, default=1, help="processes for the runs")


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def command(args) -> int:
    from sweep.errors import EXIT_OK, ConfigError
    if args.jobs < 1:
        raise ConfigError(f"--jobs {args.jobs}: at least 1")
    if args.build and args.validate:
        raise ConfigError("--build and --validate: one at a time (build, then validate)")
    if args.build:
        return _build(args)
    if args.validate:
        return _validate(args)
    sur = Surrogate.load(args.file)      # FileNotFoundError: exit status 3
    given = {a: getattr(args, a) for a in AXES}
    if args.csv is not None:
        if any(v is not None for v in given.values()) or args.dispersion:
            raise ConfigError("--csv and point options: give one")
        if not args.csv.is_file():
            raise FileNotFoundError(f"--csv {args.csv}: no such file")
        try:
            pts = pd.read_csv(args.csv)
        except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise ConfigError(f"--csv {args.csv}: not a CSV table ({exc})") from None
        missing = [c for c in (*AXES, "dispersion") if c not in pts]
        if missing:
            raise ConfigError(f"--csv {args.csv}: no column {', '.join(missing)}")
        params = {}
        for a in AXES:
            try:
                params[a] = pts[a].to_numpy(float)
            except (TypeError, ValueError):
                raise ConfigError(f"--csv {args.csv}: column {a} is not numeric") from None
        disp = pts["dispersion"].astype(str).to_numpy()
    else:
        missing = [f"--{a}" for a, v in given.items() if v is None]
        if missing or not args.dispersion:
            raise ConfigError("give every parameter (" + ", ".join(
                missing + ([] if args.dispersion else ["--dispersion"]))
                + " missing) or --csv FILE")
        params = {a: np.asarray(v, float) for a, v in given.items()}
        disp = np.asarray(args.dispersion, dtype=object)
    try:
        out = sur.predict(disp, detail=args.detail, **params)
    except (OutsideBox, ValueError) as exc:
        raise ConfigError(str(exc)) from None
    if args.out is not None:
        if not args.out.parent.is_dir():
            raise ConfigError(f"--out {args.out}: no directory {args.out.parent}")
        out.to_csv(args.out, index=False)
        print(f"{args.out}: {len(out)} points")
    else:
        with pd.option_context("display.max_columns", None, "display.width", 200):
            print(out.to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    return EXIT_OK


def _build(args) -> int:
    import sweep
    from herman2019.surrogate.build import build
    from herman2019.surrogate.validate import fit_scale, model_table, set_names, set_spec
    from sweep.errors import EXIT_OK, ConfigError
    try:
        table = pd.concat([sweep.load(g) for g in args.grid], ignore_index=True)
        sur = build(table, source=" + ".join(_relative(g) for g in args.grid),
                    commit=_commit())
    except (FileNotFoundError, ValueError) as exc:
        raise ConfigError(f"--grid {' '.join(map(str, args.grid))}: {exc}") from None
    names = set_names(sur.levels, "calibration")
    dirty = _dirty(args.dir)           # as the build starts (it writes args.dir), and ends
    runs = pd.concat([_run_set(name, sur.levels, args.dir, args.jobs) for name in names],
                     ignore_index=True)
    fit_scale(sur, model_table(runs))
    sur.meta["git_dirty"] = dirty or _dirty(args.dir)
    sur.meta["calibration"] = {"points": int(len(runs)),
                               "sets": {k: list(set_spec(k)) for k in names}}
    sur.save(args.dir / "surrogate.npz")
    print(f"{args.dir / 'surrogate.npz'}: {sur.meta['points']} nodes from"
          f" {' + '.join(map(str, args.grid))}"
          f" ({sur.meta['standard_errors']} SEs, model version"
          f" {', '.join(sur.meta['model_version'])}); the interpolation error fitted on"
          f" {len(runs)} off-grid runs (its scales: `herman2019 surrogate --validate`'s"
          " page)")
    return EXIT_OK


def _dirty(out: Path | None = None) -> bool:
    """Whether this checkout's tracked files differ from its commit, those under ``out``
    (the surrogate's own directory, which a build or a validation writes) apart."""
    spec = ["--", "."]
    if out is not None:
        try:
            spec.append(f":(exclude){Path(out).resolve().relative_to(ROOT)}")
        except ValueError:             # outside the checkout: nothing to leave out
            pass
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", *spec],
                          cwd=ROOT, capture_output=True, text=True).stdout.strip() != ""


def _run_set(name: str, levels, out: Path, jobs: int) -> pd.DataFrame:
    """The off-grid set ``name`` run (resumed) into OUT/NAME/runs.csv.gz; when this call
    computed runs, OUT/provenance.json records who made the set: model version, commit,
    clean tree, machine, date."""
    import datetime

    import floewave
    from herman2019.calibration import run_sample
    from herman2019.numbers import machine
    from herman2019.surrogate.validate import draw_set, set_spec
    kind, n, seed = set_spec(name)
    path = out / name / "runs.csv.gz"
    before = len(pd.read_csv(path)) if path.exists() else 0
    dirty = _dirty(out)                # as the runs start, and as they end
    runs = run_sample(draw_set(name, levels), [0], out / name, jobs)
    if len(runs) > before:
        prov_path = out / "provenance.json"
        prov = json.loads(prov_path.read_text()) if prov_path.exists() else {}
        dirty = dirty or _dirty(out)
        prov[name] = {"points": int(len(runs)), "kind": kind, "draw_seed": seed,
                      "model_version": str(floewave.MODEL_VERSION), "commit": _commit(),
                      "git_dirty": dirty, "machine": machine(),
                      "date": datetime.date.today().isoformat()}
        prov_path.write_text(json.dumps(prov, indent=1, sort_keys=True) + "\n")
    return runs


def _relative(path) -> str:
    try:
        return str(Path(path).resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def _validate(args) -> int:
    from herman2019.surrogate.page import make_page
    from herman2019.surrogate.validate import compare, model_table, set_names
    from sweep.errors import EXIT_OK
    sur = Surrogate.load(args.dir / "surrogate.npz")
    runs = pd.concat([_run_set(name, sur.levels, args.dir, args.jobs)
                      for name in set_names(sur.levels, "validation")], ignore_index=True)
    cmp = compare(sur, model_table(runs))
    keep = [*AXES, "dispersion", "group", "status", "zone", "p_zone"] + [
        c for q in QUANTITIES for c in (q, q + "_se", q + "_sur", q + "_sur_se", q + "_z")]
    cmp[keep].to_csv(args.dir / "validation.csv.gz", index=False)
    prov_path = args.dir / "provenance.json"
    prov = json.loads(prov_path.read_text()) if prov_path.exists() else None
    names = list(set_names(sur.levels, "validation"))
    prov = {k: v for k, v in (prov or {}).items()
            if k in names or k in sur.meta.get("calibration", {}).get("sets", {})}
    text = make_page(sur, cmp, args.docs, _relative(args.dir), prov or None)
    print(text)
    return EXIT_OK
