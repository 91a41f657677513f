"""The outcome of a pendulum-level closed-loop run (:func:`rtgait.core.pendulum.loop.run_pendulum_loop`): the per-tick
record, the planner's record, and the summary written to ``summary.json``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.laws.stepping import StepDecision
from rtgait.core.planner.levels import ControllerLevel
from rtgait.core.planner.online import PlanRecord
from rtgait.core.push import Push

__all__ = ["ClosedLoopResult"]


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """A closed-loop run, tick by tick, and its outcome. ``k`` ticks were run; each row describes tick ``i``: the
    state at ``times[i]`` and the commands held over ``[times[i], times[i] + dt)``. All in SI units (m, m/s, s, kg).

    Attributes:
        times: tick times (s), ``(k,)``; the walk starts at 0.
        cog_planned: the plan's COM at the tick (m), ``(k, 2)``.
        dcm_planned: the plan's DCM ``c + c'/w`` at the tick (m), ``(k, 2)``.
        zmp_planned: the plan's ZMP at the tick (m), ``(k, 2)``.
        zmp_reference: the tick's reference ZMP ``p_bar``, the hold-equivalent of the planned ZMP over the tick
            (module docstring) (m), ``(k, 2)``.
        zmp_command: the controller's ZMP (m), ``(k, 2)``; NaN on the tick the mass is found fallen.
        zmp_real: the ZMP the feet produced, the command clipped to the support polygon (m), ``(k, 2)``; NaN there too.
        cog: the plant's COM (m), ``(k, 2)``.
        cog_vel: the plant's COM velocity (m/s), ``(k, 2)``.
        dcm: the plant's DCM (m), ``(k, 2)``.
        support: the planned support, :data:`~rtgait.core.geometry.support.SUPPORT_CODES`, ``(k,)``.
        phase: the planner's phase index, ``(k,)``.
        saturated: whether the ZMP the controller wanted lay outside the support polygon, ``(k,)``: the feedback law's
            (projected by :class:`DcmFeedback` itself, whose command is then on the boundary) or, open loop, the
            command's (clipped by the plant).
        controller: the level run (:data:`~rtgait.core.planner.levels.CONTROLLER_LEVELS`).
        mass: of the point mass (kg).
        dt: control period (s).
        omega: the pendulum's ``w = sqrt(g / z_c)`` (1/s).
        fell: whether the mass fell (module docstring).
        fall_time: the tick at which it was found fallen (s), or ``None``.
        steps_completed: landings (end of a single support, the closing step included) reached before a fall.
        steps_planned: steps of the walk as it ended (an emergency stop shortens it), the closing step included.
        step_adjustments: the planner's step adjustments, in order (empty below ``"adaptive"``).
        ended_at_rest: not fallen, and at rest after the last tick on the final support polygon.
        pushes: the pushes applied to the mass.
        plans: every replanning of the run.
        footprints: the planner's footprints at the end of the run.
        walk_end: when the walk as finally planned comes to rest (s).
        final_cog: the plant's COM after the last tick (m), ``(2,)``.
        final_cog_vel: its velocity then (m/s), ``(2,)``.
        wall_time: wall-clock time of the loop (s).
    """

    times: np.ndarray
    cog_planned: np.ndarray
    dcm_planned: np.ndarray
    zmp_planned: np.ndarray
    zmp_reference: np.ndarray
    zmp_command: np.ndarray
    zmp_real: np.ndarray
    cog: np.ndarray
    cog_vel: np.ndarray
    dcm: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    saturated: np.ndarray
    controller: ControllerLevel
    mass: float
    dt: float
    omega: float
    fell: bool
    fall_time: float | None
    steps_completed: int
    steps_planned: int
    step_adjustments: tuple[StepDecision, ...]
    ended_at_rest: bool
    pushes: tuple[Push, ...]
    plans: tuple[PlanRecord, ...]
    footprints: tuple[Footstep, ...]
    walk_end: float
    final_cog: np.ndarray
    final_cog_vel: np.ndarray
    wall_time: float
    extra: dict[str, Any] = field(default_factory=dict)
    """Free-form facts a caller adds to :meth:`summary` (e.g. the scenario's name)."""

    @property
    def ticks(self) -> int:
        """Ticks run."""
        return len(self.times)

    @property
    def duration(self) -> float:
        """Simulated time (s): the ticks times the period."""
        return self.ticks * self.dt

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second of the loop."""
        return self.duration / self.wall_time if self.wall_time > 0.0 else math.inf

    @property
    def tick_time(self) -> float:
        """Mean wall-clock time of one tick (s)."""
        return self.wall_time / self.ticks if self.ticks else math.nan

    @property
    def step_adjustment_count(self) -> int:
        """How many step adjustments the planner decided (one may leave the landing where it was, e.g. when no
        candidate improves on it: see each decision's margins and ``reason``)."""
        return len(self.step_adjustments)

    @property
    def all_steps_completed(self) -> bool:
        """No fall and every step of the walk (as it ended) landed."""
        return not self.fell and self.steps_completed == self.steps_planned

    def _tracking_errors(self) -> np.ndarray:
        error = self.zmp_command - self.zmp_reference
        distance = np.hypot(error[:, 0], error[:, 1])
        return distance[np.isfinite(distance)]

    @property
    def zmp_tracking_error_rms(self) -> float:
        """RMS distance (m) between the commanded ZMP and the tick's planned (reference) ZMP, over all ticks.

        What the controller added to the plan: 0 in ``"open-loop"``, the feedback's correction otherwise. (The real
        ZMP differs from the command only where the command left the polygon.)
        """
        distance = self._tracking_errors()
        return float(np.sqrt(np.mean(distance * distance))) if distance.size else math.nan

    @property
    def zmp_tracking_error_max(self) -> float:
        """Largest distance (m) between the commanded and the tick's planned ZMP."""
        distance = self._tracking_errors()
        return float(distance.max()) if distance.size else math.nan

    @property
    def cog_tracking_error(self) -> np.ndarray:
        """Distance (m) between the plant's COM and the plan's at each tick, ``(k,)``."""
        error = self.cog - self.cog_planned
        return np.hypot(error[:, 0], error[:, 1])

    def summary(self) -> dict[str, Any]:
        """The outcome as JSON-ready values (SI units; NaN and infinities become ``None``)."""

        def number(value: float | None) -> float | None:
            return None if value is None or not math.isfinite(value) else float(value)

        return {
            "model": "lipm",
            "controller": self.controller,
            **self.extra,
            "mass": self.mass,
            "dt": self.dt,
            "fell": self.fell,
            "fall_time": number(self.fall_time),
            "steps_completed": self.steps_completed,
            "steps_planned": self.steps_planned,
            "step_adjustments": self.step_adjustment_count,
            "step_adjustment_log": [_decision_summary(d) for d in self.step_adjustments],
            "ended_at_rest": self.ended_at_rest,
            "pushes": [p.summary() for p in self.pushes],
            "zmp_tracking_error_rms": number(self.zmp_tracking_error_rms),
            "zmp_tracking_error_max": number(self.zmp_tracking_error_max),
            "zmp_saturated_ticks": int(self.saturated.sum()),
            "replans": len(self.plans),
            "walk_end": number(self.walk_end),
            "simulated_time": self.duration,
            "wall_time": self.wall_time,
            "tick_time": number(self.tick_time),
            "real_time_factor": number(self.real_time_factor),
        }


def _decision_summary(decision: StepDecision) -> dict[str, Any]:
    return {
        "t": float(decision.t),
        "step": int(decision.step),
        "nominal": [float(v) for v in decision.nominal],
        "landing": [float(v) for v in decision.landing],
        "margin_before": float(decision.margin_before),
        "margin_after": float(decision.margin_after),
        "emergency": bool(decision.emergency),
        "reason": decision.reason,
    }
