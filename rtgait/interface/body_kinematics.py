"""What a state estimator asks of a robot's kinematic model: the frames it needs relative to the floating base, for
the joints as the encoders report them, and the fixed placements of the feet's force sensors.

Everything is in the *base frame* (the floating base's own frame, the root of the kinematic tree) with the base held
at rest: positions from the joint positions, velocities from the joint velocities alone (``J(q) dq``). A robot
model fills these (:class:`rtgait.robot.kinematics.PinocchioKinematics`); the estimator
(:mod:`rtgait.estimation.kinematic_inertial`) places them in the world. Rotations are row-major 3x3 matrices as
tuples of nine floats, ``R[r][c] = m[3 r + c]``, mapping the frame's coordinates to the base's. SI units.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["BodyKinematics", "ForceSensorMount", "FrameMotion"]


class FrameMotion(NamedTuple):
    """A frame of the robot relative to its base (base frame, base at rest).

    Attributes:
        position: the frame's origin (m).
        rotation: its orientation, row-major 3x3 (the frame's axes as columns).
        velocity: its origin's velocity from the joints' velocities (m/s).
        angular_velocity: its angular velocity from the joints' velocities (rad/s).
    """

    position: tuple[float, float, float]
    rotation: tuple[float, ...]
    velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]


class BodyKinematics(NamedTuple):
    """The frames a kinematic-inertial estimator reads at one tick (base frame, base at rest).

    Attributes:
        com: the centre of mass (m).
        com_velocity: its velocity from the joints' velocities (m/s).
        left_sole, right_sole: the sole frames (x forward, y left, z out of the sole).
        imu: the IMU's frame.
    """

    com: tuple[float, float, float]
    com_velocity: tuple[float, float, float]
    left_sole: FrameMotion
    right_sole: FrameMotion
    imu: FrameMotion


class ForceSensorMount(NamedTuple):
    """Where a foot's 6-axis force sensor sits, in that foot's sole frame, and what it carries below it.

    Attributes:
        position: the sensor frame's origin (m).
        rotation: the sensor frame's orientation, row-major 3x3 (its axes in the sole frame).
        mass: the mass between the sensor and the ground (kg), whose weight the sensor carries besides the ground's
            force (0 for a sensor at the sole).
        com: that mass's centre (m), in the sole frame.
    """

    position: tuple[float, float, float]
    rotation: tuple[float, ...]
    mass: float
    com: tuple[float, float, float]
