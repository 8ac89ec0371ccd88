"""What a stored point costs the master: Store.add + commit of real-size records, by batch.

    python benchmarks/store_commit.py [--profile]

Builds the records of 1/24 of the paper's grid (``sweep.testing:replay_point`` results,
the shapes of real points: 16 profile datasets each), then stores them into a fresh store
in group commits of 1, 8, 64 and 512 points, and prints the wall and CPU time per point;
first, the CPU and size of a point's journal line, its arrays packed (journal version 3)
and as the JSON lists of version 2.
``--profile``: where the time goes at batches of 64 (cProfile, by internal time). Run from
the repository root. docs/cluster.md "Past one master" quotes it.
"""
import sys, time, tempfile, os, cProfile, pstats
from pathlib import Path
os.environ["FLOEWAVE_REPLAY_SCALE"] = "0"
from sweep.config import parse_campaign
from sweep.store.store import Store
from sweep.store.record import Record
from sweep.run.compute import compute_point, resolve_compute
from sweep.protocol import Task
from sweep.provenance import environment
text = Path("configs/herman2019.toml").read_text()
camp = parse_campaign(text, "configs/herman2019.toml").shard(0, 24)
pts = camp.points()
fn = resolve_compute("sweep.testing:replay_point")
env = environment(with_git=False)
from sweep.store.record import provenance_json
prov = provenance_json(env, {}, "replay")
recs = []
for p in pts:
    out = compute_point(Task(p.hash, p.config.to_dict(), 0.0), fn, 1)
    recs.append(Record.from_outcome(p, out, p.config.to_dict(), lambda r, k: prov))
print(len(recs), "records")
# a journal line: arrays packed (journal version 3) against JSON lists (version 2)
from sweep.store.journal import encode
def as_lists(r):
    return encode({"row": r.row, "profiles": {k: v.tolist() for k, v in r.profiles.items()},
                   "residual_history": r.residual_history.tolist()})
for label, fn_line in (("packed arrays (version 3)", lambda r: r.journal_line()),
                       ("JSON lists (version 2)", as_lists)):
    c0 = time.process_time()
    size = sum(len(fn_line(r)) for r in recs)
    print(f"journal line, {label}: {1e3 * (time.process_time() - c0) / len(recs):.3f} ms CPU,"
          f" {size / len(recs) / 1e3:.1f} kB per point")
prof = "--profile" in sys.argv
for k in (1, 8, 64, 512):
    with tempfile.TemporaryDirectory() as tmp:
        st = Store(str(Path(tmp) / "b.h5"), camp, run_info=env)
        n = min(len(recs), 512 if k < 64 else len(recs))
        pr = cProfile.Profile()
        t0, c0 = time.perf_counter(), time.process_time()
        if prof and k == 64: pr.enable()
        for i in range(0, n, k):
            for r in recs[i:i + k]:
                st.add(r)
            st.commit()
        if prof and k == 64: pr.disable()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        st.close("complete")
        print(f"batch {k}: {n} points, {1e3 * wall / n:.2f} ms wall, {1e3 * cpu / n:.2f} ms CPU per point")
        if prof and k == 64:
            pstats.Stats(pr).sort_stats("tottime").print_stats(18)
