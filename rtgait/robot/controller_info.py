"""A loaded robot model summed up as what a walking controller knows of it (:class:`~rtgait.interface.robot_info.
RobotInfo`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.interface.robot_info import RobotInfo
from rtgait.robot.lean import hip_strategy_limits

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = ["robot_info"]


def robot_info(robot: RobotModel, sole: SoleRect | None = None, gains: str = "stiff") -> RobotInfo:
    """From a loaded robot: its mass, its described sole (or ``sole``), its walking COM height, its ``[stepping]``
    limits and its upper body's lean (none when its hips cannot make one), bounded by its hips' servos when driven
    at its own ``gains="robot"`` (:func:`~rtgait.robot.lean.hip_strategy_limits`)."""
    description = robot.description
    try:
        lean = hip_strategy_limits(robot, gains=gains)
    except ValueError:
        lean = None
    return RobotInfo(robot.mass, sole or description.sole, description.cog_height, description.stepping, lean)
