"""Compile (or load from the numba cache) the kernels a campaign needs before its clock
starts, so that the first point's wall time, the first ETA and ``sweep status``'s slowest
points are not inflated by JIT compilation (issue *first hour* 4).

One tiny point per kernel variant of the campaign (:func:`floewave.model.kernel_mode`:
drag integration, confinement, integrator) is run on every worker: four floes, one spin-up
and one averaging period, one iteration. Only for the default compute function
(``floewave:run_point``): other compute functions (tests, benchmarks) are not called
outside their points.
"""
from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

from floewave import ModelConfig
from sweep.run.compute import resolve_compute

__all__ = ["warm_up_configs", "warm_up"]

#: The compute function whose kernels are warmed up.
WARMED = "floewave:run_point"


def warm_up_configs(points: Iterable[Any], compute: str) -> list[dict[str, Any]]:
    """One shrunken configuration (as a dict) per kernel variant of the valid ``points``."""
    if compute != WARMED:
        return []
    from floewave.model import kernel_mode  # lazy: numba, 0.4 s; every sweep command imports this

    seen: dict[str, dict[str, Any]] = {}
    for p in points:
        if p.invalid:
            continue
        mode = kernel_mode(p.config)
        if mode not in seen:
            cfg = p.config
            seen[mode] = cfg.replace(L_sheet=4 * cfg.L_x, n0=1, n0_warm=0, nT=1,
                                     max_iterations=1, replicas=1).to_dict()
    return list(seen.values())


def warm_up(configs: list[dict[str, Any]], compute: str) -> tuple[float, str]:
    """Run ``configs`` with ``compute``; return (seconds, problem or ``''``).

    A failure is reported, not raised: the campaign's own points then fail with their
    messages (or run, if the failure was particular to the shrunken point).
    """
    t0 = time.perf_counter()
    if not configs:
        return 0.0, ""
    try:
        fn = resolve_compute(compute)
        for c in configs:
            fn(ModelConfig.from_dict(c))
    except Exception as exc:  # noqa: BLE001 - reported, the campaign goes on
        return time.perf_counter() - t0, f"{type(exc).__name__}: {exc}"
    return time.perf_counter() - t0, ""
