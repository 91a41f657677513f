"""The upper body's lean on a real robot: its effective inertia and the hips' torque budget for it.

The hip strategy (:mod:`rtgait.core.laws.hip_strategy`) tilts the pelvis and torso together about the hips while the
whole-body IK holds the COM and both soles where they are. Its effective inertia about an axis ``a`` is the
centroidal angular momentum of that motion per unit lean rate:

    I_a = a . (A_g[3:6] dq),   dq: the joint velocity with  J_com dq = 0, J_soles dq = 0,
                               torso and pelvis angular velocity = a (rad/s)

with ``A_g`` Pinocchio's centroidal momentum matrix (``computeCentroidalMap``) and ``dq`` the least-squares
solution of those task equations (the IK's own Jacobians at half-sitting, :class:`~rtgait.robot.ik.WholeBodyIK`).
The COM stays put, so ``dq`` has no linear momentum: only angular momentum, the reaction-wheel effect the
strategy uses (the built-in robots' values: ``docs/robots.md``, "The hip strategy").

The lean's acceleration is bounded by the hip joints that make it: a share of the rated torque (URDF effort
limit) of the hip joint whose axis is the lean's (the leg joint closest to the pelvis whose axis lies within 40
degrees of it), over ``I_a``. The rest of the hip's torque carries the body and walks.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from rtgait.core.laws.hip_strategy import HipStrategyLimits
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.model import RobotModel

__all__ = ["HIP_TORQUE_SHARE", "hip_strategy_limits", "lean_inertia"]

HIP_TORQUE_SHARE = 0.5
"""Share of a hip joint's rated torque the lean may take (the rest carries the body)."""
_AXES = ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0))
"""The lean axes at half-sitting (feet heading +x): a forward lean turns about +y, a sideways one about +x."""
_ALIGNED = math.cos(math.radians(40.0))


def _lean_motions(robot: RobotModel) -> list[np.ndarray]:
    """The velocity ``dq`` (nv,) of a unit lean rate about each of :data:`_AXES` with the COM and the soles held
    (module docstring), from the IK's task Jacobian at half-sitting."""
    J = WholeBodyIK(robot).jacobian(robot.q_half_sitting)
    motions = []
    for axis in _AXES:
        wanted = np.zeros(len(J))
        wanted[15:18] = axis  # the torso's angular velocity
        wanted[18:21] = axis  # the pelvis's
        motions.append(np.linalg.lstsq(J, wanted, rcond=None)[0])
    return motions


def lean_inertia(robot: RobotModel) -> tuple[float, float]:
    """The lean's effective inertia ``(forward, sideways)`` (kg m^2) at half-sitting (module docstring)."""
    model, data = robot.model, robot.model.createData()
    centroidal = pin.computeCentroidalMap(model, data, robot.q_half_sitting)[3:6]
    values = [
        float(np.dot(centroidal @ motion, axis)) for axis, motion in zip(_AXES, _lean_motions(robot), strict=True)
    ]
    if min(values) <= 0.0:
        raise ValueError(f"{robot.name}: the upper body's lean has no angular momentum ({values}); no hip strategy")
    return values[0], values[1]


def _hip_torque(robot: RobotModel, axis: tuple[float, float, float]) -> float:
    """The smallest, over the two legs, rated torque (N m) of the leg joint closest to the pelvis whose axis is
    within 40 degrees of ``axis`` at half-sitting."""
    model, data = robot.model, robot.model.createData()
    pin.computeJointJacobians(model, data, robot.q_half_sitting)
    torques = []
    for sole in (robot.left_sole_id, robot.right_sole_id):
        chain = model.supports[model.frames[sole].parentJoint]  # joints from the root to the sole, in order
        for joint in list(chain)[2:]:  # past the universe and the free flyer
            column = pin.getJointJacobian(model, data, joint, pin.ReferenceFrame.WORLD)[3:6, model.joints[joint].idx_v]
            if abs(float(np.dot(column, axis))) >= _ALIGNED * float(np.linalg.norm(column)):
                torques.append(float(model.effortLimit[model.joints[joint].idx_v]))
                break
    if len(torques) != 2 or not all(math.isfinite(t) and 0.0 < t < 1e6 for t in torques):
        raise ValueError(f"{robot.name}: no rated hip joint about {axis} in each leg; no hip strategy")
    return min(torques)


def hip_strategy_limits(robot: RobotModel, max_lean: float = 0.25) -> HipStrategyLimits:
    """The hip strategy's limits for ``robot``: its lean inertia and the hips' torque budget
    (:data:`HIP_TORQUE_SHARE` of each hip's rated torque over the inertia), leaning at most ``max_lean`` (rad)."""
    inertia = lean_inertia(robot)
    accelerations = tuple(
        HIP_TORQUE_SHARE * _hip_torque(robot, axis) / i for axis, i in zip(_AXES, inertia, strict=True)
    )
    return HipStrategyLimits(inertia=inertia, max_acceleration=accelerations, max_lean=max_lean)  # type: ignore[arg-type]
