"""What a campaign will cost before it runs: kernel shapes, calibrated speeds, core-hours.

A point's cost is its expected floe-steps (:attr:`sweep.config.Point.cost`); the kernel's
speed, in floe-steps per second, depends on the point's *kernel shape*
(:func:`kernel_shape`). :func:`calibrate` measures the speed of every shape in a grid on
this machine; :func:`given_rate` assumes one speed for all; :func:`core_seconds` projects
the grid's cost; :func:`plan` does all of it for ``sweep plan``.
"""
from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import floewave

__all__ = ["Plan", "calibrate", "core_seconds", "given_rate", "kernel_shape", "plan"]

#: Seconds each kernel shape is timed for by :func:`calibrate` (after a warm-up run).
CALIBRATION_SECONDS = 0.5


def kernel_shape(cfg: Any) -> tuple:
    """What the kernel speed depends on: floe count, drag cells and mode, confinement, the
    number of chains run in one kernel (replicas) and the steps between drag evaluations."""
    n_x = cfg.n_x if cfg.drag_integration == "quadrature" else 0
    return (cfg.n_floes, n_x, cfg.drag_integration, cfg.confined, cfg.n_chains,
            1 if cfg.confined else cfg.drag_every)      # the confined kernel holds nothing


def calibrate(points: Iterable[Any]) -> tuple[dict[tuple, float], str]:
    """Floe-steps per second of the kernel for every kernel shape in the grid, and a
    one-line description of how they were found.

    For each distinct :func:`kernel_shape` the costliest point of that shape runs 2
    iterations (1 spin-up period and 3 averaging periods, then 3 more averaging periods:
    with the default ``n0_warm = 0`` nearly every step of a real run accumulates the
    averaging statistics, which is the slower kind of step) for about
    :data:`CALIBRATION_SECONDS` of CPU time after a compile/warm-up run. CPU time, not wall
    time: a core-hour is CPU time, and on a shared machine the wall clock also counts the
    time other processes had the core. No valid point, or no
    ``floewave.run_point``: no rates (``{}``) and the reason.
    """
    try:
        run_point = floewave.run_point
    except (AttributeError, ImportError) as exc:
        return {}, f"no calibration: floewave.run_point unavailable ({exc})"
    shapes: dict[tuple, Any] = {}
    for p in points:
        if not p.invalid:
            key = kernel_shape(p.config)
            if key not in shapes or p.cost > shapes[key].cost:
                shapes[key] = p
    if not shapes:
        return {}, "no calibration: no valid point"
    rates: dict[tuple, float] = {}
    notes = []
    for key, p in sorted(shapes.items(), key=lambda kv: str(kv[0])):
        cfg = p.config.replace(max_iterations=2, n0=1, n0_warm=0, nT=3)
        run_point(cfg.replace(L_sheet=min(cfg.L_sheet, 4 * cfg.L_x)))  # compile / warm up
        steps = 0
        t0 = time.process_time()
        while time.process_time() - t0 < CALIBRATION_SECONDS:
            steps += int(run_point(cfg).floe_steps)
        rates[key] = steps / (time.process_time() - t0)
        notes.append(f"{key[0]} floes/{key[2]}: {rates[key] / 1e6:.1f}M")
    return rates, "calibrated " + ", ".join(notes) + " floe-steps/s"


def given_rate(points: Iterable[Any], rate: float) -> dict[tuple, float]:
    """The same speed, ``rate`` floe-steps per second, for every kernel shape of the grid."""
    return {kernel_shape(p.config): rate for p in points}


def core_seconds(points: Iterable[Any], rates: dict[tuple, float]) -> float:
    """Projected core-seconds: sum over valid points of cost / rate of the point's shape
    (NaN when a shape has no rate)."""
    total = 0.0
    for p in points:
        if not p.invalid:
            rate = rates.get(kernel_shape(p.config), float("nan"))
            total += p.cost / rate
    return total


@dataclass(frozen=True)
class Plan:
    """A campaign's projected cost (what ``sweep plan`` prints)."""

    points: int              #: grid points
    invalid_points: int      #: physically invalid points (stored, never computed)
    floe_steps: float        #: expected floe-steps of the valid points
    rates: dict[tuple, float]  #: floe-steps per second per kernel shape
    calibration: str         #: how the rates were found
    core_hours: float        #: projected core-hours (NaN without rates)

    @property
    def floe_steps_per_s(self) -> float:
        """The mean speed the projection assumes (NaN without a projection)."""
        hours = self.core_hours
        return self.floe_steps / (hours * 3600) if hours == hours and hours > 0 else math.nan


def plan(points: Sequence[Any], rate: float | None = None) -> Plan:
    """The projected cost of ``points`` (a campaign's :meth:`~sweep.config.Campaign.points`)
    at ``rate`` floe-steps per second, or at the rates :func:`calibrate` measures."""
    if rate:
        rates, how = given_rate(points, rate), "rate given with --rate"
    else:
        rates, how = calibrate(points)
    return Plan(points=len(points), invalid_points=sum(1 for p in points if p.invalid),
                floe_steps=sum(p.cost for p in points if not p.invalid), rates=rates,
                calibration=how,
                core_hours=core_seconds(points, rates) / 3600 if rates else float("nan"))
