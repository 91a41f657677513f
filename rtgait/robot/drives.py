"""Each moving joint's drive as the robot description states it: its torque limit and its armature, the rotor
inertia the joint carries through the gear (``J_rotor N^2``).

The values of the description's ``[actuation]`` table (:mod:`rtgait.robot.actuation_table`), else defaults from the
URDF: the torque limit is the URDF's ``<limit effort>`` (none when it is missing, 0 or infinite), the armature
``armature_per_torque`` times that limit. The simulator's servos (:mod:`rtgait.sim.actuation`) and the state
estimator's leg dynamics (:mod:`rtgait.robot.kinematics`) read them here, so both have the same drives.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.robot.joint_limits import joint_limits
from rtgait.robot.model import RobotModel

__all__ = ["joint_drives"]


def joint_drives(robot: RobotModel) -> tuple[np.ndarray, np.ndarray]:
    """The moving joints' torque limits (N m, ``inf``: none; :func:`~rtgait.robot.joint_limits.joint_limits`'s) and
    armatures (kg m^2), in ``robot.joint_names`` order (module docstring)."""
    limits = joint_limits(robot).torque
    armatures = []
    for name, limit in zip(robot.joint_names, limits, strict=True):
        spec = robot.description.joint_actuation(name)
        rotor = spec.armature
        if rotor is None:
            rotor = spec.armature_per_torque * limit if math.isfinite(limit) else 0.0
        armatures.append(rotor)
    return limits, np.array(armatures)
