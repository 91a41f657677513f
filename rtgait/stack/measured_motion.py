"""The robot's sensed configuration and velocity, and the joint torques that track the IK's motion from them: what the
feed-forward torques of torque drive are computed at (:mod:`rtgait.stack.feedforward`), as TSID and mc_rtc's torque
mode compute theirs at the measured state.

**Configuration** ``q_s``: the encoders' joint positions; the floating base placed so that the stance sole (the foot
that carries more of the measured load) sits where the estimator has it, ``(x, y, z)`` and ``R = Rz(yaw) Ry(pitch)
Rx(roll)`` of its :class:`~rtgait.estimation.state.FootState`: with the joints' forward kinematics ``T_sole = T_base
T_bs(q)``, the base is ``T_base = T_sole,measured T_bs^-1``. The base's tilt is thus the stance leg's and the sole's,
which is what gravity's torques at the joints depend on.

**Velocity** ``v_s``: the encoders' joint velocities ``dq``; the base's twist the one that holds the stance sole still,
``J_b v_b + J_j dq = 0`` with ``J = [J_b J_j]`` the sole frame's Jacobian (its own axes; ``J_b``, 6x6, is the sole's
adjoint seen from the base, always invertible).

**Acceleration**: the IK motion's own ``a_ref`` (its base's and joints', consistent with both feet's targets), so that
inverse dynamics at ``(q_s, v_s, a_ref)`` gives the torques of gravity and of the motion's inertia at the joints' real
configuration, and the contact wrenches the motion needs.

**Tracking**: the errors from the IK's joint references are corrected by a PD on each joint scaled by the inertia it
carries (:func:`~rtgait.robot.joint_inertia.carried_inertia` plus its drive's armature, ``I_j``, kg m^2):

    tau_fb = I_j (w^2 (q_ref - q_s) + 2 w (dq_ref - dq))                                     (N m)

critically damped at ``w = 2 pi`` :data:`TRACKING_FREQUENCY`: every joint settles at the same rate whatever it
carries, a computed-torque law with the mass matrix's diagonal. Gravity no longer takes stiffness away (it is
compensated at the sensed configuration), so this rate needs to be well above the gait's (a step a second), not above
gravity's toppling rate; it stays well below what the loop's delays allow (a command a period late and a sensor sample
or two behind: ``w`` times the few milliseconds of delay is under a quarter radian). The joint-space PD is the
posture task of TSID or mc_rtc's torque mode; their COM and base tasks are here the IK's references and the DCM
law's wrench (:mod:`rtgait.stack.feedforward`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from rtgait.robot.drives import joint_drives
from rtgait.robot.joint_inertia import carried_inertia

if TYPE_CHECKING:
    from rtgait.estimation.state import Measurement
    from rtgait.robot.model import RobotModel

__all__ = ["TRACKING_FREQUENCY", "MeasuredMotion"]

TRACKING_FREQUENCY = 5.0
"""The tracking PD's natural frequency (Hz; module docstring)."""

_LOCAL = pin.ReferenceFrame.LOCAL


class MeasuredMotion:
    """The sensed state and the tracking torques of the module docstring.

    Args:
        robot: the loaded robot (its Pinocchio model, sole frames).
        frequency: the tracking PD's natural frequency (Hz), ``> 0``.
    """

    def __init__(self, robot: RobotModel, frequency: float = TRACKING_FREQUENCY) -> None:
        if not (math.isfinite(frequency) and frequency > 0.0):
            raise ValueError(f"the tracking frequency must be > 0 Hz, got {frequency}")
        w = 2.0 * math.pi * frequency
        self.kp, self.kd = w * w, 2.0 * w
        self.model = robot.model
        self.data = robot.model.createData()
        self._soles = (robot.left_sole_id, robot.right_sole_id)
        nv = robot.model.nv
        distal, _ = carried_inertia(robot)
        self.inertia = distal + joint_drives(robot)[1]
        self.feedback = np.zeros(nv - 6)
        """The last :meth:`update`'s tracking torques ``tau_fb`` (N m, joint order; rewritten by the next)."""
        self.q = np.zeros(robot.model.nq)
        self.v = np.zeros(nv)
        self.a = np.zeros(nv)

    def update(
        self,
        q_ref: np.ndarray,
        v_ref: np.ndarray,
        a_ref: np.ndarray,
        joints_ref: np.ndarray,
        joints: np.ndarray,
        joint_velocities: np.ndarray,
        measurement: Measurement,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q_s, v_s, a_ref)`` (module docstring; arrays kept and rewritten by the next call), and the tracking
        torques in :attr:`feedback`, from the IK's
        configuration ``q_ref`` and its rates ``v_ref``, ``a_ref`` (Pinocchio's coordinates), the commanded joints
        ``joints_ref`` (rad; the IK's with the feet's tilts), the encoders' ``joints`` (rad) and
        ``joint_velocities`` (rad/s) and the estimator's ``measurement`` (the stance sole's pose)."""
        model, data = self.model, self.data
        left, right = measurement.left, measurement.right
        side = 0 if left.normal_force >= right.normal_force else 1
        foot = left if side == 0 else right
        sole = self._soles[side]
        q, v, a = self.q, self.v, self.a
        q[:] = q_ref
        q[7:] = joints
        # The joints' kinematics with the IK's base: the sole's placement relative to the base, and its Jacobian in
        # its own axes (which does not depend on where the base is).
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, sole)
        jacobian = pin.getFrameJacobian(model, data, sole, _LOCAL)
        x, y, z, yaw = foot.pose
        measured = pin.SE3(pin.rpy.rpyToMatrix(foot.roll, foot.pitch, yaw), np.array([x, y, z]))
        base = measured * data.oMf[sole].inverse() * pin.XYZQUATToSE3(q_ref[:7])
        q[:7] = pin.SE3ToXYZQUAT(base)
        base_part, joint_part = jacobian[:, :6], jacobian[:, 6:]
        v[6:] = joint_velocities
        v[:6] = np.linalg.solve(base_part, -(joint_part @ joint_velocities))
        a[:] = a_ref
        fb = self.feedback
        np.subtract(joints_ref, joints, out=fb)
        fb *= self.kp
        fb += self.kd * (v_ref[6:] - joint_velocities)
        fb *= self.inertia
        return q, v, a
