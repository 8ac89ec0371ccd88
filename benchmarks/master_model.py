"""The master at scale, modelled: the real master loop fed by simulated workers.

    python benchmarks/master_model.py [--workers 7 15 31 63 1024 4096] [--cost-scale 1 0.25]
                                      [--shards 1 32] [--seconds 15] [--check RECORD.json]
                                      [--write-path inline none forward]

The model is not an equation but the master itself: ``sweep run``'s own code (the
scheduling loop of :class:`sweep.run.master.Master`, its group commits into a real HDF5
store and journal, its depth rule) over a transport whose W workers are simulated in the
master's process. A worker "computes" a task for the point's replayed cost (the real
cost distribution, ``benchmarks/data/point_costs.json``, times ``--cost-scale``, as
``sweep.testing:replay_point`` sleeps it) and its result arrives when that time has
passed in real time; the master finds it by the same backoff polling as under MPI. What
the workers would do (build the result, pickle it) is done in the master's process too,
and its CPU is subtracted from the master's; the master's own share of a message, the
unpickling, stays in. So the master's CPU, its batches and the workers' waits are
measured on the real code at any W, while only the MPI transport is left out (checked
against ``bench_master.py --scale`` at 8-64 ranks: ``--check``).

``--shards S``: the campaign split into S shards (``sweep run --shard K/S``), each with its
own master and store on its own node, W/S workers each; the shards are independent, so one
shard's master is simulated with W/S workers and its figures are each master's.

``--write-path none``: the master's write path taken out (:func:`scheduling_only`): what
a master whose store is written by another process would spend itself (docs/cluster.md);
``forward``: the same with each result read only for its header (hash, status, wall
time) and its record passed on as bytes (to ``/dev/null``, for a writer's pipe).

Reported per run: workers, shards, stored points/s per master and in all, the master's CPU
share and CPU per point, the hand-out latency (a worker's wait from finishing a point to
being handed the next) and the workers' idle share while there is work to hand out.
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import heapq
import json
import os
import pickle
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
COSTS = ROOT / "benchmarks" / "data" / "point_costs.json"
GRID = ROOT / "configs" / "herman2019.toml"


class SimTransport:
    """W simulated workers: a task sent at time t to a worker free at f completes at
    max(t, f) + cost; ``poll`` returns completed results in completion order."""

    def __init__(self, workers: int, scale: float, forward: bool = False,
                 packed: bool = False) -> None:
        from sweep.protocol import Kind
        from sweep.provenance import environment
        from sweep.run.compute import compute_point, resolve_compute
        self.Kind = Kind
        self.compute_point = compute_point
        # replay_point's record (the per-replica profiles too) without its sleep
        os.environ["FLOEWAVE_REPLAY_SCALE"] = "0"
        self.fn = resolve_compute("sweep.testing:replay_point")
        self.workers = list(range(1, workers + 1))
        env = environment(with_git=False)
        self.worker_env = {w: env for w in self.workers}
        self.compute = "sweep.testing:replay_point"
        self.scale = scale
        #: ``--write-path forward``: a result travels as a small header (hash, status,
        #: wall time) plus its record's pickled bytes, which the master passes on unread
        self.forward = forward
        #: a result as sweep's workers send it: :class:`sweep.protocol.Packed`
        self.packed = packed
        self._sink = os.open(os.devnull, os.O_WRONLY) if forward else -1
        self.free_at = {w: 0.0 for w in self.workers}
        self.events: list[tuple[float, int, int, bytes]] = []
        self.seq = 0
        self.worker_cpu = 0.0  # [s] CPU spent here on the workers' behalf: subtracted
        self.intervals: dict[int, list[tuple[float, float]]] = {w: [] for w in self.workers}
        from sweep.run.transport import Backoff
        self._backoff = Backoff()

    def cost(self, config: dict[str, Any]) -> float:
        from sweep.testing import replay_cost
        return replay_cost(config) * self.scale

    def start(self) -> None:
        pass

    def warm_up(self, configs):
        return 0.0, ""

    def send(self, worker: int, task) -> None:
        now = time.monotonic()
        pickle.dumps(task, protocol=pickle.HIGHEST_PROTOCOL)  # the master's side of a task
        c0 = time.process_time()
        cost = self.cost(task.config)
        out = self.compute_point(task, self.fn, worker)  # the worker's work
        out = dataclasses.replace(out, wall_time=cost)  # as long as the point it replays
        if self.forward:
            import types
            header = types.SimpleNamespace(hash=out.hash, status=out.status,
                                           wall_time=out.wall_time)
            body = pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL)
            blob = pickle.dumps((self.Kind.RESULT, header, body),
                                protocol=pickle.HIGHEST_PROTOCOL)
        else:
            if self.packed:
                from sweep.protocol import Packed
                out = Packed.of(out)
            blob = pickle.dumps((self.Kind.RESULT, out), protocol=pickle.HIGHEST_PROTOCOL)
        self.worker_cpu += time.process_time() - c0
        free = self.free_at[worker]
        start = max(now, free)
        done = start + cost
        self.free_at[worker] = done
        self.intervals[worker].append((start, done))
        self.seq += 1
        heapq.heappush(self.events, (done, self.seq, worker, blob))

    def poll(self, timeout: float):
        deadline = time.monotonic() + timeout

        def ready() -> bool:
            return bool(self.events) and self.events[0][0] <= time.monotonic()
        if not self._backoff.wait(ready, deadline):
            return None
        done, _, worker, blob = heapq.heappop(self.events)
        if self.forward:                 # the header read, the record passed on unread
            kind, out, body = pickle.loads(blob)
            os.write(self._sink, body)
            return worker, kind, out
        kind, out = pickle.loads(blob)  # the master's side of a message
        return worker, kind, out

    def shutdown(self) -> None:
        pass

    def abort(self, code: int) -> None:
        pass


@contextlib.contextmanager
def scheduling_only():
    """The master's write path taken out of its process: the store's ``add``, ``commit``,
    ``handout`` and ``release`` do nothing and a result's record is not built, so what is
    left is the scheduling path (poll, unpickle, queues, the next task), what a master
    whose writer is another process would spend itself."""
    import types

    from sweep.run.master import Master
    from sweep.store.store import Store
    saved = {(cls, name): getattr(cls, name) for cls, name in
             ((Store, "add"), (Store, "commit"), (Store, "handout"), (Store, "release"),
              (Master, "record"))}
    Store.add = lambda self, record: None
    Store.commit = lambda self: 0
    Store.handout = lambda self, hashes, alone=False: None
    Store.release = lambda self, hashes: None
    Master.record = lambda self, point, out, config=None: types.SimpleNamespace(
        status=out.status)
    try:
        yield
    finally:
        for (cls, name), fn in saved.items():
            setattr(cls, name, fn)


def simulate(workers: int, scale: float, seconds: float, tmp: Path,
             write_path: str = "inline") -> dict[str, float]:
    """One master with ``workers`` simulated workers for about ``seconds`` of real time
    (``write_path`` "inline": sweep's master writing the store itself; "process": the store
    written by sweep's writer process, :class:`sweep.run.store_process.StoreProcess`, the
    master forwarding each result; "none": :func:`scheduling_only`; "forward": that, each
    result's record passed on unread, as bytes, to ``/dev/null`` for a writer's pipe).
    Returns the figures of the run; ``writer_cpu_share``: the writer process's CPU."""
    import sweep.run.launch as launch
    from sweep.config import parse_campaign
    mean = json.loads(COSTS.read_text())["mean"] * scale
    want = int(workers * seconds / mean) + 2 * workers
    # at most the whole grid (then a run is shorter than ``seconds``)
    campaign = parse_campaign(GRID.read_text(), str(GRID))
    shards = max(1, campaign.size // want)
    store = tmp / f"model-{workers}-{scale}.h5"
    sim = SimTransport(workers, scale, forward=write_path == "forward",
                       packed=write_path in ("inline", "process"))
    real_open, real_sink = launch._open_transport, launch._open_sink
    launch._open_transport = lambda comm, compute, mpi: sim
    if write_path == "process":  # as an MPI run opens its store ([run] writer = "process")
        launch._open_sink = lambda path, campaign, writer, **kw: real_sink(
            path, campaign, "process", **kw)
    campaign = campaign.shard(0, shards)
    import io
    try:
        with contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()), \
                (scheduling_only() if write_path in ("none", "forward")
                 else contextlib.nullcontext()):
            summary = launch.run_campaign(campaign, str(store),
                                          compute="sweep.testing:replay_point",
                                          progress_bar=False)
    finally:
        launch._open_transport, launch._open_sink = real_open, real_sink
    n = summary.computed
    loop = summary.loop_elapsed
    cpu = summary.master_cpu - sim.worker_cpu
    for p in (store, Path(str(store) + ".journal")):
        p.unlink(missing_ok=True)
    # as bench_master.py measures it from a store: per worker the gaps between one
    # point's end and the next's start, and the idle share up to the moment the first
    # worker ran out of work (the drain at the end is no one's doing)
    per = [v for v in sim.intervals.values() if v]
    t0 = min(st for v in per for st, _ in v)
    full = min(v[-1][1] for v in per)
    gaps = np.concatenate([np.diff(np.asarray(v).ravel())[1::2] for v in per]) \
        if any(len(v) > 1 for v in per) else np.zeros(1)
    busy = sum(max(0.0, min(done, full) - st) for v in per for st, done in v)
    span = max(v[-1][1] for v in per) - t0
    return {"workers": workers, "scale": scale, "points": n, "loop_s": loop,
            "rate": n / loop, "span_s": span, "master_cpu_share": cpu / loop,
            "cpu_per_point_ms": 1e3 * cpu / n, "writer_cpu_share": summary.writer_cpu / loop,
            "latency_mean": float(gaps.mean()), "latency_p95": float(np.quantile(gaps, 0.95)),
            "idle": 1.0 - busy / (len(per) * (full - t0)), "point_mean": mean}


def _share(x: float) -> str:
    return f"{100 * x:.1f} %" if x else "-"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, nargs="+", default=[7, 15, 31, 63, 1024, 4096])
    ap.add_argument("--cost-scale", type=float, nargs="+", default=[1.0, 0.25])
    ap.add_argument("--shards", type=int, nargs="+", default=[1])
    ap.add_argument("--seconds", type=float, default=15.0)
    ap.add_argument("--write-path", nargs="+", default=["inline"],
                    choices=["inline", "process", "none", "forward"],
                    help="inline: the master stores every point itself ([run] writer ="
                    " \"inline\"); process: sweep's writer process stores them, the master"
                    " forwards results (the MPI default); none: the scheduling path alone;"
                    " forward: that, each result's record passed on unread")
    ap.add_argument("--check", type=Path, help="bench_master.py --scale --record JSON:"
                    " print the model beside each measured row")
    args = ap.parse_args()
    measured = {}
    if args.check:
        for r in json.loads(args.check.read_text())["rows"]:
            measured[(r["ranks"] - 1, r["scale"], r.get("writer", "inline"))] = r
    print("| workers | shards | cost scale | write path | points/s per master | points/s in all"
          " | master CPU | master CPU per point [ms] | writer CPU"
          " | hand-out latency mean / p95 [ms] | workers idle | from |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scale in args.cost_scale:
            for shards in args.shards:
                for w, path in ((w, p) for w in args.workers for p in args.write_path):
                    per = max(1, w // shards)
                    r = simulate(per, scale, args.seconds, Path(tmp), path)
                    print(f"| {w} | {shards} | {scale:g} | {path} | {r['rate']:.1f} |"
                          f" {r['rate'] * shards:.0f} | {100 * r['master_cpu_share']:.1f} % |"
                          f" {r['cpu_per_point_ms']:.2f} |"
                          f" {_share(r['writer_cpu_share'])} |"
                          f" {1e3 * r['latency_mean']:.1f} /"
                          f" {1e3 * r['latency_p95']:.1f} | {100 * r['idle']:.1f} % | model",
                          flush=True)
                    m = measured.get((w, scale, path)) if shards == 1 else None
                    if m:
                        print(f"| {w} | 1 | {scale:g} | {path} | {m['rate']:.1f} |"
                              f" {m['rate']:.0f} |"
                              f" {100 * m['master_cpu_share']:.1f} % |"
                              f" {m['cpu_per_point_ms']:.2f} |"
                              f" {_share(m.get('writer_cpu_share', 0.0))} |"
                              f" {1e3 * m['latency_mean']:.1f} /"
                              f" {1e3 * m['latency_p95']:.1f} | {100 * m['idle']:.1f} % |"
                              " measured (MPI)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
