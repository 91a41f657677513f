"""A loaded robot's joint limits (:class:`~rtgait.interface.joint_limits.JointLimits`): the URDF's ``<limit>``
position range and velocity, and the drives' torque limit (the description's ``[actuation]`` ``effort_limit``, else
the URDF's ``effort``), in the order of ``robot.joint_names``.

Pinocchio stands a limit the URDF does not give by a huge number (or 0 for an effort): those are no limit (``inf``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rtgait.interface.joint_limits import JointLimits

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = ["joint_limits", "urdf_limit"]

_NO_LIMIT = 1e30  # a URDF value this large stands for no limit


def urdf_limit(value: float) -> float:
    """A URDF velocity or effort limit as a limit: missing (Pinocchio's huge default), 0 or not finite means none
    (``inf``)."""
    return value if math.isfinite(value) and 0.0 < value < _NO_LIMIT else math.inf


def _position(value: float, sign: float) -> float:
    return value if math.isfinite(value) and abs(value) < _NO_LIMIT else sign * math.inf


def joint_limits(robot: RobotModel) -> JointLimits:
    """The limits of ``robot``'s moving joints (module docstring), in the order of its joint commands."""
    model, description = robot.model, robot.description
    lower, upper, velocity, torque = [], [], [], []
    for i, name in enumerate(robot.joint_names):
        joint = model.joints[model.getJointId(name)]
        if joint.idx_q != 7 + i or joint.nq != 1:  # pragma: no cover - RobotModel's reduced models are built so
            raise ValueError(f"joint {name} is not the one-coordinate joint {i} after the free flyer")
        lower.append(_position(float(model.lowerPositionLimit[joint.idx_q]), -1.0))
        upper.append(_position(float(model.upperPositionLimit[joint.idx_q]), 1.0))
        velocity.append(urdf_limit(float(model.velocityLimit[joint.idx_v])))
        effort = description.joint_actuation(name).effort_limit
        torque.append(effort if effort is not None else urdf_limit(float(model.effortLimit[joint.idx_v])))
    return JointLimits(tuple(robot.joint_names), np.array(lower), np.array(upper), np.array(velocity), np.array(torque))
