"""The analytical real-time gait planner, numpy and scipy only: importable alone, no robot, no simulator.

The public names of a control loop are exported here; the subpackages are mapped in ``docs/architecture.md`` and
the README has a quick start.
"""

from rtgait.core.analysis.rollout import Rollout, ScheduledChange, rollout
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, Timeline, Timing, place_footsteps, standing_feet
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.lipm.bvp import BoundaryValueSolver
from rtgait.core.lipm.closed_form import GRAVITY, CogTrajectory, omega
from rtgait.core.lipm.connect import ConnectionSolver
from rtgait.core.lipm.spline import PiecewisePolynomial
from rtgait.core.planner.online import (
    CONNECTION_MODES,
    FEEDBACK_MODES,
    SAMPLE_FIELDS,
    CommandClampedWarning,
    GaitSample,
    InputOutOfBoundsError,
    OnlinePlanner,
    PlannerConfig,
    PlanRecord,
    SampleColumns,
    SampleValues,
    StepChangeTooLateError,
    StopCancelledWarning,
    VelocityCommand,
    straight_walk,
)

__all__ = [
    "CONNECTION_MODES",
    "FEEDBACK_MODES",
    "GRAVITY",
    "SAMPLE_FIELDS",
    "BoundaryValueSolver",
    "CogTrajectory",
    "CommandClampedWarning",
    "ConnectionSolver",
    "Footstep",
    "GaitSample",
    "InputOutOfBoundsError",
    "OnlinePlanner",
    "PiecewisePolynomial",
    "PlanRecord",
    "PlannerConfig",
    "Rollout",
    "SampleColumns",
    "SampleValues",
    "ScheduledChange",
    "SoleRect",
    "StepChangeTooLateError",
    "StopCancelledWarning",
    "Stride",
    "Timeline",
    "Timing",
    "VelocityCommand",
    "omega",
    "place_footsteps",
    "rollout",
    "signed_margin",
    "standing_feet",
    "straight_walk",
    "support_polygon",
]
