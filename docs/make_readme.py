"""Regenerate the README's measured sample output: the demo campaign's lines and the test
tiers' counts and times, each between its markers, with the machine, date and model
version that made them.

    python docs/make_readme.py --demo     # runs `mpiexec -n 3 sweep run configs/demo.toml`
    python docs/make_readme.py --tests    # times `python -m pytest -q -n 2` (about a minute)

Both are stochastic timings of this machine. ``tests/test_readme_fresh.py`` fails when a
block was made at another model version than this checkout's (rerun this script), so a
model change cannot leave them stale silently.
"""
from __future__ import annotations

import argparse
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


def machine() -> str:
    """The CPU's model name and vector width, as the project names every speed figure."""
    text = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    name = next((ln.split(":", 1)[1].strip() for ln in text.splitlines()
                 if ln.startswith("model name")), platform.processor() or "unknown CPU")
    width = "AVX-512" if "avx512f" in text else "AVX2" if "avx2" in text else "no AVX2"
    return f"{name} with {width}"


def stamp() -> str:
    import floewave

    return (f"model version {floewave.MODEL_VERSION}, {machine()},"
            f" {datetime.now(UTC).date().isoformat()}")


def replace_block(text: str, name: str, body: str) -> str:
    """``body`` between ``<!-- NAME: ... -->`` and ``<!-- /NAME -->`` (the opening marker's
    text replaced by the stamp)."""
    pattern = re.compile(rf"<!-- {name}: [^>]*-->\n.*?<!-- /{name} -->", re.S)
    if not pattern.search(text):
        raise SystemExit(f"README.md: no <!-- {name}: ... --> block")
    return pattern.sub(lambda m: f"<!-- {name}: {stamp()} -->\n{body}<!-- /{name} -->",
                       text, count=1)


def demo_output() -> str:
    launcher = shutil.which("mpiexec")
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ([launcher, "-n", "3"] if launcher else []) + [
            sys.executable, "-m", "sweep", "run", str(ROOT / "configs" / "demo.toml"),
            "--store", str(Path(tmp) / "demo.h5")]
        done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, cwd=tmp)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} exited {done.returncode}:\n{done.stdout}")
    lines = done.stdout.replace(tmp + "/", "").strip()
    return f"```text\n{lines}\n```\n"


def tests_line() -> str:
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "2"], cwd=ROOT,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    last = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
    if done.returncode != 0:
        raise SystemExit(f"the fast tier failed: {last}")
    return f"Fast tier: `{last.strip('= ')}`, {wall:.0f} s wall.\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--demo", action="store_true", help="the demo campaign's output")
    p.add_argument("--tests", action="store_true", help="the fast tier's count and time")
    args = p.parse_args(argv)
    text = README.read_text()
    if args.demo:
        text = replace_block(text, "demo-output", demo_output())
    if args.tests:
        text = replace_block(text, "fast-tier", tests_line())
    README.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
