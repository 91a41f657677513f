"""The outcome of a walk in physics as JSON-ready values (``summary.json``'s body, SI units, times on the walk's
clock), and the statistics of its ZMP errors (m)."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rtgait.core.laws.stepping import StepDecision

__all__ = ["result_summary"]


def _number(value: float | None) -> float | None:
    """A JSON-ready number: NaN and infinities become ``None`` (JSON has neither)."""
    return None if value is None or not math.isfinite(value) else float(value)


def _decision(decision: StepDecision) -> dict[str, Any]:
    """One step adjustment, JSON-ready (s, m)."""
    return {
        "t": float(decision.t),
        "step": int(decision.step),
        "landing": [float(v) for v in decision.landing],
        "emergency": bool(decision.emergency),
        "reason": decision.reason,
    }


def _error_stats(measured: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> dict[str, float | int | None]:
    """RMS, median, 95th percentile and largest distance (m), the RMS per axis, of ``measured - reference`` over
    ``mask`` where both are known, and the number of ``ticks`` that makes. The median and the 95th percentile tell a
    steady error from a few large ones, which the RMS and the largest mix in."""
    mask = mask & np.isfinite(measured[:, 0]) & np.isfinite(reference[:, 0])
    if not mask.any():
        return {**dict.fromkeys(("rms", "median", "p95", "max", "rms_x", "rms_y")), "ticks": 0}
    error = measured[mask] - reference[mask]
    distance = np.hypot(*error.T)
    return {
        "rms": float(np.sqrt(np.mean(distance * distance))),
        "median": float(np.median(distance)),
        "p95": float(np.percentile(distance, 95.0)),
        "max": float(np.max(distance)),
        "rms_x": float(np.sqrt(np.mean(error[:, 0] ** 2))),
        "rms_y": float(np.sqrt(np.mean(error[:, 1] ** 2))),
        "ticks": int(mask.sum()),
    }


def result_summary(result: Any) -> dict[str, Any]:
    """:meth:`SimResult.summary <rtgait.sim.result.SimResult.summary>`: ``result``'s outcome, JSON-ready (``result``
    is a :class:`~rtgait.sim.result.SimResult`, not named here: its module imports this one)."""
    worst = max(result.stances, key=lambda s: s.slip, default=None)
    summary: dict[str, Any] = {
        "model": "mujoco",
        "robot": result.robot,
        "controller": result.controller,
        "fell": result.fell,
        "fall_time": _number(result.fall_time),
        "fall_cause": result.fall_cause,
        "tipped": result.tipped,
        "tip_time": _number(result.tip_time),
        "steps_planned": result.steps_planned,
        "steps_completed": result.steps_completed,
        "missed_landings": result.missed_landings,
        "step_adjustments": result.step_adjustment_count,
        "step_adjustment_log": [_decision(d) for d in result.step_adjustments],
        "replans": result.replans,
        "ended_at_rest": result.ended_at_rest,
        "distance_walked": result.distance_walked,
        "foot_slip_max": result.foot_slip_max,
        "foot_slip_max_time": None if worst is None else worst.start,
        "foot_yaw_slip_max": result.foot_yaw_slip_max,
        "zmp_error": result.zmp_errors(),
        "zmp_tracking_error_rms": _number(result.zmp_tracking_error_rms),
        "zmp_tracking_error_max": _number(result.zmp_tracking_error_max),
        "pushes": [push.summary() for push in result.pushes],
        "simulated_time": result.duration,
        "wall_time": result.wall_time,
        "real_time_factor": result.real_time_factor,
        "run_start": result.run_start,
        "walk_end": result.walk_end,
        "legs_touched": result.legs_touched,
        "control_dt": result.control_dt,
        "physics_dt": result.physics_dt,
        "safety": result.safety,
        "drive": result.drive,
        "state": result.state,
        "sensors": None if result.sensors is None else dataclasses.asdict(result.sensors),
        "estimation": None if result.estimation_errors is None else result.estimation_errors.summary(),
    }
    if result.model_error is not None:
        summary["model_error"] = result.model_error.summary()
    return summary
