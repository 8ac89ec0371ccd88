"""Ship a campaign's result without its store: one shard's table and its provenance.

    herman2019 record STORE --shard K/N --log RUN.log [--log ...] [--out results/herman2019]

Writes ``OUT/shard-K-of-N.csv.gz`` (``sweep export``: every scalar with its standard
error, hash, status, parameters, config_json and provenance per point; floats as their
shortest round-trip text, so ``sweep.load(OUT)`` reads the stored values bit for bit),
``OUT/profiles/profiles-K-of-N.nc`` (``sweep export --profiles``: a/a0 and its SE, x, mean
gap and contact fraction along the ice for every point with results; netCDF-4 with CF
attributes, ``sweep.load_profiles(OUT)`` or xarray alone reads it) and
updates ``OUT/provenance.json`` with this shard's entry: model version, commit, machine,
every ``sweep run`` on the store (start, end, outcome, ranks) with, from its log (a
``sweep run`` under bash's ``time``, as ``results/herman2019/run_shard.sh`` starts it), the
points stored, the master's CPU share and the CPU seconds of every rank; the points per
status; the store's and journal's size on disk.

A store of gigabytes never goes into git: the table of a 3,000-point shard is about a
megabyte.
"""
from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any

import pandas as pd

import sweep
from herman2019.numbers import machine
from sweep.analysis.export import export_profiles, export_table
from sweep.analysis.load import load_profile, store_attrs, store_runs
from sweep.config import load_campaign, parse_campaign
from sweep.errors import ConfigError

__all__ = ["RESULTS", "parse_log", "parse_plan", "problems", "summary", "command"]

#: Where the shipped campaign's tables and provenance go (``--out``'s default).
RESULTS = Path(__file__).resolve().parents[1] / "results" / "herman2019"

TIME = re.compile(r"\[time\] real ([0-9.]+) s, user ([0-9.]+) s, sys ([0-9.]+) s")
SUMMARY = re.compile(r"sweep: (\d+) grid points: (\d+) already stored, (\d+) stored now"
                     r".* in ([0-9.]+) s; master CPU ([0-9.]+)% of a core")
STOPPED = re.compile(r"campaign stopped by (\S+): (\d+) points stored")


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


def problems(store: Path, df, out: Path) -> dict:
    """Every point that is not ``converged``/``converged_noisy``, with why, into ``out``
    (CSV): a ``not_converged`` point stopped (at ``max_average`` windows averaged, or at
    ``max_iterations``) with an error bar still above its target (max_i SE(a_i) / a0
    against ``target_stderr``, SE(W_c) against ``target_W_c_stderr``, from the store's
    profiles) or without a stationary stretch; a
    ``failed``/``invalid``/``crashed``/``timeout`` point carries its message. Returns the
    counts per reason."""
    rows = []
    for _, r in df[~df["status"].isin(["converged", "converged_noisy"])].iterrows():
        cfg = json.loads(r["config_json"])
        why = str(r["message"])
        se_a = float("nan")
        if str(r["status"]) == "not_converged":
            prof = load_profile(store, r["hash"])
            se_a = float(prof["a_stderr"].max()) / r["a0"]
            parts = []
            if se_a > cfg["target_stderr"]:
                parts.append(f"SE(a) {100 * se_a:.2f} % of a0 > {100 * cfg['target_stderr']:g} %")
            if r["W_c_n"] >= 2 and r["W_c_stderr"] > cfg["target_W_c_stderr"]:
                parts.append(f"SE(W_c) {r['W_c_stderr']:.2f} m > {cfg['target_W_c_stderr']:g} m")
            why = "; ".join(parts) or "no stationary stretch (MSER / halves test)"
            why = f"{int(r['iterations'])} windows: " + why
        rows.append({"hash": r["hash"], **{c: r[c] for c in ("L_x", "T", "a0", "C_sd", "eps",
                                                             "d_f", "dispersion")},
                     "status": str(r["status"]), "se_a_max_rel": se_a,
                     "W_c_stderr": r["W_c_stderr"], "reason": why})
    table = pd.DataFrame(rows, columns=["hash", "L_x", "T", "a0", "C_sd", "eps", "d_f",
                                        "dispersion", "status", "se_a_max_rel", "W_c_stderr",
                                        "reason"])
    table.to_csv(out, index=False)
    kinds = table["reason"].str.replace(r"[0-9.]+", "#", regex=True)
    return {str(k): int(v) for k, v in kinds.value_counts().items()}


#: The markers of a results README's block that ``record`` keeps equal to :func:`summary`.
SUMMARY_START, SUMMARY_END = "<!-- herman2019 record --summary -->\n", "<!-- end of summary -->"
PLAN = re.compile(r"projected: ([0-9.]+) core-hours")
RATE = re.compile(r"kernel: ([0-9.e+]+) floe-steps/s per core on average")


def parse_plan(path: Path) -> dict:
    """What a ``sweep plan`` log says: the projected core-hours and the calibrated rate."""
    if not path.is_file():
        raise ConfigError(f"--plan {path}: no such file")
    text = path.read_text(errors="replace")
    m, r = PLAN.search(text), RATE.search(text)
    if not m:
        raise ConfigError(f"--plan {path}: no 'projected: ... core-hours' line in it")
    return {"core_hours": float(m.group(1)), "rate": float(r.group(1)) if r else None,
            "log": path.name, "machine": machine()}


def campaign_points(prov: dict) -> int | None:
    """How many points the campaign of a ``provenance.json`` has: its ``grid_points``
    (recorded from the store's campaign), else the size of its ``campaign`` file in this
    checkout, else None."""
    if prov.get("grid_points"):
        return int(prov["grid_points"])
    path = Path(__file__).resolve().parents[1] / str(prov.get("campaign", ""))
    if prov.get("campaign") and path.is_file():
        try:
            return load_campaign(path).size
        except ConfigError:
            return None
    return None


def summary(prov: dict, grid_points: int | None = None) -> str:
    """The run of a shipped campaign from its ``provenance.json`` as a Markdown table:
    shards and points (of ``grid_points``, default its campaign's: :func:`campaign_points`),
    statuses, runs (stops and resumes), commits and clean trees, CPU of all ranks against
    the projection, wall time, master share, sizes, machines."""
    shards = prov.get("shards", {})
    if not shards:
        return "no shard recorded"
    if grid_points is None:
        grid_points = campaign_points(prov)
    n_total = {int(k.split("/")[1]) for k in shards}
    points = sum(s["points"] for s in shards.values())
    status: dict[str, int] = {}
    for s in shards.values():
        for k, v in s["status"].items():
            status[k] = status.get(k, 0) + v
    runs = [r for s in shards.values() for r in s["runs"]]
    resumed = sorted((k for k, s in shards.items() if len(s["runs"]) > 1),
                     key=lambda k: int(k.split("/")[0]))
    commits = sorted({str(r.get("git_commit")) for r in runs})
    dirty = sorted({str(r.get("git_dirty")) for r in runs})
    cpu = sum(s.get("cpu_s_all_ranks") or 0.0 for s in shards.values())
    wall = sum(r.get("wall_s", 0.0) for r in runs)
    share = [r["master_cpu_share"] for r in runs if "master_cpu_share" in r]
    plan = prov.get("plan")
    prof_mb = sum(s["profiles"]["bytes"] for s in shards.values() if "profiles" in s) / 1e6
    rows = [
        ("shards", f"{len(shards)} of {'/'.join(str(n) for n in sorted(n_total))}: "
         + ", ".join(sorted(shards, key=lambda k: int(k.split("/")[0])))),
        ("points", f"{points:,}" + (f" of {grid_points:,}" if grid_points else "")),
        ("status", "; ".join(f"{k} {v:,}" for k, v in sorted(status.items()))),
        ("runs", f"{len(runs)}" + (f"; shards run more than once (stopped and resumed):"
                                   f" {', '.join(resumed)}" if resumed else
                                   "; every shard in one run")),
        ("commit", f"{', '.join(c[:12] for c in commits)}; git_dirty {', '.join(dirty)}"),
        ("CPU, all ranks", f"{cpu:,.0f} s = **{cpu / 3600:.2f} core-hours**"
         + (f" against `sweep plan`'s {plan['core_hours']:.2f} for the whole grid before the"
            f" run ({cpu / 3600 / plan['core_hours'] * (grid_points or points) / points:.2f}x"
            " the projection, scaled to the points run)" if plan else "")),
        ("wall", f"{wall / 3600:.2f} h (sum over runs)"),
        ("master", f"{100 * min(share):.1f}-{100 * max(share):.1f} % of a core"
         if share else "not logged"),
        ("on disk", f"stores {sum(s['store_bytes'] for s in shards.values()) / 1e6:,.0f} MB"
         f" + journals {sum(s.get('journal_bytes') or 0 for s in shards.values()) / 1e6:,.0f}"
         f" MB; shipped tables {sum(s['table_bytes'] for s in shards.values()) / 1e6:.1f} MB"
         + (f", profiles {prof_mb:.1f} MB" if prof_mb else "")),
        ("machine", _machines(shards)),
    ]
    return "\n".join(["| | |", "|---|---|"] + [f"| {a} | {b} |" for a, b in rows])


def remake_readme(out: Path) -> bool:
    """Remake the summary block of ``OUT/README.md`` from ``OUT/provenance.json``, if the
    README has one (between SUMMARY_START and SUMMARY_END); True when it had."""
    readme = out / "README.md"
    if not (readme.exists() and SUMMARY_START in (text := readme.read_text())
            and SUMMARY_END in text[text.index(SUMMARY_START):]):
        return False
    i = text.index(SUMMARY_START) + len(SUMMARY_START)
    j = text.index(SUMMARY_END, i)
    prov = json.loads((out / "provenance.json").read_text())
    readme.write_text(text[:i] + summary(prov) + "\n" + text[j:])
    return True


def _machines(shards: dict) -> str:
    """Each CPU the shards ran on, with its shards and CPU seconds per point (a row is
    reproduced bit for bit only on a CPU of its kind; on another, within its error bar)."""
    by: dict[str, list[str]] = {}
    for k in sorted(shards, key=lambda k: int(k.split("/")[0])):
        by.setdefault(shards[k]["machine"], []).append(k)
    parts = []
    for m, ks in sorted(by.items(), key=lambda kv: int(kv[1][0].split("/")[0])):
        cpu = sum(shards[k].get("cpu_s_all_ranks") or 0.0 for k in ks)
        pts = sum(shards[k]["points"] for k in ks)
        parts.append(f"{m}: shard{'s' if len(ks) > 1 else ''} {', '.join(ks)}"
                     + (f" ({cpu / pts:.2f} CPU-s per point)" if cpu and pts else ""))
    return "; ".join(parts)


def _campaign_file(attrs: dict) -> str | None:
    """``configs/<name>.toml`` of the store's campaign (its ``[run] name``), if it says."""
    import tomllib
    try:
        name = tomllib.loads(str(attrs.get("campaign_toml", ""))).get("run", {}).get("name")
    except tomllib.TOMLDecodeError:
        return None
    return f"configs/{name}.toml" if name else None


def _plain(o):
    """numpy scalars (a store's attributes) as Python values for JSON."""
    return o.item() if hasattr(o, "item") else str(o)


def command(args: Any) -> int:
    """``herman2019 record``: the shard's table and its provenance entry (status 0; 2 for a
    bad ``--shard``); with ``--summary``, only the run's summary of ``--out``."""
    if getattr(args, "summary", False):
        prov_path = args.out / "provenance.json"
        if not prov_path.exists():
            raise ConfigError(f"--summary: no {prov_path}")
        print(summary(json.loads(prov_path.read_text())))
        return 0
    if args.store is None or args.shard is None:
        raise ConfigError("herman2019 record: give STORE and --shard K/N (or --summary)")
    plan = parse_plan(args.plan) if getattr(args, "plan", None) else None   # before writing
    for log in args.log:
        if not log.is_file():
            raise ConfigError(f"--log {log}: no such file")
    try:
        k, n = (int(v) for v in args.shard.split("/"))
    except ValueError:
        raise ConfigError(f"--shard {args.shard}: expected K/N, e.g. 0/8") from None
    attrs = store_attrs(args.store)
    campaign = _campaign_file(attrs)
    prov_path = args.out / "provenance.json"
    if prov_path.exists():             # another campaign's directory: refuse, write nothing
        have = json.loads(prov_path.read_text()).get("campaign_hash")
        if have and have != attrs.get("campaign_hash"):
            raise ConfigError(f"{args.store} is campaign {campaign or '?'} (hash"
                              f" {str(attrs.get('campaign_hash'))[:12]}); {args.out} records"
                              f" campaign hash {have[:12]}: give the --out of its campaign")
    args.out.mkdir(parents=True, exist_ok=True)
    table = args.out / f"shard-{k}-of-{n}.csv.gz"
    rows = export_table(args.store, table)
    df = sweep.load(table)
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
    (args.out / "profiles").mkdir(exist_ok=True)     # not tables of points: beside them
    profiles = args.out / "profiles" / f"profiles-{k}-of-{n}.nc"
    entry["profiles"] = {"file": f"profiles/{profiles.name}",
                         "points": export_profiles(args.store, profiles, df),
                         "bytes": os.path.getsize(profiles)}
    (args.out / "problems").mkdir(exist_ok=True)
    entry["problems"] = problems(args.store, df,
                                 args.out / "problems" / f"problems-{k}-of-{n}.csv")
    prov = json.loads(prov_path.read_text()) if prov_path.exists() else {}
    if plan is not None:
        prov["plan"] = plan
    prov["campaign"] = campaign or prov.get("campaign", "configs/herman2019.toml")
    prov["campaign_hash"] = attrs.get("campaign_hash")
    try:
        prov["grid_points"] = parse_campaign(str(attrs.get("campaign_toml", ""))).size
    except ConfigError:
        prov.pop("grid_points", None)
    prov.setdefault("shards", {})[f"{k}/{n}"] = entry
    prov_path.write_text(json.dumps(prov, indent=1, sort_keys=True, default=_plain) + "\n")
    remake_readme(args.out)
    print(f"{table}: {rows} points, {entry['table_bytes'] / 1e6:.2f} MB; status"
          f" {entry['status']}; runs {len(runs)}; CPU of all ranks"
          f" {entry['cpu_s_all_ranks'] or 0:.1f} s;"
          f" profiles {entry['profiles']['bytes'] / 1e6:.2f} MB;"
          f" store {entry['store_bytes'] / 1e6:.0f} MB + journal"
          f" {(entry['journal_bytes'] or 0) / 1e6:.0f} MB")
    return 0
