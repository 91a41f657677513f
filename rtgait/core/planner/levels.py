"""The controller levels and the planner settings each one runs with.

Both closed loops (the point-mass bench, :mod:`rtgait.core.pendulum.loop`, and the MuJoCo controller,
:mod:`rtgait.control.controller`) offer the same three levels, from the plan alone to the whole closed loop:

* ``"open-loop"``: the planned ZMP, the paper's assumption of perfect tracking; the planner replans from its own
  plan (``feedback="planned"``);
* ``"stabilized"``: the DCM feedback law on the measured state; the planner still replans from its own plan;
* ``"adaptive"``: ``"stabilized"`` with a planner that closes the loop: every plan from the measured COM state
  (``feedback="measured"``), an immediate replan when the DCM error exceeds ``replan_dcm_error``, and step
  adjustment.

:func:`level_config` makes a level's planner configuration; the levels differ only by what the loop adds, so the
settings of the lower ones are cleared whatever the base configuration says.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.planner.config import PlannerConfig

__all__ = ["CONTROLLER_LEVELS", "DEFAULT_REPLAN_DCM_ERROR", "ControllerLevel", "check_level", "level_config"]

ControllerLevel = Literal["open-loop", "stabilized", "adaptive"]
"""A controller level's name (module docstring)."""

CONTROLLER_LEVELS: tuple[ControllerLevel, ...] = ("open-loop", "stabilized", "adaptive")
"""The controller levels, from the plan alone to the whole closed loop; logs store a level as its index here."""

DEFAULT_REPLAN_DCM_ERROR = 0.025
"""DCM error (m) beyond which the ``"adaptive"`` planner replans at once from the measured state.

The DCM feedback alone keeps the error of an unpushed walk at a few millimetres (round-off and the tick's hold), so
25 mm means a disturbance; it is some 20 % of the sole's half length (0.115 m for an HRP-2-like sole), early enough
for a step adjustment to still have most of a swing to act on."""


def check_level(level: object, name: str = "controller") -> None:
    """Refuse anything but a level of :data:`CONTROLLER_LEVELS`: a ValueError naming ``name`` and the levels."""
    if level not in CONTROLLER_LEVELS:
        raise ValueError(f"{name} must be one of {', '.join(CONTROLLER_LEVELS)}, got {level!r}")


def level_config(
    base: PlannerConfig,
    level: ControllerLevel,
    sole: SoleRect,
    *,
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR,
    step_adjustment: StepAdjustment | None = None,
) -> PlannerConfig:
    """The planner configuration of controller level ``level``, made from ``base`` with :func:`dataclasses.replace`.

    ``"open-loop"`` and ``"stabilized"``: ``feedback="planned"``, no DCM-error replanning, no step adjustment.
    ``"adaptive"``: ``feedback="measured"``, ``replan_dcm_error`` (m) and ``step_adjustment`` (default:
    ``StepAdjustment(sole)`` with its default limits, :class:`~rtgait.core.laws.stepping.SteppingLimits`: landings
    within 0.35 m forward or back and 0.12-0.45 m sideways of the stance foot, swing at most 1.5 m/s on average, no
    change in the last 0.2 s before touch-down).
    """
    check_level(level)
    if level != "adaptive":
        return dataclasses.replace(base, feedback="planned", replan_dcm_error=None, step_adjustment=None)
    adjust = step_adjustment if step_adjustment is not None else StepAdjustment(sole=sole)
    return dataclasses.replace(base, feedback="measured", replan_dcm_error=replan_dcm_error, step_adjustment=adjust)
