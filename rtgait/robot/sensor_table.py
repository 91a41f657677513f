"""The ``[sensors]`` table of a robot description, read into a :class:`~rtgait.interface.sensor_spec.SensorSpec`.

Keys (all optional; units as :mod:`rtgait.interface.sensor_spec`):

* ``encoder_resolution`` (rad), ``encoder_noise`` (rad), ``velocity_noise`` (rad/s), ``joint_torques`` (bool),
  ``torque_noise`` (N m), ``latency`` (control periods, an integer >= 0);
* ``[sensors.imu]``: ``frame`` (a URDF link or joint), ``offset`` ([x, y, z] in that frame, m), and the noise keys
  of :class:`~rtgait.interface.sensor_spec.ImuSpec`, and ``yaw_source`` (``"feet"``, default, or ``"imu"``);
* ``[sensors.feet]``: ``left_frame``, ``right_frame``, ``left_offset``, ``right_offset`` and the noise keys of
  :class:`~rtgait.interface.sensor_spec.FootSensorSpec`. No table: the robot has no foot force sensor.
"""

from __future__ import annotations

from typing import Any

from rtgait.interface.sensor_spec import YAW_SOURCES, FootSensorSpec, ImuSpec, SensorFrame, SensorSpec
from rtgait.robot.description_checks import FILES, RobotError, UrdfNames
from rtgait.scenario.tomlfile import is_finite_number

__all__ = ["parse_sensors"]

_IMU_NOISE = {"gyro_noise_density": "rad/s/sqrt(Hz)", "gyro_bias": "rad/s", "gyro_bias_walk": "rad/s^2/sqrt(Hz)",
              "accel_noise_density": "m/s^2/sqrt(Hz)", "accel_bias": "m/s^2", "accel_bias_walk": "m/s^3/sqrt(Hz)",
              "orientation_noise": "rad", "yaw_drift": "rad/s"}  # fmt: skip
_FOOT_NOISE = {"force_noise": "N", "torque_noise": "N m", "force_offset": "N", "torque_offset": "N m"}
_TABLE_NOISE = {"encoder_resolution": "rad", "encoder_noise": "rad", "velocity_noise": "rad/s", "torque_noise": "N m"}


def parse_sensors(raw: Any, names: UrdfNames) -> SensorSpec:
    """The ``[sensors]`` table (module docstring); frames are checked against the URDF's ``names``."""
    table = FILES.table(raw, "sensors")
    FILES.check_keys(table, "sensors", (), (*_TABLE_NOISE, "joint_torques", "latency", "imu", "feet"))
    values: dict[str, Any] = _numbers(table, "sensors", _TABLE_NOISE)
    if "joint_torques" in table:
        if not isinstance(table["joint_torques"], bool):
            raise RobotError(f"sensors.joint_torques must be true or false, got {table['joint_torques']!r}")
        values["joint_torques"] = table["joint_torques"]
    if "latency" in table:
        latency = table["latency"]
        if not (isinstance(latency, int) and not isinstance(latency, bool) and 0 <= latency <= 1000):
            raise RobotError(f"sensors.latency must be a whole number of control periods in [0, 1000], got {latency!r}")
        values["latency"] = latency
    if "imu" in table:
        imu = FILES.table(table["imu"], "sensors.imu")
        FILES.check_keys(imu, "sensors.imu", ("frame",), ("offset", "yaw_source", *_IMU_NOISE))
        frame = _frame(imu, "frame", "offset", "sensors.imu", names)
        yaw_source = imu.get("yaw_source", "feet")
        if yaw_source not in YAW_SOURCES:
            raise RobotError(f"sensors.imu.yaw_source must be one of {', '.join(YAW_SOURCES)}, got {yaw_source!r}")
        values["imu"] = ImuSpec(frame, **_numbers(imu, "sensors.imu", _IMU_NOISE), yaw_source=yaw_source)
    if "feet" in table:
        feet = FILES.table(table["feet"], "sensors.feet")
        FILES.check_keys(
            feet, "sensors.feet", ("left_frame", "right_frame"), ("left_offset", "right_offset", *_FOOT_NOISE)
        )
        left = _frame(feet, "left_frame", "left_offset", "sensors.feet", names)
        right = _frame(feet, "right_frame", "right_offset", "sensors.feet", names)
        if left.link == right.link:
            raise RobotError("sensors.feet.left_frame and sensors.feet.right_frame must be different frames")
        values["feet"] = FootSensorSpec(left, right, **_numbers(feet, "sensors.feet", _FOOT_NOISE))
    return SensorSpec(**values)


def _numbers(table: dict[str, Any], where: str, keys: dict[str, str]) -> dict[str, float]:
    """The keys of ``keys`` that ``table`` has, each a number >= 0 in the unit ``keys`` gives."""
    return {
        key: FILES.number(table[key], f"{where}.{key}", rule=">= 0", unit=unit)
        for key, unit in keys.items()
        if key in table
    }


def _frame(table: dict[str, Any], link_key: str, offset_key: str, where: str, names: UrdfNames) -> SensorFrame:
    """The sensor frame named by ``table[link_key]`` with the offset ``table[offset_key]`` (default 0)."""
    link = FILES.string(table, link_key, where, non_empty=True)
    if link not in names.frames:
        raise RobotError(f"{where}.{link_key}: the URDF has no link or joint named {link!r}")
    offset = table.get(offset_key, [0.0, 0.0, 0.0])
    if not (isinstance(offset, list) and len(offset) == 3 and all(is_finite_number(v) for v in offset)):
        raise RobotError(f"{where}.{offset_key} must be three finite numbers [x, y, z] in m, got {offset!r}")
    return SensorFrame(link, (float(offset[0]), float(offset[1]), float(offset[2])))
