"""The robot's sensors in its MuJoCo model: a site per sensor frame and MuJoCo's own sensors on them.

MuJoCo computes what each sensor measures (:mod:`rtgait.sim.sensors` adds the noise, which MuJoCo does not):

* encoders, drives: ``jointpos``, ``jointvel`` and ``jointactuatorfrc`` of each moving joint, in the robot's joint
  order (the torque the joint's servo applies);
* IMU (a site at the description's IMU frame): ``framequat`` (its orientation in the world, ``(w, x, y, z)``),
  ``gyro`` (angular velocity in the site frame), ``accelerometer`` (the specific force ``R^T (a - g)`` in the site
  frame at this instant: MuJoCo's accelerations include the gravity field, so a body at rest reads ``+g`` upward)
  and ``framelinvel`` (the site's velocity in the world frame, from which :mod:`rtgait.sim.sensors` makes the
  accelerometer's reading, the mean specific force over the sample period);
* feet (a site at each force sensor's frame): ``force`` and ``torque``, the interaction wrench between the site's
  body and its parent body, in the site frame, about the site. MuJoCo's sign is that of the force the parent exerts
  on the child body's subtree: on a foot standing on the floor it points down. :mod:`rtgait.sim.sensors` negates it
  into the force the foot exerts on the leg above the sensor, the convention of
  :class:`~rtgait.interface.readings.Wrench` (``fz`` about the weight the foot carries, less the foot's own).

The sensors are laid out in ``sensordata`` in that order, so one slice reads them all (:class:`SensorLayout`).
Sites and sensors are massless and feed nothing back: the physics is the same with or without them.

A frame is placed on the body of its parent joint in the robot's reduced model (joints outside the walking ones are
locked, and MuJoCo fuses their bodies into their parents the same way).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import pinocchio as pin

from rtgait.robot.description import RobotError

if TYPE_CHECKING:
    from rtgait.interface.sensor_spec import SensorFrame
    from rtgait.robot.model import RobotModel

__all__ = ["FOOT_SITES", "IMU_SITE", "IMU_SIZE", "SensorLayout", "add_sensors"]

IMU_SITE = "imu"
"""Name of the IMU's site."""
IMU_SIZE = 13
"""Numbers of the IMU in the layout: quaternion (4), gyro (3), accelerometer (3), the site's world velocity (3)."""
FOOT_SITES = {"left": "left_foot_sensor", "right": "right_foot_sensor"}
"""Names of the feet's force sensor sites."""
_PREFIX = "rtgait_"  # of every sensor's name


def _site_on_frame(spec: mujoco.MjSpec, robot: RobotModel, root: mujoco.MjsBody, name: str, frame: SensorFrame) -> None:
    """A site ``name`` at ``frame`` (its link's orientation, the offset in it), on the body that carries it."""
    model = robot.model
    if not model.existFrame(frame.link):
        raise RobotError(f"sensor frame {frame.link!r} is not in {robot.name}'s model")
    placed = model.frames[model.getFrameId(frame.link)]
    joint = model.names[placed.parentJoint]
    body = root if placed.parentJoint == 1 else spec.joint(joint).parent
    rotation = placed.placement.rotation
    xyzw = pin.Quaternion(rotation).coeffs()
    body.add_site(
        name=name,
        pos=placed.placement.translation + rotation @ np.asarray(frame.offset, dtype=float),
        quat=[xyzw[3], xyzw[0], xyzw[1], xyzw[2]],
        size=[0.01, 0.01, 0.01],
        group=4,
    )


def add_sensors(spec: mujoco.MjSpec, robot: RobotModel, root: mujoco.MjsBody) -> None:
    """Add the sites and sensors of ``robot``'s ``[sensors]`` (module docstring) to ``spec``; ``root``: its root
    body."""
    sensors = robot.description.sensors
    site, joint = mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_JOINT
    kinds = (("pos", mujoco.mjtSensor.mjSENS_JOINTPOS), ("vel", mujoco.mjtSensor.mjSENS_JOINTVEL),
             ("tau", mujoco.mjtSensor.mjSENS_JOINTACTFRC))  # fmt: skip
    for suffix, kind in kinds:
        for name in robot.joint_names:
            spec.add_sensor(name=f"{_PREFIX}{suffix}_{name}", type=kind, objtype=joint, objname=name)
    if sensors.imu is not None:
        _site_on_frame(spec, robot, root, IMU_SITE, sensors.imu.frame)
        for suffix, kind in (("quat", mujoco.mjtSensor.mjSENS_FRAMEQUAT), ("gyro", mujoco.mjtSensor.mjSENS_GYRO),
                             ("accel", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
                             ("vel", mujoco.mjtSensor.mjSENS_FRAMELINVEL)):  # fmt: skip
            spec.add_sensor(name=f"{_PREFIX}imu_{suffix}", type=kind, objtype=site, objname=IMU_SITE)
    if sensors.feet is not None:
        for side, frame in (("left", sensors.feet.left), ("right", sensors.feet.right)):
            _site_on_frame(spec, robot, root, FOOT_SITES[side], frame)
            for suffix, kind in (("force", mujoco.mjtSensor.mjSENS_FORCE), ("torque", mujoco.mjtSensor.mjSENS_TORQUE)):
                spec.add_sensor(name=f"{_PREFIX}{side}_{suffix}", type=kind, objtype=site, objname=FOOT_SITES[side])


@dataclass(frozen=True)
class SensorLayout:
    """Where the robot's sensors are in ``data.sensordata`` (module docstring): one slice ``[start, stop)``, in it
    the joints' positions, velocities and torques (``n`` each), then the IMU's 13 numbers (quaternion, gyro,
    accelerometer, the site's velocity in the world) if it has one, then each foot's 6 (force, torque) if it has
    force sensors."""

    start: int
    joints: int
    imu: bool
    feet: bool

    @property
    def size(self) -> int:
        """Numbers in the slice."""
        return 3 * self.joints + (IMU_SIZE if self.imu else 0) + (12 if self.feet else 0)

    @property
    def stop(self) -> int:
        return self.start + self.size

    @classmethod
    def of(cls, model: mujoco.MjModel, robot: RobotModel) -> SensorLayout:
        """The layout of ``model`` built with :func:`add_sensors` for ``robot`` (checked, not assumed)."""
        sensors = robot.description.sensors
        first = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, f"{_PREFIX}pos_{robot.joint_names[0]}")
        if first < 0:  # pragma: no cover - add_sensors adds it
            raise RobotError(f"the MuJoCo model of {robot.name} has no joint sensors")
        layout = cls(int(model.sensor_adr[first]), len(robot.joint_names), sensors.imu is not None,
                     sensors.feet is not None)  # fmt: skip
        last = first + 3 * layout.joints + (4 if layout.imu else 0) + (4 if layout.feet else 0) - 1
        if last >= model.nsensor or model.sensor_adr[last] + model.sensor_dim[last] != layout.stop:  # pragma: no cover
            raise RobotError(f"the sensors of {robot.name}'s MuJoCo model are not laid out as added")
        return layout
