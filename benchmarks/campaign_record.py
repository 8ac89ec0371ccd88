"""Ship a campaign's result without its store: one shard's table and its provenance.

    python benchmarks/campaign_record.py STORE --shard K/N --log RUN.log [--log ...]
                                         [--out results/herman2019]

Writes ``OUT/shard-K-of-N.csv.gz`` (``sweep export``: every scalar with its standard
error, hash, status, parameters, config_json and provenance per point; floats as their
shortest round-trip text, so ``sweep.load(OUT)`` reads the stored values bit for bit) and
updates ``OUT/provenance.json`` with this shard's entry: model version, commit, machine,
every ``sweep run`` on the store (start, end, outcome, ranks) with, from its log (a
``sweep run`` under bash's ``time``, as ``results/herman2019/run_shard.sh`` starts it), the
points stored, the master's CPU share and the CPU seconds of every rank; the points per
status; the store's and journal's size on disk.

A store of gigabytes never goes into git: the table of a 3,000-point shard is about a
megabyte.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import sweep  # noqa: E402
from sweep.analysis.export import export_table  # noqa: E402
from sweep.analysis.load import store_attrs, store_runs  # noqa: E402

TIME = re.compile(r"\[time\] real ([0-9.]+) s, user ([0-9.]+) s, sys ([0-9.]+) s")
SUMMARY = re.compile(r"sweep: (\d+) grid points: (\d+) already stored, (\d+) stored now"
                     r".* in ([0-9.]+) s; master CPU ([0-9.]+)% of a core")
STOPPED = re.compile(r"campaign stopped by (\S+): (\d+) points stored")


def machine() -> str:
    """CPU model and vector width, as ``benchmarks/docs_numbers.py`` names them."""
    from docs_numbers import machine as m
    return m()


def parse_log(path: Path) -> dict:
    """What one ``sweep run`` log says: points stored, master CPU share, CPU of all ranks."""
    text = path.read_text(errors="replace")
    out: dict = {"log": path.name}
    m = TIME.search(text)
    if m:
        out.update(wall_s=float(m.group(1)), cpu_s=float(m.group(2)) + float(m.group(3)))
    m = SUMMARY.search(text)
    if m:
        out.update(already_stored=int(m.group(2)), stored=int(m.group(3)),
                   loop_s=float(m.group(4)), master_cpu_share=float(m.group(5)) / 100)
    m = STOPPED.search(text)
    if m:
        out.update(stopped_by=m.group(1), stored=int(m.group(2)))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store", type=Path)
    ap.add_argument("--shard", required=True, help="K/N")
    ap.add_argument("--log", action="append", default=[], type=Path,
                    help="the log of each sweep run on the store, oldest first")
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "herman2019")
    args = ap.parse_args()
    k, n = (int(v) for v in args.shard.split("/"))
    args.out.mkdir(parents=True, exist_ok=True)
    table = args.out / f"shard-{k}-of-{n}.csv.gz"
    rows = export_table(args.store, table)
    df = sweep.load(table)
    attrs = store_attrs(args.store)
    runs = store_runs(args.store)
    logs = [parse_log(p) for p in args.log]
    keep = ("started", "ended", "outcome", "git_commit", "git_dirty", "host", "mpi_size",
            "model_version", "numba", "numpy", "python")
    entry = {
        "table": table.name, "points": rows,
        "status": {str(s): int(c) for s, c in df["status"].value_counts().items() if c},
        "model_version": sorted({r.get("model_version") for r in runs}),
        "machine": machine(),
        "runs": [{key: r.get(key) for key in keep} | (logs[i] if i < len(logs) else {})
                 for i, r in enumerate(runs)],
        "cpu_s_all_ranks": sum(lg.get("cpu_s", 0.0) for lg in logs) or None,
        "model_wall_s_sum": float(df["model_wall_time"].sum()),
        "store_bytes": os.path.getsize(args.store),
        "journal_bytes": (os.path.getsize(str(args.store) + ".journal")
                          if os.path.exists(str(args.store) + ".journal") else None),
        "table_bytes": os.path.getsize(table),
    }
    prov_path = args.out / "provenance.json"
    prov = json.loads(prov_path.read_text()) if prov_path.exists() else {}
    prov.setdefault("campaign", "configs/herman2019.toml")
    prov["campaign_hash"] = attrs.get("campaign_hash")
    prov.setdefault("shards", {})[f"{k}/{n}"] = entry
    prov_path.write_text(json.dumps(prov, indent=1, sort_keys=True) + "\n")
    print(f"{table}: {rows} points, {entry['table_bytes'] / 1e6:.2f} MB; status"
          f" {entry['status']}; runs {len(runs)}; CPU of all ranks {entry['cpu_s_all_ranks']}"
          f" s; store {entry['store_bytes'] / 1e6:.0f} MB + journal"
          f" {(entry['journal_bytes'] or 0) / 1e6:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
