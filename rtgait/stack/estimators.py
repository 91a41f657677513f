"""The estimator a stack runs, by name: ``"truth"`` (the simulator's ground truth, for comparison) or
``"estimated"`` (the kinematic-inertial estimator on the robot's own sensors, with the robot's kinematics and the
sensors of its description's ``[sensors]``).

The kinematic-inertial estimator's kinematics are wrapped so that each tick's result stays readable
(:class:`SharedKinematics`): the feed-forward at the sensed state places the robot from the same encoder readings, and
takes the soles' placements and velocities relative to the base from there rather than running the kinematics again
(:mod:`rtgait.stack.measured_motion`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES, StateSource, check_state
from rtgait.estimation.ground_truth import GroundTruthEstimator
from rtgait.estimation.kinematic_inertial import KinematicInertialEstimator
from rtgait.estimation.torque_landing import torque_landing_force
from rtgait.robot.kinematics import PinocchioKinematics

if TYPE_CHECKING:
    import numpy as np

    from rtgait.estimation.anchors import Pose
    from rtgait.estimation.estimator import Estimator
    from rtgait.estimation.joint_friction import JointFriction
    from rtgait.interface.body_kinematics import BodyKinematics
    from rtgait.interface.sensor_spec import SensorSpec
    from rtgait.robot.model import RobotModel

__all__ = [
    "DEFAULT_STATE", "STATE_SOURCES", "SharedKinematics", "StateSource", "check_state", "kinematic_inertial_estimator",
    "make_estimator", "shared_kinematics",
]  # fmt: skip


class SharedKinematics:
    """A robot's kinematics for the estimator (:class:`~rtgait.robot.kinematics.PinocchioKinematics`) that keeps
    the last :meth:`update`'s result in :attr:`last`; everything else is the wrapped kinematics'.

    Args:
        kinematics: the wrapped kinematics.
    """

    def __init__(self, kinematics: PinocchioKinematics) -> None:
        self.wrapped = kinematics
        self._update = kinematics.update
        self.last: BodyKinematics | None = None
        """The last :meth:`update`'s frames (``None`` before the first)."""

    def update(self, joint_positions: np.ndarray, joint_velocities: np.ndarray) -> BodyKinematics:
        """The wrapped kinematics' frames for the joints' positions (rad) and velocities (rad/s), kept in
        :attr:`last`."""
        self.last = body = self._update(joint_positions, joint_velocities)
        return body

    def __getattr__(self, name: str) -> object:
        if name == "wrapped":  # not set yet (a copy being built): no recursion
            raise AttributeError(name)
        return getattr(self.wrapped, name)


def shared_kinematics(estimator: Estimator) -> SharedKinematics | None:
    """``estimator``'s kinematics when they keep their last result (:func:`kinematic_inertial_estimator`'s), else
    ``None``."""
    kinematics = getattr(estimator, "kinematics", None)
    return kinematics if isinstance(kinematics, SharedKinematics) else None


def kinematic_inertial_estimator(
    robot: RobotModel,
    omega: float,
    *,
    gravity: float = 9.81,
    start_feet: tuple[Pose, Pose] | None = None,
    sensors: SensorSpec | None = None,
    **options: object,
) -> KinematicInertialEstimator:
    """The kinematic-inertial estimator of ``robot`` (:mod:`rtgait.estimation.kinematic_inertial`).

    Args:
        robot: the loaded robot (its reduced model's joints are the readings').
        omega: the planner's pendulum frequency (1/s), for the DCM.
        gravity: the gravity's magnitude (m/s^2).
        start_feet: the standing soles' world poses ``(x, y, z, yaw)`` that fix the world frame.
        sensors: where the IMU and the feet's force sensors are, and whose heading the estimator takes (the IMU's
            ``yaw_source``); default the description's ``[sensors]``.
        options: further settings of :class:`~rtgait.estimation.kinematic_inertial.KinematicInertialEstimator`.

    Raises:
        ValueError: the robot has no IMU.
    """
    spec = robot.description.sensors if sensors is None else sensors
    if spec.imu is None:
        raise ValueError(f"{robot.name} has no IMU in its [sensors]: the kinematic-inertial estimator needs one")
    feet = None if spec.feet is None else (spec.feet.left, spec.feet.right)
    kinematics = SharedKinematics(PinocchioKinematics(robot, spec.imu.frame, feet))
    settings = {
        "gravity": gravity, "start_feet": start_feet, "sole": robot.description.sole, "yaw": spec.imu.yaw_source,
        **options,
    }  # fmt: skip
    return KinematicInertialEstimator(kinematics, omega, **settings)  # type: ignore[arg-type]


def make_estimator(
    state: StateSource, robot: RobotModel, omega: float, *, gravity: float = 9.81,
    start_feet: tuple[Pose, Pose] | None = None, joint_friction: JointFriction | None = None,
    sensor_noise: float = 1.0,
) -> Estimator:  # fmt: skip
    """The estimator of ``state`` for ``robot``: ``"truth"``, the ground-truth estimator (the thresholds scaled to
    the robot's weight); ``"estimated"``, :func:`kinematic_inertial_estimator` from the standing feet
    ``start_feet``. ``omega`` (1/s) and ``gravity`` (m/s^2) are the planner's. ``sensor_noise``: the factor on the
    described noise the sensors read with; beyond 1, a robot without foot force sensors takes its landings at a
    threshold scaled with it (:mod:`rtgait.estimation.torque_landing`)."""
    check_state(state)
    if state == "truth":
        return GroundTruthEstimator(omega, robot.mass * gravity)
    options: dict[str, object] = {}
    if sensor_noise > 1.0 and robot.description.sensors.feet is None:  # at <= 1, the estimator's own default
        options["landing_force"] = torque_landing_force(robot.mass * gravity, sensor_noise)
    return kinematic_inertial_estimator(
        robot, omega, gravity=gravity, start_feet=start_feet, joint_friction=joint_friction, **options
    )
