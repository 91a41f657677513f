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

**Sharing the estimator's kinematics**: the kinematic-inertial estimator has already placed the soles relative to
the base for the same encoder readings, with their velocities from the joints' (``p``, ``R``, ``u``, ``w``, base axes,
:class:`~rtgait.interface.body_kinematics.BodyKinematics`). Given them, the base's twist needs no Jacobian: the sole
is still when the base turns at ``-w`` and its origin moves at ``w x p - u`` (its own axes). One kinematics pass a tick
fewer (the stack passes them, :mod:`rtgait.stack.estimators`); without them (a test, another estimator) the pass runs
here.

**Acceleration**: the IK motion's own ``a_ref`` (its base's and joints', consistent with both feet's targets), so that
inverse dynamics at ``(q_s, v_s, a_ref)`` gives the torques of gravity and of the motion's inertia at the joints' real
configuration, and the contact wrenches the motion needs.

**Base tracking**: the base's height over the stance sole is pulled toward the IK's by a PD in the base's vertical
acceleration (``k_p``, ``k_d`` below; the height compared over the sole, so that the estimate's offsets in height do not
enter):

    a_b,z += k_p (h_ref - h_s) + k_d (h_ref' - h_s')

Inverse dynamics turns it into the vertical force the feet must add (the whole robot's mass times it) and the legs'
torques that push it: the height is held by the feet's wrenches, as a COM task's height does in TSID, not by the
joints' stiffness. The horizontal position is the DCM law's (its commanded wrench). The base's orientation gets no
such task: sensed through the estimator's attitude (G1's IMU: 8.7 mrad of noise) and multiplied by the whole body's
inertia times ``k_p``, it made G1 fall after three steps of fig8, its hips at their torque limit (without it G1 walks
all eleven, TALOS too); the trunk's orientation is the joints' tracking's, on the encoders.

**Joint tracking**: the errors from the IK's joint references are corrected by a PD on each joint scaled by the
inertia of what lies beyond it (``I_j``, kg m^2: the mass matrix's diagonal at half-sitting,
:func:`~rtgait.robot.joint_inertia.carried_inertia`'s ``distal``, plus its drive's armature):

    tau_fb = I_j w^2 (q_ref - q_s),        kd_drive = 2 I_j w                              (N m, N m s/rad)

critically damped at ``w = 2 pi`` :data:`TRACKING_FREQUENCY`: a computed-torque law with the mass matrix's diagonal.
The stiffness is the controller's, on the encoders; the damping is the drives' own velocity loop's (added to the
command's ``kd``, :mod:`rtgait.sim.drive_mode`), on the joint's velocity at every physics step: computed by the
controller from velocities a control period old and held over the period, the same damping makes G1's legs chatter
at its 500 Hz (the hips at their torque limit within 0.1 s of the start).
Not the inertia a stance joint carries (the whole robot pivoting about it, ten to a hundred times more): computed from
sensed velocities a sample or two late, damping that large makes the light links chatter (TALOS's knees at their
torque limit every other tick); what a stance leg carries is held by the base's task instead. Gravity no longer takes
stiffness away (it is compensated at the sensed configuration), so this rate needs to be well above the gait's (a
step a second), not above gravity's toppling rate; it stays well below what the loop's delays allow (a command a
period late and a sensor sample or two behind: ``w`` times the few milliseconds of delay is under a quarter radian).
The joint-space PD is the
posture task of TSID or mc_rtc's torque mode; their COM and base tasks are here the IK's references and the DCM
law's wrench (:mod:`rtgait.stack.feedforward`).

**Position drive** (``track=False``): the sensed state and the IK's acceleration alone, the drives' own gains doing
the tracking. It matters where a drive is about as soft as gravity's toppling: G1's waist at 40 N m/rad against the
upper body's ``m g l`` of some 35 N m/rad. Torques of gravity at the reference, not at the sensed configuration,
leave the trunk nearly no net stiffness: it sags by a tenth of a radian in each single support, and the robot fell
after 8 of fig8's 11 steps; with them it walks them all.
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
    from rtgait.interface.body_kinematics import BodyKinematics
    from rtgait.robot.model import RobotModel

__all__ = ["TRACKING_FREQUENCY", "MeasuredMotion"]

TRACKING_FREQUENCY = 5.0
"""The tracking PD's natural frequency (Hz; module docstring)."""

_LOCAL = pin.ReferenceFrame.LOCAL
# The calls of a tick, bound once.
_SE3, _rpy_to_matrix, _se3_to_xyzquat = pin.SE3, pin.rpy.rpyToMatrix, pin.SE3ToXYZQUAT


class MeasuredMotion:
    """The sensed state and the tracking torques of the module docstring.

    Args:
        robot: the loaded robot (its Pinocchio model, sole frames).
        frequency: the tracking PD's natural frequency (Hz), ``> 0``.
        track: whether to add the base's and the joints' tracking (torque drive); ``False``: the sensed state and the
            IK's acceleration alone (position drive, whose drives' own gains track; module docstring).
    """

    def __init__(self, robot: RobotModel, frequency: float = TRACKING_FREQUENCY, track: bool = True) -> None:
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
        self.track = track
        if not track:
            self.kp = self.kd = 0.0
        self.stiffness = self.kp * self.inertia
        """``I_j w^2`` per joint (N m/rad): the tracking's stiffness, applied by :attr:`feedback`."""
        self.damping = self.kd * self.inertia
        """``2 I_j w`` per joint (N m s/rad): the tracking's damping, for the drives to apply (module docstring)."""
        self.feedback = np.zeros(nv - 6)
        """The last :meth:`update`'s tracking torques ``I_j w^2 (q_ref - q_s)`` (N m, joint order; rewritten by the
        next)."""
        self.q = np.zeros(robot.model.nq)
        self.v = np.zeros(nv)
        self.a = np.zeros(nv)
        # The estimator's sole rotation (row-major) and translation, then the stance sole's measured position.
        self._pose_values = np.zeros(15)
        self._sole_matrix = self._pose_values[:9].reshape(3, 3)  # views
        self._sole_translation = self._pose_values[9:12]
        self._point = self._pose_values[12:15]

    def update(
        self,
        q_ref: np.ndarray,
        v_ref: np.ndarray,
        a_ref: np.ndarray,
        joints_ref: np.ndarray,
        joints: np.ndarray,
        joint_velocities: np.ndarray,
        measurement: Measurement,
        body: BodyKinematics | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q_s, v_s, a_ref)`` (module docstring; arrays kept and rewritten by the next call, ``a_ref`` itself without
        tracking), and the tracking
        torques in :attr:`feedback`, from the IK's
        configuration ``q_ref`` and its rates ``v_ref``, ``a_ref`` (Pinocchio's coordinates), the commanded joints
        ``joints_ref`` (rad; the IK's with the feet's tilts), the encoders' ``joints`` (rad) and
        ``joint_velocities`` (rad/s) and the estimator's ``measurement`` (the stance sole's pose). ``body``: the
        estimator's kinematics of those encoder readings (the soles relative to the base), which spares this tick its
        own pass ("Sharing the estimator's kinematics"); ``None``: computed here."""
        model, data = self.model, self.data
        left, right = measurement.left, measurement.right
        side = 0 if left.normal_force >= right.normal_force else 1
        foot = left if side == 0 else right
        sole = self._soles[side]
        q, v, a = self.q, self.v, self.a
        q[7:] = joints  # the base's coordinates below
        v[6:] = joint_velocities
        if body is None:
            base_ref = pin.XYZQUATToSE3(q_ref[:7])
            # The joints' kinematics with the IK's base: the sole's placement relative to the base, and its Jacobian
            # in its own axes (which does not depend on where the base is); the base's twist from J_b v_b = -J_j dq.
            q[:7] = q_ref[:7]
            pin.computeJointJacobians(model, data, q)
            sole_in_base = base_ref.actInv(pin.updateFramePlacement(model, data, sole))
            jacobian = pin.getFrameJacobian(model, data, sole, _LOCAL)
            v[:6] = np.linalg.solve(jacobian[:, :6], -(jacobian[:, 6:] @ joint_velocities))
            x, y, z, yaw = foot.pose
            self._point[:] = x, y, z
        else:
            # The estimator's: the sole relative to the base at rest, moving at (u, w) from the joints alone (base
            # axes); the base's twist that holds the sole still is (w x p - u, -w) in its own axes.
            frame = body.left_sole if side == 0 else body.right_sole
            px, py, pz = position = frame.position
            ux, uy, uz = frame.velocity
            wx, wy, wz = frame.angular_velocity
            v[:6] = (wy * pz - wz * py - ux, wz * px - wx * pz - uy, wx * py - wy * px - uz, -wx, -wy, -wz)
            # Into views of one buffer kept for it (one assignment, no array made a tick), copied by the SE3s.
            x, y, z, yaw = foot.pose
            self._pose_values[:] = (*frame.rotation, *position, x, y, z)
            sole_in_base = _SE3(self._sole_matrix, self._sole_translation)
        measured = _SE3(_rpy_to_matrix(foot.roll, foot.pitch, yaw), self._point)
        base = measured * sole_in_base.inverse()
        q[:7] = _se3_to_xyzquat(base)
        fb = self.feedback
        if not self.track:
            return q, v, a_ref  # the IK's acceleration itself: nothing is added to it
        a[:] = a_ref
        # The IK's base height over its stance sole (m), to compare with the sensed one's.
        base_ref = pin.XYZQUATToSE3(q_ref[:7])
        pin.forwardKinematics(model, data, q_ref)
        height_ref = float(base_ref.translation[2] - pin.updateFramePlacement(model, data, sole).translation[2])
        # The base's height over the stance sole toward the IK's, in the base's acceleration.
        rotation, rotation_ref = base.rotation, base_ref.rotation
        height_error = height_ref - float(base.translation[2] - z)
        rate_error = float(rotation_ref[2] @ v_ref[:3] - rotation[2] @ v[:3])
        a[:3] += rotation[2] * (self.kp * height_error + self.kd * rate_error)  # R^T (0, 0, a_z): the base's axes
        np.subtract(joints_ref, joints, out=fb)
        fb *= self.stiffness
        return q, v, a
