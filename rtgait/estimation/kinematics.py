"""What the kinematic-inertial estimator needs of a robot's model, as a protocol: the frames of
:class:`~rtgait.interface.body_kinematics.BodyKinematics` for the encoders' joint positions and velocities, the
mounts of the feet's force sensors, and, for a robot without foot force sensors, each leg's dynamics.

A leg's dynamics are what turns its joint torques into the wrench of the ground on its sole
(:mod:`rtgait.estimation.torque_wrenches`): the sole frame's Jacobian with respect to the leg's joints and the torques
those joints need to move the leg as it moves, the sole free (inverse dynamics). Implemented with Pinocchio by
:class:`rtgait.robot.kinematics.PinocchioKinematics`; the estimator itself imports no robot-model library.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from rtgait.interface.body_kinematics import BodyKinematics, ForceSensorMount

__all__ = ["RobotKinematics"]


@runtime_checkable
class RobotKinematics(Protocol):
    """A robot's kinematics for an estimator (module docstring).

    Attributes:
        joint_count: how many joints the readings carry (the robot's joint order).
        mass: the robot's mass (kg).
        leg_joints: each leg's joints, left then right, as indices into the joint order, hip to ankle.
        foot_sensors: the left and right feet's force sensor mounts; ``None`` for a robot without them.
    """

    joint_count: int
    mass: float
    leg_joints: tuple[Sequence[int], Sequence[int]]
    foot_sensors: tuple[ForceSensorMount, ForceSensorMount] | None

    def update(self, joint_positions: np.ndarray, joint_velocities: np.ndarray) -> BodyKinematics:
        """The frames for joint positions (rad) and velocities (rad/s), shape ``(joint_count,)`` each, base frame,
        base at rest."""
        ...

    def leg_dynamics(
        self, angular_velocity: tuple[float, float, float], acceleration: tuple[float, ...],
        joint_accelerations: np.ndarray,
    ) -> tuple[Sequence[np.ndarray], np.ndarray]:  # fmt: skip
        """Each leg's dynamics at the configuration and joint velocities of the last :meth:`update`.

        Args:
            angular_velocity: the base's angular velocity (rad/s, base frame).
            acceleration: the base origin's specific force ``a - g`` (m/s^2: ``(0, 0, 9.81)`` upright at rest) then
                the base's angular acceleration (rad/s^2), base frame.
            joint_accelerations: the joints' accelerations (rad/s^2), shape ``(joint_count,)``.

        Returns:
            ``(jacobians, torques)``: the left and right sole frames' Jacobians with respect to their legs' joints,
            shape ``(6, n_leg)`` each, rows ``(linear; angular)`` in the sole frame; and the torques (N m) each leg's
            joints need for that motion with the sole free, gravity included, shape ``(2, n_leg)``, in
            :attr:`leg_joints` order.
        """
        ...
