"""Which way of extending one point buys standard error (SE) cheapest ("settling" work).

    nice python benchmarks/settle_cost.py [--dispersion ml] [--eps 0.8] [--variants a b c d e]
                                          [--repeats 1]

The point is configs/fig2.toml's grid point at ``--eps`` and ``--dispersion`` (L_x 0.5,
T 1.2, a0 0.0125, C_sd 0.05, d_f 0.005). Each variant runs that point once, in this process,
on one core (NUMBA_NUM_THREADS=1), after a cheap warm-up point (numba compiled / loaded):

  (a) R=8 seed 0 (the default)        (b) R=8 seed 1          (c) R=16 seed 0
  (d) R=8 seed 0 n_average=20         (e) R=8 seed 0 target_stderr=0.005, target_W_c_stderr=0.5

For each: CPU seconds (time.process_time() around ``run_point``), the model's iterations,
floe-steps and wall_time, and a_end/a0, W_c, alpha_inner/alpha_c with their jackknife SEs.
Figure of merit per quantity: cost x SE^2 relative to (a) (cost: CPU seconds; a second table
uses floe-steps, free of timing noise); below 1 the extension buys SE more cheaply than
pooling S independent seeds (SE/sqrt(S) at S times the cost: (a)'s figure of merit). One SE
from R replicas is itself uncertain by ~1/sqrt(2(R-1)) (27 % at R=8): (a) vs (b) shows that
scatter. Replica r's arrangement depends on every field but ``replicas``: (c) holds (a)'s
replicas plus 8 new ones, (d) and (e) are new draws. ``--repeats K`` runs each variant on K
disjoint seeds (b: 1, 3, 5, ...; others 0, 2, 4, ...) and uses mean cost x mean SE^2, plus
mean cost x the variance of the values over the draws (a check on the reported SEs:
stopping on an SE target biases them low).
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from floewave import run_point  # noqa: E402
from sweep.config import load_campaign  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
VARIANTS = {
    "a": ("R=8 (default)", {}),
    "b": ("R=8 odd seeds", {}),
    "c": ("R=16", {"replicas": 16}),
    "d": ("R=8 n_average=20", {"n_average": 20}),
    "e": ("R=8 targets/2", {"target_stderr": 0.005, "target_W_c_stderr": 0.5}),
}
QUANTITIES = ("a_end/a0", "W_c", "inner/c")


def machine() -> str:
    text = Path("/proc/cpuinfo").read_text()
    name = next((ln.split(":", 1)[1].strip() for ln in text.splitlines()
                 if ln.startswith("model name")), "?")
    return f"{name}; avx512f: {'yes' if ' avx512f' in text else 'no'}; cores: {os.cpu_count()}"


def base_point(dispersion: str, eps: float):
    camp = load_campaign(ROOT / "configs" / "fig2.toml")
    for p in camp.points():
        if p.swept["dispersion"] == dispersion and math.isclose(p.swept["eps"], eps):
            return p.config
    raise SystemExit(f"no fig2 point with dispersion={dispersion} eps={eps}")


def measure(cfg) -> dict:
    t0 = time.process_time()
    r = run_point(cfg)
    cpu = time.process_time() - t0
    a0, ac = r.a0, r.alpha_c
    return {"cpu": cpu, "it": r.iterations, "fs": r.floe_steps, "wall": r.wall_time,
            "status": r.status, "W_c_n": r.W_c_n,
            "q": {"a_end/a0": (r.a_end / a0, r.a_end_stderr / a0),
                  "W_c": (r.W_c, r.W_c_stderr),
                  "inner/c": (r.alpha_inner / ac, r.alpha_inner_stderr / ac)}}


def mean_row(draws: list[dict]) -> dict:
    """Mean cost; per quantity the values' SD over the draws (the SE it really has) and the
    root-mean-square reported SE."""
    out = {c: sum(d[c] for d in draws) / len(draws) for c in ("cpu", "fs")}
    out["q"] = {q: (statistics.stdev(d["q"][q][0] for d in draws) if len(draws) > 2 else math.nan,
                    math.sqrt(sum(d["q"][q][1] ** 2 for d in draws) / len(draws)))
                for q in QUANTITIES}
    return out


def fom_table(rows: dict, cost: str, i: int = 1) -> None:
    ref, what = rows.get("a"), ("(SD of the values over the draws)^2", "SE^2")[i]
    print(f"\nfigure of merit: {cost} x {what} relative to (a)  (< 1: cheaper than more seeds)")
    print(f"{'':3}{'variant':18}{'cost/(a)':>9}" + "".join(f"{q:>11}" for q in QUANTITIES))
    for key, m in rows.items():
        line = f"({key}){VARIANTS[key][0]:17}{m[cost] / ref[cost]:9.2f}"
        for q in QUANTITIES:
            se, se_ref = m["q"][q][i], ref["q"][q][i]
            f = m[cost] * se**2 / (ref[cost] * se_ref**2) if se_ref > 0 else math.nan
            line += f"{f:11.2f}"
        print(line)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dispersion", default="ml", choices=("ml", "ep"))
    ap.add_argument("--eps", type=float, default=0.8)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--repeats", type=int, default=1, help="draws (seeds) per variant")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    cfg = base_point(args.dispersion, args.eps)
    print(f"point: fig2 dispersion={cfg.dispersion} eps={cfg.eps} L_x={cfg.L_x} T={cfg.T}"
          f" a0={cfg.a0} C_sd={cfg.C_sd} d_f={cfg.d_f} n_floes={cfg.n_floes}"
          f" protocol={cfg.protocol} coupling={cfg.coupling}")
    t0 = time.process_time()
    run_point(cfg.replace(replicas=2, max_iterations=2, seed=12345))   # compile / load numba
    print(f"warm-up (R=2, 2 iterations): {time.process_time() - t0:.1f} CPU s", flush=True)
    draws: dict[str, list[dict]] = {}
    for key in args.variants:
        label, changes = VARIANTS[key]
        for k in range(args.repeats):
            seed = 2 * k + (key == "b")
            m = measure(cfg.replace(seed=seed, **changes))
            draws.setdefault(key, []).append(m | {"seed": seed})
            print(f"  ({key}) {label} seed {seed}: {m['cpu']:.1f} CPU s, {m['status']}", flush=True)
    print(f"\n{'':3}{'variant':18}{'seed':>4}{'CPU s':>7}{'wall s':>7}{'iter':>5}{'floe-steps':>11}"
          f"{'W_c_n':>6}  {'a_end/a0':>17}  {'W_c [m]':>15}  {'inner/c':>15}")
    for key, ms in draws.items():
        for m in ms:
            q = m["q"]
            print(f"({key}){VARIANTS[key][0]:17}{m['seed']:5d}{m['cpu']:7.1f}{m['wall']:7.1f}"
                  f"{m['it']:5d}{m['fs']:11.4g}{m['W_c_n']:6d}  "
                  f"{q['a_end/a0'][0]:8.4f}±{q['a_end/a0'][1]:<8.4f}  {q['W_c'][0]:7.2f}±"
                  f"{q['W_c'][1]:<7.2f}  {q['inner/c'][0]:7.3f}±{q['inner/c'][1]:<7.3f}")
    rows = {key: mean_row(ms) for key, ms in draws.items()}
    if args.repeats > 1:
        print(f"\nover {args.repeats} draws: mean CPU s, floe-steps; per quantity SD of the"
              " values over the draws / RMS reported SE")
        for key, m in rows.items():
            print(f"({key}){VARIANTS[key][0]:17}{m['cpu']:7.2f}{m['fs']:11.4g}  " + "  ".join(
                f"{q} {m['q'][q][0]:.4f}/{m['q'][q][1]:.4f}" for q in QUANTITIES))
    if "a" in rows:
        fom_table(rows, "cpu")
        fom_table(rows, "fs")
        if args.repeats > 2:
            fom_table(rows, "cpu", 0)
        print(f"\n{args.repeats} draw(s) per variant: an SE^2 (a figure of merit) is noisy by"
              " ~sqrt(2/(R-1)/draws), more in the tails; (a) vs (b) shows it. (c) shares (a)'s replicas.")


if __name__ == "__main__":
    main()
