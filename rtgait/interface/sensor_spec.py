"""Which sensors a robot has, where they are and how good they are: the robot description's ``[sensors]`` table.

Pure data (no simulator): an estimator reads the frames and noise levels from it, the simulator
(:mod:`rtgait.sim.sensors`) reproduces the sensors with it. Frames are URDF links or joints with an offset in that
frame (m); the sensor frame has the link's orientation.

Noise follows the usual continuous-time model of inertial sensors (IEEE Std 952, Kalibr's IMU noise model): a
white noise of density ``N`` sampled every ``dt`` has the standard deviation ``sigma = N / sqrt(dt)``, and a bias
that walks with density ``N_b`` moves by ``N_b sqrt(dt)`` (standard deviation) per sample. Units: rad/s/sqrt(Hz)
for the gyroscope's density, rad/s^2/sqrt(Hz) for its bias walk; m/s^2/sqrt(Hz) and m/s^3/sqrt(Hz) for the
accelerometer's. An initial bias or offset is drawn once per run, normal with the given standard deviation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

__all__ = ["YAW_SOURCES", "FootSensorSpec", "ImuSpec", "SensorFrame", "SensorSpec", "YawSource"]

YawSource = Literal["feet", "imu"]
YAW_SOURCES: tuple[YawSource, ...] = ("feet", "imu")
"""Where an estimator takes the base's heading from (:attr:`ImuSpec.yaw_source`)."""


@dataclass(frozen=True)
class SensorFrame:
    """Where a sensor is: a URDF link or joint and an offset (m) in its frame; the sensor's axes are the link's."""

    link: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class ImuSpec:
    """An inertial measurement unit with its own attitude filter.

    Attributes:
        frame: the IMU's frame (its axes are the measurement axes).
        gyro_noise_density: angular random walk (rad/s/sqrt(Hz)).
        gyro_bias: standard deviation of the initial gyro bias, per axis (rad/s).
        gyro_bias_walk: density of the gyro bias random walk (rad/s^2/sqrt(Hz)).
        accel_noise_density: velocity random walk (m/s^2/sqrt(Hz)).
        accel_bias: standard deviation of the initial accelerometer bias, per axis (m/s^2).
        accel_bias_walk: density of the accelerometer bias random walk (m/s^3/sqrt(Hz)).
        orientation_noise: standard deviation of the filter's roll and pitch error, white (rad).
        yaw_drift: standard deviation of the rate at which the filter's yaw drifts (rad/s), drawn once per run: the
            filter sees gravity, which fixes roll and pitch, but nothing fixes yaw.
        yaw_source: where an estimator takes the base's heading from: ``"feet"``, the feet in contact, which hold
            their heading while they stand; ``"imu"``, this filter's yaw, for an IMU whose yaw drifts less than the
            robot's soles turn on the floor.
    """

    frame: SensorFrame
    gyro_noise_density: float = 0.0
    gyro_bias: float = 0.0
    gyro_bias_walk: float = 0.0
    accel_noise_density: float = 0.0
    accel_bias: float = 0.0
    accel_bias_walk: float = 0.0
    orientation_noise: float = 0.0
    yaw_drift: float = 0.0
    yaw_source: YawSource = "feet"


@dataclass(frozen=True)
class FootSensorSpec:
    """The two feet's 6-axis force/torque sensors (one model of sensor for both).

    Attributes:
        left, right: the sensor frames.
        force_noise: standard deviation of each force component's white noise (N).
        torque_noise: standard deviation of each torque component's white noise (N m).
        force_offset: standard deviation of each force component's offset, drawn once per run (N).
        torque_offset: standard deviation of each torque component's offset, drawn once per run (N m).
    """

    left: SensorFrame
    right: SensorFrame
    force_noise: float = 0.0
    torque_noise: float = 0.0
    force_offset: float = 0.0
    torque_offset: float = 0.0


@dataclass(frozen=True)
class SensorSpec:
    """A robot's sensors (module docstring); the default is perfect encoders and joint torques, nothing else.

    Attributes:
        imu: the base IMU, or ``None``.
        feet: the feet's force/torque sensors, or ``None`` (the G1 has none).
        encoder_resolution: the joint encoders' step (rad); 0: continuous.
        encoder_noise: standard deviation of the joint positions' white noise (rad), before quantization.
        velocity_noise: standard deviation of the joint velocities' white noise (rad/s).
        joint_torques: whether the drives report joint torques (measured or estimated).
        torque_noise: standard deviation of the joint torques' white noise (N m).
        latency: whole control periods between the sensors' sampling and the controller's reading.
    """

    imu: ImuSpec | None = None
    feet: FootSensorSpec | None = None
    encoder_resolution: float = 0.0
    encoder_noise: float = 0.0
    velocity_noise: float = 0.0
    joint_torques: bool = True
    torque_noise: float = 0.0
    latency: int = 0
