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

from rtgait.robot.model import RobotModel

__all__ = ["effort_limit", "joint_drives"]


def effort_limit(value: float) -> float:
    """A URDF effort limit as a torque limit: missing (Pinocchio's huge default), 0 or not finite means none."""
    return value if math.isfinite(value) and 0.0 < value < 1e30 else math.inf


def joint_drives(robot: RobotModel) -> tuple[np.ndarray, np.ndarray]:
    """The moving joints' torque limits (N m, ``inf``: none) and armatures (kg m^2), in ``robot.joint_names`` order
    (module docstring)."""
    model, description = robot.model, robot.description
    limits, armatures = [], []
    for name in robot.joint_names:
        spec = description.joint_actuation(name)
        joint = model.joints[model.getJointId(name)]
        limit = spec.effort_limit if spec.effort_limit is not None else effort_limit(model.effortLimit[joint.idx_v])
        rotor = spec.armature
        if rotor is None:
            rotor = spec.armature_per_torque * limit if math.isfinite(limit) else 0.0
        limits.append(limit)
        armatures.append(rotor)
    return np.array(limits), np.array(armatures)
