"""What a walking controller knows of its robot: mass, sole, leg length, stepping limits and upper-body lean.

Plain values (SI units), filled from a robot model by :func:`rtgait.robot.controller_info.robot_info` or by hand
for a robot rtgait has no model of.
"""

from __future__ import annotations

from dataclasses import dataclass

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.laws.hip_strategy import HipStrategyLimits
from rtgait.core.laws.stepping import SteppingLimits

__all__ = ["RobotInfo"]


@dataclass(frozen=True)
class RobotInfo:
    """What the controllers need to know about the robot (SI units).

    Attributes:
        mass: (kg).
        sole: the sole rectangle around the sole frame (m).
        leg_length: scale of the stride box (m) when ``stepping`` is ``None``: the walking COM height serves
            (:func:`rtgait.robot.controller_info.robot_info`).
        stepping: the robot description's ``[stepping]`` limits (:class:`~rtgait.core.laws.stepping.SteppingLimits`),
            the stride box of step adjustment (:func:`step_limits`); ``None``: none described.
        lean: the upper body's lean inertia and acceleration limits for the hip strategy
            (:func:`rtgait.robot.lean.hip_strategy_limits`); ``None``: no hip strategy.
    """

    mass: float
    sole: SoleRect
    leg_length: float
    stepping: SteppingLimits | None = None
    lean: HipStrategyLimits | None = None
