"""The inertia each moving joint moves, and the velocity gains of the joints' damping mode scaled by it.

**Carried inertia** (about the joint's axis, at half-sitting, armature excluded): ``distal`` is the composite inertia
of everything beyond the joint (the diagonal of the joint-space mass matrix); ``carried`` is ``distal``, or for a joint
whose subtree holds a sole the larger of ``distal`` and the rest of the robot's inertia about the same axis (the foot
on the ground, the robot pivoting about the joint). It sets the default servo gains of the simulated drives
(:mod:`rtgait.sim.actuation`) and the damping gains below.

**Damping mode** (a joint command with ``kp = 0``: ``tau = kd (0 - dq)``, as Unitree's ``create_damping_cmd`` sends
to every motor of a G1 or H1 with ``kd = 8`` N m s/rad): the joints brake and the robot sinks slowly instead of
holding a reference it may no longer be able to follow. Per joint

    kd = I_carried / T_d                                                              (N m s/rad)

the gain that slows the inertia the joint carries with the time constant ``T_d``. The default ``T_d``,
:data:`DAMPING_TIME_CONSTANT` = 1 s, gives the G1's leg joints 1.4 to 17 N m s/rad (mean 7.6), Unitree's 8 on the same
robot; Talos's, three times heavier and larger, 4 to 70 N m s/rad.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from rtgait.robot.model import RobotModel

__all__ = ["DAMPING_TIME_CONSTANT", "carried_inertia", "damping_gains"]

DAMPING_TIME_CONSTANT = 1.0
"""The time constant of the damping mode's braking of each joint's carried inertia (s): module docstring."""


def carried_inertia(robot: RobotModel) -> tuple[np.ndarray, np.ndarray]:
    """The inertia each moving joint moves, about its own axis at half-sitting (kg m^2).

    Returns:
        ``(distal, carried)`` per joint of ``robot.joint_names`` (module docstring). Armature excluded.
    """
    model = robot.model
    data = model.createData()
    q = robot.q_half_sitting
    pin.computeJointJacobians(model, data, q)
    mass_matrix = pin.crba(model, data, q)
    pin.ccrba(model, data, q, np.zeros(model.nv))
    whole = data.oYcrb[1].matrix()  # the whole robot's spatial inertia (world frame, at the origin)
    soles = {model.frames[robot.left_sole_id].parentJoint, model.frames[robot.right_sole_id].parentJoint}
    distal, carried = [], []
    for joint in range(2, model.njoints):
        v = model.joints[joint].idx_v
        axis = data.J[:, v]  # the joint's unit motion, world frame at the origin
        own = float(mass_matrix[v, v])  # the subtree's composite inertia about the axis
        rest = float(axis @ whole @ axis) - own
        holds_sole = any(joint in model.supports[s] for s in soles)
        distal.append(own)
        carried.append(max(own, rest) if holds_sole else own)
    return np.array(distal), np.array(carried)


def damping_gains(robot: RobotModel, time_constant: float = DAMPING_TIME_CONSTANT) -> np.ndarray:
    """The damping mode's velocity gain of each joint of ``robot.joint_names``, ``I_carried / time_constant``
    (N m s/rad; module docstring).

    Raises:
        ValueError: a time constant that is not a duration > 0 s.
    """
    if not (math.isfinite(time_constant) and time_constant > 0.0):
        raise ValueError(f"the damping time constant must be a duration > 0 s, got {time_constant}")
    return carried_inertia(robot)[1] / time_constant
