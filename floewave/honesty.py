"""Are an ensemble's error bars honest? The library of the checks that say so.

Two independent ensembles of one point (differing only in ``seed`` or ``placement``) give,
per quantity, z = (x1 - x2) / sqrt(se1^2 + se2^2) (:func:`z_scores`); honest standard
errors give an RMS z near 1. A long reference run (:func:`reference_config`: the
stationary protocol with a fixed, long transient and 150 periods averaged) judges the biases
two runs of one protocol share. Points are the paper's Fig. 2 points and valid random points
of its grid (:func:`points`); :func:`run_one` runs one configuration into a JSON-able record
(cached by :func:`key_of` of its configuration); :func:`compute_missing` runs a list of them
at the matched run length :data:`MATCHED`. Used by ``benchmarks/honesty.py`` (the check
itself, docs/convergence.md "Ensembles and error bars"), ``dt_convergence.py``,
``drag_every_convergence.py`` and ``convergence_share.py``.
"""
from __future__ import annotations

import hashlib
import json
import math
import multiprocessing as mp
import time
from pathlib import Path

import numpy as np

from . import MODEL_VERSION
from .config import InvalidPointError, ModelConfig
from .dispersion import solve_dispersion
from .iteration.estimate import SE_FLOOR
from .model import run_point
from .transient import drag_time

#: the paper's grid (docs/model.md §7), from which :func:`points` draws
GRID = {"L_x": [0.5, 1.5, 3.0], "T": [1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0],
        "a0": [0.0125, 0.015, 0.02, 0.025], "C_sd": [0.005, 0.01, 0.05, 0.1, 0.15, 0.2],
        "eps": [0.2, 0.4, 0.6, 0.8], "d_f": [0.005, 0.010, 0.020, 0.050],
        "dispersion": ["ep", "ow", "ml"]}
#: the scalar results compared (each with its ``_stderr``), beside the profile a(x)
SCALARS = ("W_c", "alpha_inner", "alpha_all", "alpha_edge", "alpha_exp", "a_end")
#: the long reference run (``--reference``): 10 periods of spin-up, a fixed transient of 15
#: windows (75 periods), then 30 windows (150 periods) averaged per replica; the drag
#: evaluated every step (``drag_every = 1``, the paper's), so the check also judges the held
#: drag of the runs it compares
REFERENCE = {"dt": 1e-3, "drag_every": 1, "n0": 10, "coupling": "independent",
             "placement": "random",
             "protocol": "stationary", "stationarity": "fixed", "transient_min": 15,
             "n_average": 30, "max_iterations": 45, "target_stderr": 0.0,
             "target_W_c_stderr": 0.0}
REFERENCE_SEEDS = (101, 102)
#: matched run length: 5 periods of spin-up (the default n0), 6 windows (30 periods) of
#: transient, 14 windows (70 periods) averaged, at every dt. A like-for-like comparison of
#: the two time steps: at C_sd 0.005 both are still inside the drag transient (0.4 drag
#: times), which is no matter for it
MATCHED = {"protocol": "stationary", "stationarity": "fixed", "transient_min": 6,
           "n_average": 14, "max_iterations": 20, "target_stderr": 0.0,
           "target_W_c_stderr": 0.0}
#: a reference's transient is also at least this many drag relaxation times
#: (:func:`floewave.transient.drag_time`): 1.5x the default runs' 2, so that the judge sees
#: less of a slow point's transient than the runs it judges (85 periods alone are about
#: 1.1 drag times at C_sd 0.005)
REFERENCE_DRAG_TIMES = 3.0


def reference_config(p: dict, replicas: int, seed: int) -> dict:
    """The reference run of point ``p``: :data:`REFERENCE` with a transient of at least
    :data:`REFERENCE_DRAG_TIMES` drag times, then 30 windows averaged."""
    d = {**p, **REFERENCE, "replicas": replicas, "seed": seed}
    cfg = ModelConfig(**d)
    k, _ = solve_dispersion(cfg)
    tau = drag_time(cfg, k)
    n_tr = REFERENCE["transient_min"]
    if math.isfinite(tau):
        n_tr = max(n_tr, math.ceil(REFERENCE_DRAG_TIMES * tau / (cfg.nT * cfg.T)))
    d.update(transient_min=n_tr, max_iterations=n_tr + REFERENCE["n_average"])
    return d


#: model versions whose reference runs are this version's: a reference runs the drag of
#: every step (``drag_every = 1``) at dt 1e-3 with every protocol field set, and
#: model version 8 changed only the held drag and the default dt (the loop of
#: ``drag_every = 1`` is version 7's bit for bit: ``python benchmarks/kernel_bits.py
#: --against 9fc2add --every-step``); version 9 changed only how the stationary protocol's
#: update pools windows before ``n_average`` and when it stops (``max_average``), neither
#: of which a reference (``stationarity = "fixed"``, targets 0) uses: its runs are
#: version 8's numerics, on other draws (the new field is in the seeds' hash)
REFERENCE_VERSIONS = {MODEL_VERSION, "8", "7"}


def points(n_random: int, seed: int) -> list[dict]:
    """The Fig. 2 points, then ``n_random`` valid random grid points."""
    out = [dict(eps=e, dispersion=d) for d in ("ml", "ep") for e in (0.2, 0.4, 0.6, 0.8)]
    rng = np.random.default_rng(seed)
    while len(out) < 8 + n_random:
        p = {k: v[int(rng.integers(len(v)))] for k, v in GRID.items()}
        try:
            ModelConfig(**p).check_physics()
        except InvalidPointError:
            continue
        out.append(p)
    return out


def run_one(task: tuple) -> tuple[str, dict]:
    """Run (config dict, cache key[, is a reference]); the record with the model version."""
    cfg_dict, key = task[:2]
    cfg = ModelConfig(**cfg_dict)
    t = time.perf_counter()
    r = run_point(cfg)
    rec = {"config": cfg_dict, "reference": bool(task[2]) if len(task) > 2 else False,
           "model_version": MODEL_VERSION,
           "a": r.a.tolist(), "a_stderr": r.a_stderr.tolist(), "status": r.status,
           "iterations": r.iterations, "floe_steps": r.floe_steps,
           "wall": time.perf_counter() - t, "W_c_n": r.W_c_n, "layout": r.compact_zone,
           "W_c_replicas": np.asarray(r.W_c_replicas).tolist()}
    for name in SCALARS:
        rec[name] = getattr(r, name)
        rec[name + "_stderr"] = getattr(r, name + "_stderr")
    return key, rec


def key_of(d: dict) -> str:
    """The cache key of a run's configuration dict."""
    return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:20]


#: quantities of the compact zone: compared only where both runs found the same layout (a
#: W_c or zone fit of an ``edge`` point is another quantity than that of a ``none`` point;
#: such pairs are counted apart as layout disagreements)
ZONE_QUANTITIES = ("W_c", "alpha_inner", "alpha_edge")


def z_scores(r1: dict, r2: dict, name: str) -> np.ndarray:
    """z of quantity ``name`` between records ``r1`` and ``r2`` (per floe for a profile),
    where both values and the combined variance are finite; none for a compact-zone
    quantity of two different layouts."""
    if name in ZONE_QUANTITIES and r1.get("layout") != r2.get("layout"):
        return np.zeros(0)
    x1, x2 = np.asarray(r1[name], float), np.asarray(r2[name], float)
    s1, s2 = np.asarray(r1[name + "_stderr"], float), np.asarray(r2[name + "_stderr"], float)
    var = s1**2 + s2**2
    ok = np.isfinite(x1) & np.isfinite(x2) & np.isfinite(var) & (var > 0)
    return np.atleast_1d(((x1 - x2) / np.sqrt(np.where(ok, var, 1.0)))[ok])


def floored(rec: dict, a0: float) -> dict:
    """``rec`` with SE(a) and SE(a_end) at least the model's floor
    (:data:`floewave.iteration.estimate.SE_FLOOR` a0; runs stored before the floor existed)."""
    out = dict(rec)
    out["a_stderr"] = np.maximum(np.asarray(rec["a_stderr"], float), SE_FLOOR * a0).tolist()
    out["a_end_stderr"] = max(float(rec["a_end_stderr"]), SE_FLOOR * a0)
    return out


def combine(r1: dict, r2: dict) -> dict:
    """The mean of two independent runs with its standard error (per quantity); the layout
    where both agree (else none is compared)."""
    out = {"layout": r1.get("layout") if r1.get("layout") == r2.get("layout") else "differ"}
    for name in ("a", *SCALARS):
        x = (np.asarray(r1[name], float) + np.asarray(r2[name], float)) / 2
        se = np.sqrt(np.asarray(r1[name + "_stderr"], float) ** 2
                     + np.asarray(r2[name + "_stderr"], float) ** 2) / 2
        out[name], out[name + "_stderr"] = x, se
    return out


def compute_missing(tasks: list[tuple[dict, str]], cache: dict, cache_path: Path, jobs: int,
                    n_points: int) -> None:
    """Run the (config, key) ``tasks`` not in ``cache`` at matched run length, costliest
    first, ``jobs`` at a time, saving ``cache`` to ``cache_path`` after each."""
    todo = list({k: (d, k) for d, k in tasks if k not in cache}.values())
    todo.sort(key=lambda t: -ModelConfig(**t[0]).floe_steps_per_iteration())
    print(f"{n_points} points, {len(todo)} runs to compute, matched run length {MATCHED}",
          flush=True)
    t0 = time.perf_counter()
    with mp.get_context("fork").Pool(jobs) as pool:
        for i, (key, rec) in enumerate(pool.imap_unordered(run_one, todo), 1):
            cache[key] = rec
            cache_path.write_text(json.dumps(cache))
            if i % 10 == 0 or i == len(todo):
                print(f"  {i}/{len(todo)} done ({time.perf_counter() - t0:.0f} s)", flush=True)
