"""What ``sweep status`` reports of a store: counts, failures, slow points, runs.

As data (:func:`status_report`, ``--json``) and as text (:func:`status_text`).
"""
from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sweep.analysis.load import journal_points, load, store_attrs, store_runs
from sweep.arguments import plural
from sweep.store.lock import writer_alive

__all__ = ["status_report", "status_text", "mark_dead_runs"]


def swept_values(row: Any, dims: Sequence[str]) -> dict[str, Any]:
    """A point's swept values as plain Python values (for text and JSON)."""
    out = {}
    for k in dims:
        v = getattr(row, k)
        out[k] = v if isinstance(v, str) else float(v)
    return out


def swept_text(swept: dict[str, Any]) -> str:
    return " ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in swept.items())


def status_report(path: Path, slowest: int = 5) -> dict[str, Any]:
    """The data behind ``sweep status``: counts, the points that did not converge or
    failed (with their swept values), the slowest points, and one line per run."""
    df = load(path)
    journaled = journal_points(path)
    attrs = store_attrs(path)
    campaign = json.loads(attrs["campaign_json"])
    dims = list(campaign["sweep"])
    total = 1
    for values in campaign["sweep"].values():
        total *= len(values)
    # a shard's store (``sweep run --shard K/N``) counts against its shard of the grid: the
    # size its latest run recorded
    run_attrs = store_runs(path)
    latest = max(run_attrs, key=lambda r: int(r["index"]), default={})
    shard = str(latest.get("shard", "")) or None
    if shard is not None:
        total = int(latest.get("shard_points", total))
    counts = {str(k): int(v) for k, v in df["status"].value_counts().items() if v}
    failures = [{"hash": r.hash[:12], "status": str(r.status), "swept": swept_values(r, dims),
                 "message": r.message.splitlines()[0] if r.message else ""}
                for r in df[df["status"].isin(["failed", "invalid", "crashed",
                                               "timeout"])].itertuples()]
    not_converged = [{"hash": r.hash[:12], "swept": swept_values(r, dims),
                      "iterations": int(r.iterations), "residual": float(r.residual)}
                     for r in df[df["status"] == "not_converged"].itertuples()]
    slow = df.sort_values("wall_time", ascending=False).head(slowest)
    runs = [{"index": int(r["index"]), "started": str(r.get("started", "")),
             "ended": str(r.get("ended", "")), "outcome": str(r.get("outcome", "")),
             "mpi_size": int(r.get("mpi_size", 1)), "host": str(r.get("host", "")),
             "stored": int((df["run"] == r["index"]).sum())} for r in run_attrs]
    mark_dead_runs(path, runs)
    return {"store": str(path), "grid_points": total, "shard": shard, "stored": len(df),
            "journaled": journaled,
            "remaining": max(total - len(df), 0), "counts": counts, "failures": failures,
            "not_converged": not_converged,
            "slowest": [{"hash": r.hash[:12], "wall_time": float(r.wall_time),
                         "status": str(r.status), "host": r.host, "rank": int(r.rank),
                         "swept": swept_values(r, dims)}
                        for r in slow.itertuples()],
            "runs": runs,
            "total_wall_time": float(df["wall_time"].sum()) if len(df) else 0.0}


def mark_dead_runs(path: Path, runs: list[dict[str, Any]]) -> None:
    """A run recorded as "running" whose writer is gone (killed: SIGKILL, a double
    Ctrl-C under mpiexec) is shown as such, not as running; only the last run can be
    live, and only while its writer holds the store's lock."""
    for i, r in enumerate(runs):
        if r["outcome"] != "running" or r["ended"]:
            continue
        if i == len(runs) - 1 and writer_alive(path):
            continue
        r["outcome"] = ("died: its writer was killed; the same command resumes the"
                        " campaign")


def status_text(rep: dict[str, Any]) -> str:
    """:func:`status_report`'s data as the lines ``sweep status`` prints."""
    out: list[str] = []
    of = f" (shard {rep['shard']} of the grid)" if rep.get("shard") else ""
    out.append(f"{rep['store']}: {rep['stored']}/{rep['grid_points']} points{of} stored,"
               f" {rep['remaining']} remaining; point wall time {rep['total_wall_time']:.1f} s")
    if rep["journaled"] is not None and rep["journaled"] > rep["stored"]:
        extra = rep["journaled"] - rep["stored"]
        out.append(f"  the journal holds {rep['journaled']} points: {extra}"
                   " more than the file (a live run mid-commit, or a killed one: its next run"
                   " writes them)")
    for k, v in sorted(rep["counts"].items()):
        out.append(f"  {k:16s} {v}")
    if rep["failures"]:
        out.append("failed / invalid:")
        for f in rep["failures"]:
            out.append(f"  {f['hash']} {f['status']:8s} {swept_text(f['swept'])}:"
                       f" {f['message']}")
    if rep["not_converged"]:
        out.append("not converged (error bars above their targets, or not stationary; the"
                   " estimate so far is stored, with its error bars):")
        for f in rep["not_converged"]:
            out.append(f"  {f['hash']} {swept_text(f['swept'])}: {f['iterations']} iterations,"
                       f" residual {f['residual']:.3g}")
    if rep["slowest"]:
        out.append("slowest:")
        for s in rep["slowest"]:
            out.append(f"  {s['hash']} {s['wall_time']:9.2f} s  {s['status']}  rank {s['rank']}"
                       f" on {s['host']}  {swept_text(s['swept'])}")
    if rep["runs"]:
        out.append("runs:")
        for r in rep["runs"]:
            end = r["ended"][:19] or ("(running)" if r["outcome"] == "running"
                                      else "(no end recorded)")
            out.append(f"  {r['index']}: {r['started'][:19]} to {end},"
                       f" {r['mpi_size']} rank(s) on {r['host']}, {plural(r['stored'], 'point')}"
                       f" stored: {r['outcome']}")
    return "\n".join(out)
