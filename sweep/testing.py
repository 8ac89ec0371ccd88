"""Stand-in compute functions for tests and benchmarks (``--compute sweep.testing:NAME``).

They take a :class:`floewave.ModelConfig` and return a dict shaped like
``floewave.PointResult.to_dict()``, deterministically from the configuration, so
campaigns can be tested without the DEM kernel: :func:`fake_point` (a smooth 1/a
profile), :func:`raising_point` (raises for eps = 0.4), :func:`nan_point` (NaN
amplitudes for d_f = 0.01), :func:`trivial_point` (no work: the master benchmark) and
:func:`sleepy_point` (sleeps 0.2 s: signal and CPU-share tests) and :func:`power_point`
(known alpha(omega) exponents and collision-zone ratios: the analysis tests).
"""
from __future__ import annotations

import ctypes
import hashlib
import json
import os
import shutil
import signal
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from floewave import ModelConfig

__all__ = ["fake_point", "seeded_point", "raising_point", "nan_point", "trivial_point", "sleepy_point",
           "power_point", "faulty_point", "crashing_point", "stuck_point",
           "sleepy_trivial_point", "exiting_point", "c_exit_point", "misfit_point",
           "stdout_closing_point", "stubborn_point", "replay_point", "replay_cost", "REPLAY_COSTS",
           "POWER_M", "catches_signal",
           "find_mpiexec"]


#: ``[base]`` of the small real campaigns of the kill/resume tests (torture, Slurm): 4 or
#: 8 floes of a 24 m sheet, 1 + 1 periods per iteration, at most 10 iterations, ensembles
#: of 2 replicas: ~0.1-0.4 s per point on one core.
SMALL_REAL_BASE = """\
[base]
L_sheet = 24.0
n0 = 1
nT = 1
max_iterations = 10
noise_window = 2
n_average = 2
n0_warm = 1
replicas = 2
target_W_c_stderr = 0.0
"""


def fake_point(cfg: ModelConfig) -> dict[str, Any]:
    """A deterministic PointResult-like dict: a = 1 / (1/a0 + alpha x)."""
    n = cfg.n_floes
    x = (np.arange(n) + 0.5) * (cfg.L_x + cfg.d_f)
    alpha = cfg.C_sd * (1 + cfg.eps) / cfg.T ** 4 * (2.0 if cfg.dispersion == "ml" else 1.0)
    a = 1.0 / (1.0 / cfg.a0 + alpha * x)
    gap = np.full(n, cfg.d_f)
    gap[-1] = np.nan
    hist = np.geomspace(0.5, 1e-4, 5 + int(10 * cfg.eps))
    return {
        "x_mean": x, "a": a, "a_stderr": 0.01 * a, "S_sd": -cfg.C_sd * a ** 3,
        "gap_mean": gap, "contact_fraction": np.linspace(0, 1, n),
        "collisions": np.arange(n, dtype=float), "F_w_mean": a * 100, "F_c_mean": a * 50,
        "F_d_mean": a * 5, "n_floes": n, "W_c": float(x[n // 3]), "compact_zone": "edge",
        "compact_end": float(x[-1] + 0.5 * cfg.L_x), "ice_extent": float(x[-1] + 0.5 * cfg.L_x),
        "alpha_all": alpha,
        "alpha_all_resid": 1e-3, "alpha_edge": 2 * alpha, "alpha_edge_resid": 2e-3,
        "alpha_inner": alpha, "alpha_inner_resid": 1e-3, "alpha_exp": alpha * cfg.a0,
        "alpha_exp_resid": 5e-3, "alpha_c": 0.9 * alpha, "k": 4.0 / cfg.T ** 2,
        "c_g": 0.5 * cfg.T, "status": "converged" if cfg.eps < 0.7 else "converged_noisy",
        "noise": 0.0 if cfg.eps < 0.7 else 0.02, "iterations": len(hist),
        "residual": float(hist[-1]), "floe_steps": cfg.floe_steps_of(len(hist)),
        "wall_time": 1e-3, "kernel_mode": "fake", "a_end": float(a[-1]), "a0": cfg.a0,
        "residual_history": hist,
    }


def seeded_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point` with the ensemble's scatter: its W_c, rates and amplitudes moved
    by a draw of the point's ``seed`` (and its other fields), with standard errors, so
    that independent seeds of one point differ as an ensemble's would."""
    other = cfg.to_dict()
    other.pop("seed")
    key = int(hashlib.sha256(json.dumps(other, sort_keys=True).encode()).hexdigest()[:8], 16)
    u = np.random.default_rng([cfg.seed, key]).standard_normal(4)
    out = fake_point(cfg)
    a = out["a"] * (1.0 + 0.004 * u[0])
    rate = 1.0 + 0.05 * u[1]
    out.update(a=a, a_stderr=0.004 * a, a_end=float(a[-1]), a_end_stderr=0.004 * float(a[-1]),
               W_c=out["W_c"] + 0.5 * u[2], W_c_stderr=0.5,
               **{k: out[k] * rate for k in ("alpha_all", "alpha_edge", "alpha_inner",
                                            "alpha_exp")},
               **{f"{k}_stderr": 0.05 * out[k] for k in ("alpha_all", "alpha_edge",
                                                         "alpha_inner", "alpha_exp")})
    return out


def raising_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but raises RuntimeError for eps = 0.4."""
    if cfg.eps == 0.4:
        raise RuntimeError(f"deliberate failure for eps = {cfg.eps}")
    return fake_point(cfg)


def nan_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, with NaN amplitudes for d_f = 0.01."""
    out = fake_point(cfg)
    if cfg.d_f == 0.01:
        out["a"] = np.full_like(out["a"], np.nan)
    return out


_TRIVIAL = {name: np.zeros(4) for name in ("x_mean", "a", "a_stderr", "S_sd", "gap_mean",
                                           "contact_fraction", "collisions", "F_w_mean",
                                           "F_c_mean", "F_d_mean")}


def trivial_point(cfg: ModelConfig) -> dict[str, Any]:
    """Almost no work: four-floe zero profiles (benchmarks the master, not the model)."""
    return {**_TRIVIAL, "a": np.full(4, cfg.a0), "n_floes": 4, "status": "converged",
            "iterations": 1, "kernel_mode": "trivial", "residual_history": np.zeros(1)}


def sleepy_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point` after sleeping 0.2 s."""
    time.sleep(0.2)
    return fake_point(cfg)


#: Exponent m of alpha_inner = C_sd omega^m in :func:`power_point`, per dispersion relation.
POWER_M = {"ep": 2.0, "ow": 4.0, "ml": 6.0}


def power_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point` with hand-set rates whose analysis results are known exactly.

    alpha_inner = C_sd omega^m (m = :data:`POWER_M` of the dispersion relation),
    alpha_c = alpha_inner / (1 + eps) (so alpha_inner / alpha_c = 1 + eps),
    alpha_edge = (2 + d_f * 100) alpha_inner, W_c = 10 eps L_x with layout ``edge`` — or,
    where that would not be inside the sheet (10 eps L_x >= L_sheet), no compact zone:
    layout ``none``, W_c and alpha_inner NaN, alpha_c = C_sd omega^m / (1 + eps) still;
    alpha_all_resid = 1e-3 and alpha_exp_resid = 1e-3 (1 + eps) for eps < 0.5, else 5e-4
    (the exponential fits better).
    """
    out = fake_point(cfg)
    omega = 2.0 * np.pi / cfg.T
    inner = cfg.C_sd * omega ** POWER_M[cfg.dispersion]
    W_c = 10.0 * cfg.eps * cfg.L_x
    compact = W_c < cfg.L_sheet
    out.update(alpha_inner=inner if compact else np.nan, alpha_c=inner / (1.0 + cfg.eps),
               alpha_edge=(2.0 + 100.0 * cfg.d_f) * inner,
               W_c=W_c if compact else np.nan, compact_zone="edge" if compact else "none",
               compact_end=out["ice_extent"] if compact else np.nan, alpha_all_resid=1e-3,
               alpha_exp_resid=1e-3 * (1.0 + cfg.eps) if cfg.eps < 0.5 else 5e-4,
               status="converged" if cfg.eps < 0.7 else "not_converged")
    return out


#: A tiny real campaign: 8 points of a 6-floe sheet, well under a second each.
TINY_TOML = """\
[base]
L_sheet = 3.0
n0 = 1
nT = 1
max_iterations = 3
noise_window = 2
n_average = 2

[sweep]
L_x = [0.5, 1.0]
eps = [0.2, 0.6]
dispersion = ["ml", "ep"]

[run]
name = "tiny"
progress_interval = 5.0
grace_period = 5.0
"""


def catches_signal(pid: int, sig: int) -> bool:
    """Whether process ``pid`` has a handler installed for signal ``sig`` (``SigCgt`` in
    /proc/<pid>/status; False once the process is gone)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = int(next(x for x in status.splitlines() if x.startswith("SigCgt:")).split()[1], 16)
    return bool(mask & (1 << (sig - 1)))


def find_mpiexec() -> str | None:
    """The ``mpiexec`` on PATH or beside the Python interpreter (the mpich wheel's)."""
    beside = Path(sys.executable).parent / "mpiexec"
    if beside.exists():
        return str(beside)
    return shutil.which("mpiexec")


def faulty_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but faulty by eps: 0.1 ``sys.exit(0)``, 0.2 raises
    ``KeyboardInterrupt``, 0.3 returns ``W_c = "wide"``, 0.4 ``iterations = 1e20``, 0.5
    raises with a lone surrogate in its message (``os.fsdecode`` of a non-UTF-8 name)."""
    if cfg.eps == 0.1:
        sys.exit(0)
    if cfg.eps == 0.2:
        raise KeyboardInterrupt
    out = fake_point(cfg)
    if cfg.eps == 0.3:
        out["W_c"] = "wide"
    elif cfg.eps == 0.4:
        out["iterations"] = 1e20
    elif cfg.eps == 0.5:
        name = os.fsdecode(b"data-\xff.bin")
        raise FileNotFoundError(f"no such file: {name}")
    return out


def crashing_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but the process dies (``os._exit(3)``) for eps = 0.4, as a
    segfault would."""
    if cfg.eps == 0.4:
        os._exit(3)
    return fake_point(cfg)


def stuck_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but eps = 0.4 never returns (a Python loop) and eps = 0.6
    sleeps for an hour (a blocking call)."""
    if cfg.eps == 0.4:
        while True:
            sum(range(1000))
    if cfg.eps == 0.6:
        time.sleep(3600)
    return fake_point(cfg)


def native_stuck_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but eps = 0.4 is stuck where no Python handler can run (as in
    native code): the timeout signal is blocked and the thread sleeps for an hour."""
    if cfg.eps == 0.4:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGUSR2})
        time.sleep(3600)
    return fake_point(cfg)


def sleepy_trivial_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`trivial_point` after 2 ms (a steady stream of commits: reader tests)."""
    time.sleep(0.002)
    return trivial_point(cfg)


def exiting_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but the process ends with status 0 (``os._exit(0)``) for
    eps = 0.4: no handler runs, as for a C ``_exit(0)``."""
    if cfg.eps == 0.4:
        os._exit(0)
    return fake_point(cfg)


def c_exit_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but the C library's ``exit(0)`` ends the process for
    eps = 0.4 (a model library's ``exit(0)`` or Fortran ``STOP``: C atexit handlers run,
    Python's do not)."""
    if cfg.eps == 0.4:
        ctypes.CDLL(None).exit(0)
    return fake_point(cfg)


def misfit_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point` with output the schema cannot hold, by eps: 0.1 a profile 'a'
    of 3 values, 0.2 a 'gap_mean' of 10**6, 0.3 a complex 'F_w_mean', 0.4
    alpha_all = inf, 0.5 iterations = -inf."""
    out = fake_point(cfg)
    if cfg.eps == 0.1:
        out["a"] = out["a"][:3]
    elif cfg.eps == 0.2:
        out["gap_mean"] = np.zeros(10 ** 6)
    elif cfg.eps == 0.3:
        out["F_w_mean"] = out["F_w_mean"] * (1 + 1j)
    elif cfg.eps == 0.4:
        out["alpha_all"] = np.inf
    elif cfg.eps == 0.5:
        out["iterations"] = -np.inf
    return out


def stdout_closing_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but eps = 0.4 closes ``sys.stdout`` and descriptor 1 first (a
    model library that closes its output)."""
    if cfg.eps == 0.4:
        sys.stdout.close()
        os.close(1)
    return fake_point(cfg)


def stubborn_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point`, but eps = 0.4 swallows everything, its timeout included
    (``except BaseException`` in a loop), and never returns."""
    if cfg.eps == 0.4:
        while True:
            try:
                time.sleep(3600)
            except BaseException:  # noqa: BLE001, S110 - the point under test does this
                pass
    return fake_point(cfg)


#: The point costs :func:`replay_point` replays: a JSON file with ``wall_time_quantiles``
#: (the model wall time [s] at quantiles 0, 1/Q, ..., 1 of a real campaign, made by
#: ``benchmarks/bench_master.py --costs-from STORE_OR_TABLE``).
REPLAY_COSTS = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "point_costs.json"
_REPLAY_Q: list[float] | None = None


def replay_cost(config: dict[str, Any]) -> float:
    """The replayed cost [s] of the point whose configuration (as a dict) is ``config``:
    the cost distribution of :data:`REPLAY_COSTS` (or of the file
    ``FLOEWAVE_REPLAY_COSTS`` names) at a quantile drawn from the configuration's hash."""
    global _REPLAY_Q
    if _REPLAY_Q is None:
        path = Path(os.environ.get("FLOEWAVE_REPLAY_COSTS", REPLAY_COSTS))
        _REPLAY_Q = [float(v) for v in json.loads(path.read_text())["wall_time_quantiles"]]
    digest = hashlib.sha256(json.dumps(config, sort_keys=True).encode()).digest()
    u = int.from_bytes(digest[:8], "little") / 2.0**64 * (len(_REPLAY_Q) - 1)
    i = min(int(u), len(_REPLAY_Q) - 2)
    return _REPLAY_Q[i] + (u - i) * (_REPLAY_Q[i + 1] - _REPLAY_Q[i])


def replay_point(cfg: ModelConfig) -> dict[str, Any]:
    """:func:`fake_point` after sleeping as long as a real point: the cost distribution of
    :data:`REPLAY_COSTS` (or the file ``FLOEWAVE_REPLAY_COSTS`` names), sampled by a
    quantile drawn from the configuration's hash (so one point always costs the same),
    times ``FLOEWAVE_REPLAY_SCALE`` (default 1; 0.25: points 4x cheaper). It sleeps
    rather than computes, so that many oversubscribed ranks can stand for many cores:
    the master's benchmark at scale (``benchmarks/bench_master.py --scale``)."""
    cost = replay_cost(cfg.to_dict()) * float(os.environ.get("FLOEWAVE_REPLAY_SCALE", "1"))
    t0 = time.perf_counter()
    time.sleep(cost)
    out = fake_point(cfg)
    # a real point's record: the per-replica profiles too (16 datasets of its shapes)
    r, n = cfg.replicas, out["n_floes"]
    out.update(W_c_replicas=np.full(r, out["W_c"]),
               compact_end_replicas=np.full(r, out["compact_end"]),
               x_mean_replicas=np.tile(out["x_mean"], (r, 1)),
               gap_mean_replicas=np.tile(out["gap_mean"], (r, 1)),
               S_sd_replicas=np.tile(out["S_sd"], (r, 1)), replicas=r)
    assert out["x_mean_replicas"].shape == (r, n)
    out["wall_time"] = time.perf_counter() - t0
    out["kernel_mode"] = "replay"
    return out
