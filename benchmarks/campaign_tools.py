"""Time the rest of the tool on a real campaign store: load, status, validate, validate
--deep, export, load_xarray, figures and report, each in a fresh interpreter, with its wall
time and peak memory (``/usr/bin/time``'s maximum resident set size).

    python benchmarks/campaign_tools.py STORE [--out DIR] [--skip NAME ...]

STORE is a campaign store (for the paper's grid: the eight shard stores merged by
``sweep merge``, results/herman2019/README.md). Outputs go to DIR (a temporary directory by
default) and are removed afterwards. Prints one Markdown row per tool.
"""
from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def tools(store: Path, out: Path) -> dict[str, list[str]]:
    py = sys.executable
    return {
        "sweep.load": [py, "-c", f"import sweep; df = sweep.load({str(store)!r}); print(len(df))"],
        "sweep status": ["sweep", "status", str(store)],
        "sweep validate": ["sweep", "validate", str(store)],
        "sweep validate --deep": ["sweep", "validate", "--deep", str(store)],
        "sweep export": ["sweep", "export", str(store), "--output", str(out / "table.csv.gz")],
        "sweep.load_xarray": [py, "-c", "import sweep; ds = sweep.load_xarray("
                              f"{str(store)!r}); print(dict(ds.sizes))"],
        "sweep figures": ["sweep", "figures", str(store), "--out", str(out / "figs")],
        "sweep report": ["sweep", "report", str(store), "--out", str(out / "report.html")],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--skip", action="append", default=[])
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="campaign_tools_"))
    out.mkdir(parents=True, exist_ok=True)
    print(f"store {args.store}: {args.store.stat().st_size / 1e6:.0f} MB")
    print("| tool | wall [s] | peak memory [MB] | exit | output |")
    print("|---|---|---|---|---|")
    try:
        for name, cmd in tools(args.store, out).items():
            if name in args.skip:
                continue
            t0 = time.perf_counter()
            p = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True)
            wall = time.perf_counter() - t0
            rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
            made = ""
            if p.returncode:
                made = (p.stderr.strip().splitlines() or [""])[0][:60]
            elif name == "sweep export":
                made = f"{(out / 'table.csv.gz').stat().st_size / 1e6:.1f} MB"
            elif name == "sweep report" and (out / "report.html").exists():
                made = f"{(out / 'report.html').stat().st_size / 1e6:.1f} MB page"
            elif name == "sweep figures" and (out / "figs").exists():
                made = f"{len(list((out / 'figs').glob('*.png')))} PNG"
            else:
                made = (p.stdout.strip().splitlines() or [""])[-1][:60]
            print(f"| {name} | {wall:.1f} | {int(rss.group(1)) / 1024 if rss else float('nan'):.0f}"
                  f" | {p.returncode} | {made} |", flush=True)
    finally:
        if args.out is None:
            shutil.rmtree(out, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
