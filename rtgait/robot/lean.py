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

On the robot's own drives (``gains="robot"``: soft position servos), the lean is also bounded by what that hip's servo
can follow: its closed-loop natural frequency ``w_s = sqrt(kp / (I_a + armature))`` (1/s) with ``kp`` the joint's
``robot_kp`` (the softer of the two legs: in single support one hip makes the lean), which shapes the lean's reference
(:mod:`rtgait.core.laws.servo_reference`: acceleration at most ``w_s^2 max_lean``, rate ``w_s max_lean``).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from rtgait.core.laws.hip_strategy import HipStrategyLimits
from rtgait.interface.command import GAIN_SETS
from rtgait.robot.drives import joint_drives
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.model import RobotModel

__all__ = ["HIP_TORQUE_SHARE", "hip_strategy_limits", "lean_inertia", "servo_bandwidth"]

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


def _hip_joints(robot: RobotModel, axis: tuple[float, float, float]) -> list[int]:
    """Per leg, the velocity index of the leg joint closest to the pelvis whose axis is within 40 degrees of
    ``axis`` at half-sitting."""
    model, data = robot.model, robot.model.createData()
    pin.computeJointJacobians(model, data, robot.q_half_sitting)
    found = []
    for sole in (robot.left_sole_id, robot.right_sole_id):
        chain = model.supports[model.frames[sole].parentJoint]  # joints from the root to the sole, in order
        for joint in list(chain)[2:]:  # past the universe and the free flyer
            column = pin.getJointJacobian(model, data, joint, pin.ReferenceFrame.WORLD)[3:6, model.joints[joint].idx_v]
            if abs(float(np.dot(column, axis))) >= _ALIGNED * float(np.linalg.norm(column)):
                found.append(model.joints[joint].idx_v)
                break
    return found


def _hip_torque(robot: RobotModel, axis: tuple[float, float, float]) -> float:
    """The smallest, over the two legs, rated torque (N m) of :func:`_hip_joints`."""
    torques = [float(robot.model.effortLimit[v]) for v in _hip_joints(robot, axis)]
    if len(torques) != 2 or not all(math.isfinite(t) and 0.0 < t < 1e6 for t in torques):
        raise ValueError(f"{robot.name}: no rated hip joint about {axis} in each leg; no hip strategy")
    return min(torques)


def servo_bandwidth(robot: RobotModel, inertia: tuple[float, float] | None = None) -> tuple[float, float]:
    """The closed-loop natural frequency ``sqrt(robot_kp / (I_a + armature))`` (1/s) of the hip joint that makes
    each lean ``(forward, sideways)`` at the robot's own gains, the softer leg's (module docstring); ``inertia``:
    :func:`lean_inertia`'s, computed when not given.

    Raises:
        ValueError: a hip joint without ``robot_kp`` in the description.
    """
    inertia = inertia or lean_inertia(robot)
    _, armature = joint_drives(robot)
    names = robot.joint_names
    bandwidths = []
    for axis, moved in zip(_AXES, inertia, strict=True):
        lowest = math.inf
        for v in _hip_joints(robot, axis):
            index = v - 6  # the free flyer's 6 velocities come first
            kp = robot.description.joint_actuation(names[index]).robot_kp
            if kp is None:
                raise ValueError(f"{robot.name}: joint {names[index]} has no robot_kp; no servo bound for the lean")
            lowest = min(lowest, math.sqrt(kp / (moved + float(armature[index]))))
        bandwidths.append(lowest)
    return bandwidths[0], bandwidths[1]


def hip_strategy_limits(robot: RobotModel, max_lean: float = 0.25, gains: str = "stiff") -> HipStrategyLimits:
    """The hip strategy's limits for ``robot``: its lean inertia and the hips' torque budget
    (:data:`HIP_TORQUE_SHARE` of each hip's rated torque over the inertia), leaning at most ``max_lean`` (rad); with
    ``gains="robot"`` (the robot's own soft servos) also :func:`servo_bandwidth`."""
    if gains not in GAIN_SETS:
        raise ValueError(f"gains must be {' or '.join(map(repr, GAIN_SETS))}, got {gains!r}")
    inertia = lean_inertia(robot)
    accelerations = tuple(
        HIP_TORQUE_SHARE * _hip_torque(robot, axis) / i for axis, i in zip(_AXES, inertia, strict=True)
    )
    bandwidth = servo_bandwidth(robot, inertia) if gains == "robot" else None
    return HipStrategyLimits(
        inertia=inertia,
        max_acceleration=accelerations,  # type: ignore[arg-type]
        max_lean=max_lean,
        servo_bandwidth=bandwidth,
    )
