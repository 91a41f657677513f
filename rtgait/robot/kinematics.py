"""A robot's kinematics for the state estimator, with Pinocchio: the frames of
:class:`~rtgait.interface.body_kinematics.BodyKinematics` relative to the floating base, the feet's force sensor
mounts and the legs' dynamics (the protocol :class:`rtgait.estimation.kinematics.RobotKinematics`).

The reduced model's configuration is the base at the origin, unrotated, and the encoders' joints; its velocity the
joints' alone. One ``centerOfMass(q, v)`` a tick runs the forward kinematics (positions and velocities) and the COM
with its velocity; the sole frames and the IMU's are read off it (the IMU's only when a joint moves it relative to
the base). The legs' dynamics (for a robot without foot force sensors) cost one recursive Newton-Euler pass and the
joint Jacobians from the placements the forward kinematics left.

**Legs' dynamics.** The joint torques of the whole tree for the base's motion and the joints' (inverse dynamics,
the soles free), of which the legs' rows depend only on the base's motion and the leg's own: the base frame turning
at ``w`` with angular acceleration ``w'`` and its origin accelerating at ``a``. The gravity is the base origin's
specific force ``f = a - g`` taken as the base's linear acceleration in a gravity-free model: a body at rest in
gravity and one accelerated upward at ``g`` without it have the same joint torques. The base's linear velocity is
taken as zero: a constant velocity added to every body changes no acceleration, hence no force, and with it zero
the base's spatial acceleration is its origin's classical one. The drives' armatures (:mod:`rtgait.robot.drives`)
add ``I_a q''`` to each joint, as the rotors a motor's torque also accelerates.

A foot force sensor on frame ``s`` measures the wrench between the body it is on and that body's parent (as a
simulator's force sensor at a site does, and an ankle sensor between shin and foot): the mass it carries besides
the ground's force is that of the subtree of the frame's joint (the foot), centred where that subtree's COM is.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from rtgait.interface.body_kinematics import BodyKinematics, ForceSensorMount, FrameMotion
from rtgait.interface.sensor_spec import SensorFrame
from rtgait.robot.description import RobotError
from rtgait.robot.drives import joint_drives
from rtgait.robot.model import RobotModel

__all__ = ["PinocchioKinematics"]

_ROOT = 1  # the free flyer's joint id in Pinocchio's models (0 is the universe)
_AT_REST = (0.0, 0.0, 0.0)
_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing
# The calls of a tick, bound once (a module attribute lookup each otherwise).
_center_of_mass, _frame_placement, _frame_velocity = pin.centerOfMass, pin.updateFramePlacement, pin.getFrameVelocity
_rnea, _joint_jacobians, _frame_jacobian = pin.rnea, pin.computeJointJacobians, pin.getFrameJacobian
_WORLD, _LOCAL = pin.LOCAL_WORLD_ALIGNED, pin.LOCAL


class PinocchioKinematics:
    """The estimator's kinematics of ``robot`` (module docstring).

    Args:
        robot: the loaded robot; its reduced model (the joints the readings carry).
        imu: the IMU's frame (a link or joint of the model and an offset in it, the link's axes); ``None``: the
            base's own frame.
        feet: the left and right feet's force sensor frames; ``None``: a robot without foot force sensors (its feet's
            wrenches come from the joint torques).

    Raises:
        RobotError: a frame the model does not have, a foot sensor not on its sole's body, or a leg whose joints are
            not all one-coordinate joints.
    """

    def __init__(
        self,
        robot: RobotModel,
        imu: SensorFrame | None = None,
        feet: tuple[SensorFrame, SensorFrame] | None = None,
    ) -> None:
        model = pin.Model(robot.model)  # its own copy: without gravity, with the drives' armatures and sensor frames
        imu_frame = None if imu is None else _add_frame(model, "rtgait_imu", imu, "sensors.imu.frame")
        sensor_frames = None
        if feet is not None:
            sensor_frames = tuple(
                _add_frame(model, f"rtgait_{side}_foot_sensor", frame, f"sensors.feet.{side}_frame")
                for side, frame in zip(("left", "right"), feet, strict=True)
            )
        self.model, self.data = model, model.createData()
        self.joint_count = model.nv - 6
        self.mass = robot.mass
        self._q = pin.neutral(model)
        self._v = np.zeros(model.nv)
        self._soles = (robot.left_sole_id, robot.right_sole_id)
        self._imu = imu_frame
        self.leg_joints = (self._leg(robot.left_sole_id), self._leg(robot.right_sole_id))
        # Each leg's columns of the velocity vector: a slice where they follow each other (no copy to index them).
        self._leg_columns = tuple(_columns(leg, 6) for leg in self.leg_joints)
        # The legs' needed torques: a view of the inverse dynamics' output in the data (rewritten by each pass), both
        # legs' rows at once when the right leg's joints follow the left's; else gathered into an array.
        both = _columns(self.leg_joints[0] + self.leg_joints[1], 6)
        legs_shape = (2, len(self.leg_joints[0]))
        self._needed = self.data.tau[both].reshape(legs_shape) if isinstance(both, slice) else np.empty(legs_shape)
        self._needed_rows = None if isinstance(both, slice) else both
        # The legs' dynamics: the gravity comes in as the base's specific force (module docstring); the rotors.
        model.gravity = pin.Motion.Zero()
        model.armature[6:] = joint_drives(robot)[1]
        self._v_dynamics = np.zeros(model.nv)
        self._a_dynamics = np.zeros(model.nv)
        standing = model.createData()  # for the fixed placements, at half-sitting
        pin.centerOfMass(model, standing, robot.q_half_sitting)
        pin.framesForwardKinematics(model, standing, robot.q_half_sitting)
        # An IMU on the base's own body has a fixed placement: read once.
        self._imu_fixed: FrameMotion | None = None
        if self._imu is None:
            self._imu_fixed = FrameMotion(_AT_REST, (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), _AT_REST, _AT_REST)
        elif model.frames[self._imu].parentJoint == _ROOT:
            placement = model.frames[self._imu].placement
            self._imu_fixed = FrameMotion(
                tuple(placement.translation.tolist()), tuple(placement.rotation.ravel().tolist()), _AT_REST, _AT_REST
            )
        # Views of the data's arrays that the forward kinematics rewrite in place: the COM, its velocity, each frame's
        # translation and rotation (the frames' velocities are new arrays each tick).
        data = self.data
        frames = (robot.left_sole_id, robot.right_sole_id) + (() if self._imu_fixed is not None else (self._imu,))
        self._frames = (*frames[:2], frames[2] if len(frames) == 3 else -1)
        self._com, self._com_velocity = data.com[0], data.vcom[0]
        self._placements = {frame: (data.oMf[frame].translation, data.oMf[frame].rotation) for frame in frames}
        self.foot_sensors: tuple[ForceSensorMount, ForceSensorMount] | None = None
        if sensor_frames is not None:
            self.foot_sensors = tuple(  # type: ignore[assignment]
                self._mount(standing, sole, sensor) for sole, sensor in zip(self._soles, sensor_frames, strict=True)
            )

    def update(self, joint_positions: np.ndarray, joint_velocities: np.ndarray) -> BodyKinematics:
        """The frames for the joints' positions (rad) and velocities (rad/s), base frame, base at rest."""
        model, data, q, v = self.model, self.data, self._q, self._v
        q[7:] = joint_positions
        v[6:] = joint_velocities
        _center_of_mass(model, data, q, v, False)  # forward kinematics (positions, velocities), COM, COM velocity
        left, right, imu = self._frames
        fixed = self._imu_fixed
        return _new_tuple(
            BodyKinematics,
            (tuple(self._com.tolist()), tuple(self._com_velocity.tolist()), self._frame_motion(left),
             self._frame_motion(right), self._frame_motion(imu) if fixed is None else fixed),
        )  # fmt: skip

    def _frame_motion(self, frame: int) -> FrameMotion:
        """A frame's placement and velocity after the forward kinematics, as Python floats: position, rotation
        (row-major), linear and angular velocity (base frame)."""
        model, data = self.model, self.data
        translation, rotation = self._placements[frame]
        _frame_placement(model, data, frame)
        r0, r1, r2 = rotation.tolist()
        vx, vy, vz, wx, wy, wz = _frame_velocity(model, data, frame, _WORLD).vector.tolist()
        return _new_tuple(FrameMotion, (tuple(translation.tolist()), (*r0, *r1, *r2), (vx, vy, vz), (wx, wy, wz)))

    def leg_dynamics(
        self, angular_velocity: tuple[float, float, float], acceleration: tuple[float, ...],
        joint_accelerations: np.ndarray,
    ) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:  # fmt: skip
        """The soles' Jacobians (sole frame, rows linear then angular) with respect to each leg's joints, left then
        right, shape ``(6, n_leg)`` each, and the torques each leg's joints need for the motion with the soles free,
        shape ``(2, n_leg)``, at the configuration and joint velocities of the last :meth:`update` (the torques an
        array the next call overwrites; module docstring).

        Args:
            angular_velocity: the base's angular velocity (rad/s, base frame).
            acceleration: the base origin's specific force ``a - g`` (m/s^2) then the base's angular acceleration
                (rad/s^2), base frame.
            joint_accelerations: the joints' accelerations (rad/s^2), shape ``(joint_count,)``.
        """
        model, data, q, v, a = self.model, self.data, self._q, self._v_dynamics, self._a_dynamics
        v[:] = self._v  # the joints' velocities of update(), the base at rest; then the base turning
        v[3], v[4], v[5] = angular_velocity
        a[0:6] = acceleration
        a[6:] = joint_accelerations
        _rnea(model, data, q, v, a)  # into data.tau, of which the needed torques are a view
        _joint_jacobians(model, data)  # from the joint placements of q, which update() and rnea computed
        (left, right), (columns_left, columns_right) = self._soles, self._leg_columns
        # Each sole's columns of its frame Jacobian: views of Pinocchio's new arrays, no copy.
        jacobians = (_frame_jacobian(model, data, left, _LOCAL)[:, columns_left],
                     _frame_jacobian(model, data, right, _LOCAL)[:, columns_right])  # fmt: skip
        needed, rows = self._needed, self._needed_rows
        if rows is not None:  # legs whose joints do not follow each other: gathered
            data.tau.take(rows, out=needed.reshape(-1))
        return jacobians, needed

    # ----- construction --------------------------------------------------------------------------------------------
    def _leg(self, sole: int) -> tuple[int, ...]:
        """The joints from the base to a sole's body, as indices into the joint order."""
        model = self.model
        chain = [j for j in model.supports[model.frames[sole].parentJoint] if j > _ROOT]
        if any(model.joints[j].nv != 1 for j in chain):
            raise RobotError(f"the leg of frame {model.frames[sole].name!r} has joints of more than one coordinate")
        return tuple(model.joints[j].idx_v - 6 for j in chain)

    def _mount(self, data: pin.Data, sole: int, sensor: int) -> ForceSensorMount:
        """A force sensor's mount in its sole frame at half-sitting (both fixed on the foot), and the foot's mass below
        it (module docstring)."""
        model = self.model
        if model.frames[sensor].parentJoint != model.frames[sole].parentJoint:
            raise RobotError(
                f"the foot force sensor frame {model.frames[sensor].name!r} is not on the body of the sole frame "
                f"{model.frames[sole].name!r}"
            )
        in_sole = data.oMf[sole].actInv(data.oMf[sensor])
        joint = model.frames[sole].parentJoint
        # The subtree of the foot's joint: its mass and COM (Pinocchio's data.mass and data.com per joint subtree, the
        # COM in the joint's frame), the COM then in the sole frame.
        mass = float(data.mass[joint])
        com = model.frames[sole].placement.actInv(data.com[joint])
        return ForceSensorMount(
            tuple(in_sole.translation.tolist()), tuple(in_sole.rotation.ravel().tolist()), mass, tuple(com.tolist())
        )


def _add_frame(model: pin.Model, name: str, frame: SensorFrame, field: str) -> int:
    """A frame ``name`` at a sensor's frame (its link's axes, the offset in the link's frame) added to ``model``."""
    if not model.existFrame(frame.link):
        raise RobotError(f"{field}: the robot's model has no frame {frame.link!r}")
    link_id = model.getFrameId(frame.link)
    link = model.frames[link_id]
    placement = link.placement * pin.SE3(np.eye(3), np.asarray(frame.offset, dtype=float))
    return int(model.addFrame(pin.Frame(name, link.parentJoint, link_id, placement, pin.FrameType.OP_FRAME)))


def _columns(indices: tuple[int, ...], offset: int) -> slice | np.ndarray:
    """``indices + offset`` as a slice when they follow each other, else as an index array."""
    first = indices[0] + offset
    if list(indices) == list(range(indices[0], indices[0] + len(indices))):
        return slice(first, first + len(indices))
    return np.array(indices) + offset
