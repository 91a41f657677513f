"""What a robot's sensors report at one control tick: encoders, IMU, force/torque sensors, joint torques.

Fields follow the low-level interfaces of real humanoids (Unitree's ``LowState``, ros2_control's state interfaces,
Talos's ankle force/torque sensors): joint positions and velocities in the order of the robot's joint names; the
IMU's orientation as its own filter reports it, with its angular velocity and linear acceleration in the IMU frame;
a 6-axis wrench per force sensor, in that sensor's frame. A sensor the robot does not have is ``None``. SI units:
rad, rad/s, N m, m/s^2, N. Where the sensors are and how noisy: the robot description's ``[sensors]``
(:mod:`rtgait.interface.sensor_spec`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["ImuReading", "SensorReadings", "Wrench"]


class Wrench(NamedTuple):
    """A 6-axis force/torque reading in its sensor's frame.

    Sign: the wrench the environment exerts on the robot's body through the sensor. For a foot's sensor between the
    ankle and the sole, that is the wrench the part of the foot below the sensor (which the floor pushes) exerts on
    the leg above it: standing still with the sensor's z axis up, ``fz`` is the weight the foot carries less the
    weight of the foot below the sensor, positive.

    Attributes:
        force: ``(fx, fy, fz)`` (N), the force the environment exerts on the body through the sensor.
        torque: ``(tx, ty, tz)`` (N m), its moment about the sensor frame's origin.
    """

    force: tuple[float, float, float]
    torque: tuple[float, float, float]


class ImuReading(NamedTuple):
    """An inertial measurement unit's reading.

    Attributes:
        orientation: the IMU frame's orientation in the world as its filter estimates it, a unit quaternion
            ``(w, x, y, z)``.
        angular_velocity: ``(wx, wy, wz)`` in the IMU frame (rad/s).
        linear_acceleration: specific force ``(ax, ay, az)`` in the IMU frame (m/s^2): ``R^T (a - g)``, so about
            ``(0, 0, 9.81)`` at rest with the IMU's z axis up; its mean over the sample period that ends at the
            reading (an IMU's anti-aliasing filter or velocity increment), in the IMU frame at the reading.
    """

    orientation: tuple[float, float, float, float]
    angular_velocity: tuple[float, float, float]
    linear_acceleration: tuple[float, float, float]


class SensorReadings(NamedTuple):
    """Everything the robot's sensors report at one tick (module docstring).

    Attributes:
        t: when the sensors sampled (s): with a latency of ``L`` control periods, ``L`` periods before the tick
            that reads them.
        joint_positions: encoder positions, one per joint in the robot's joint order (rad), shape ``(n,)``.
        joint_velocities: joint velocities (rad/s), shape ``(n,)``.
        joint_torques: measured or estimated joint torques (N m), shape ``(n,)``; ``None`` where the drives do not
            report them.
        imu: the base IMU; ``None`` for a robot without one.
        left_foot, right_foot: the feet's force/torque sensors, in the sensor frames; ``None`` where the robot has
            none (the G1 has no foot force sensor).
    """

    t: float
    joint_positions: np.ndarray
    joint_velocities: np.ndarray
    joint_torques: np.ndarray | None = None
    imu: ImuReading | None = None
    left_foot: Wrench | None = None
    right_foot: Wrench | None = None
