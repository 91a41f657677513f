"""The kinematic-inertial estimator against the exact state of a rigid robot whose feet stand still: a base placed
and moved in the world, the readings an ideal IMU, feet force sensors and leg kinematics would give of it."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from rtgait.estimation.estimator import Estimator
from rtgait.estimation.kinematic_inertial import KinematicInertialEstimator
from rtgait.interface.body_kinematics import BodyKinematics, ForceSensorMount, FrameMotion
from rtgait.interface.readings import ImuReading, SensorReadings, Wrench

G = 9.81
MASS = 60.0
W = math.sqrt(G / 0.8)
DT = 0.001
I3 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
SOLE_SENSOR = ForceSensorMount((0.0, 0.0, 0.0), I3, 0.0, (0.0, 0.0, 0.0))
COM_IN_BASE = np.array([0.02, -0.01, 0.1])


def rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def quat(r: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion ``(w, x, y, z)`` of a rotation matrix (its trace is positive here)."""
    w = 0.5 * math.sqrt(1.0 + np.trace(r))
    return (w, (r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w), (r[1, 0] - r[0, 1]) / (4 * w))


class RigidRobot:
    """A robot whose joints hold still while its base moves: the soles stand at fixed world poses, the COM is fixed
    in the base. :meth:`readings` gives what its sensors read for a base pose, velocity and acceleration; as
    :class:`~rtgait.estimation.kinematics.RobotKinematics` it gives the leg kinematics of the same instant."""

    joint_count = 12
    mass = MASS
    leg_joints = (tuple(range(6)), tuple(range(6, 12)))
    foot_sensors = (SOLE_SENSOR, SOLE_SENSOR)

    def __init__(self, feet: list[tuple[float, float, float, float]]) -> None:
        self.feet = [(np.array(f[:3]), rot(0.0, 0.0, f[3])) for f in feet]
        self.state: BodyKinematics | None = None

    def place(self, p: np.ndarray, r: np.ndarray, v: np.ndarray, w: np.ndarray) -> None:
        """The base at ``p`` with rotation ``r``, moving at ``v`` (world) and turning at ``w`` (world)."""
        w_base, v_base = r.T @ w, r.T @ v
        soles = []
        for s, rs in self.feet:
            position = r.T @ (s - p)
            # A still sole seen from a moving base: d/dt R^T (s - p) = -w_B x p_i - R^T v.
            velocity = -np.cross(w_base, position) - v_base
            soles.append(FrameMotion(tuple(position), tuple((r.T @ rs).ravel()), tuple(velocity), tuple(-w_base)))
        imu = FrameMotion((0.0, 0.0, 0.0), I3, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        self.state = BodyKinematics(tuple(COM_IN_BASE), (0.0, 0.0, 0.0), soles[0], soles[1], imu)

    def update(self, joint_positions: np.ndarray, joint_velocities: np.ndarray) -> BodyKinematics:
        assert self.state is not None
        return self.state

    def leg_dynamics(self, angular_velocity, acceleration, joint_accelerations):  # pragma: no cover - sensors are read
        raise AssertionError("a robot with foot force sensors")

    def readings(
        self, t: float, p: np.ndarray, r: np.ndarray, v: np.ndarray, a: np.ndarray, w: np.ndarray,
        loads: tuple[float, float], imu_orientation: np.ndarray | None = None,
    ) -> SensorReadings:  # fmt: skip
        """The sensors' readings of the base at ``p``, ``r``, moving at ``v``, accelerating at ``a``, turning at ``w``
        (world), the feet carrying ``loads`` (N, vertical, at their sole origins)."""
        self.place(p, r, v, w)
        specific = r.T @ (a + np.array([0.0, 0.0, G]))
        imu = ImuReading(quat(r if imu_orientation is None else imu_orientation), tuple(r.T @ w), tuple(specific))
        wrenches = [
            Wrench(tuple(rs.T @ np.array([0.0, 0.0, f])), (0.0, 0.0, 0.0))
            for (_, rs), f in zip(self.feet, loads, strict=True)
        ]
        zeros = np.zeros(12)
        return SensorReadings(t, zeros, zeros, None, imu, wrenches[0], wrenches[1])


FEET = [(0.1, 0.12, 0.0, 0.2), (0.12, -0.1, 0.0, 0.15)]


def estimator(robot: RigidRobot, **options) -> KinematicInertialEstimator:
    return KinematicInertialEstimator(robot, W, start_feet=tuple(FEET), **options)


def test_it_is_an_estimator_of_the_robots_readings_only():
    e = estimator(RigidRobot(FEET))
    assert isinstance(e, Estimator) and not e.reads_truth


def test_a_tilted_turned_robot_standing_still_is_where_it_is():
    robot = RigidRobot(FEET)
    e = estimator(robot)
    p, r = np.array([0.1, 0.01, 0.75]), rot(0.05, -0.08, 0.17)
    loads = (400.0, 188.6)
    zero = np.zeros(3)
    for k in range(3):
        m = e.update(robot.readings(k * DT, p, r, zero, zero, zero, loads))
    com = p + r @ COM_IN_BASE
    np.testing.assert_allclose(m.com, com, atol=1e-12)
    np.testing.assert_allclose(m.com_vel, zero, atol=1e-12)
    np.testing.assert_allclose(m.dcm, com[:2], atol=1e-12)
    for foot, (x, y, z, yaw) in zip((m.left, m.right), FEET, strict=True):
        np.testing.assert_allclose(foot.pose, (x, y, z, yaw), atol=1e-12)
        assert foot.loaded and foot.tilt == pytest.approx(0.0, abs=1e-12)
    # Vertical forces at the sole origins: the ZMP is their force-weighted mean.
    soles = np.array([f[:2] for f in FEET])
    np.testing.assert_allclose(m.zmp, np.average(soles, axis=0, weights=loads), atol=1e-12)
    assert m.normal_force == pytest.approx(sum(loads))


def test_a_base_moving_over_still_feet_has_its_velocity_without_lag():
    # The base accelerates and turns while the feet stand: the kinematic velocity and the integrated accelerometer
    # agree, so the blend is the velocity itself from the first tick on.
    robot = RigidRobot(FEET)
    e = estimator(robot)
    p0, v0, a = np.array([0.1, 0.0, 0.75]), np.array([0.05, -0.02, 0.01]), np.array([0.3, 0.2, -0.1])
    w = np.array([0.0, 0.0, 0.4])
    loads = (300.0, 288.6)
    for k in range(200):
        t = k * DT
        r = rot(0.02, -0.03, 0.1 + w[2] * t)
        p, v = p0 + v0 * t + 0.5 * a * t * t, v0 + a * t
        m = e.update(robot.readings(t, p, r, v, a, w, loads))
        # The COM's velocity: the base's plus the turn of the COM about the base.
        expected = v + np.cross(w, r @ COM_IN_BASE)
        np.testing.assert_allclose(m.com_vel, expected, atol=1e-9)  # a constant acceleration is its own mean
        np.testing.assert_allclose(m.com, p + r @ COM_IN_BASE, atol=1e-9)


def test_an_accelerometer_bias_costs_bias_times_the_filter_time_constant():
    robot = RigidRobot(FEET)
    cutoff = 3.5
    e = estimator(robot, velocity_cutoff=cutoff)
    p, r, zero = np.array([0.1, 0.0, 0.75]), rot(0.0, 0.0, 0.2), np.zeros(3)
    bias = 0.1  # m/s^2 along the world's x, from a base that stands still
    for k in range(2000):
        readings = robot.readings(k * DT, p, r, zero, np.array([bias, 0.0, 0.0]), zero, (300.0, 288.6))
        m = e.update(readings)
    tau = 1.0 / (2.0 * math.pi * cutoff)
    assert m.com_vel[0] == pytest.approx(bias * tau, rel=0.02)


@pytest.mark.parametrize("yaw", ["feet", "imu"])
def test_the_imu_filters_yaw_drift_stays_out_of_a_feet_anchored_estimate(yaw):
    robot = RigidRobot(FEET)
    e = estimator(robot, yaw=yaw)
    p, r, zero = np.array([0.1, 0.0, 0.75]), rot(0.01, 0.02, 0.18), np.zeros(3)
    drift = 0.01  # rad/s of the IMU filter's heading, the robot standing still
    for k in range(1000):
        t = k * DT
        m = e.update(robot.readings(t, p, r, zero, zero, zero, (300.0, 288.6), rot(0.0, 0.0, drift * t) @ r))
    error = math.remainder(m.left.pose[3] - FEET[0][3], math.tau)
    if yaw == "feet":
        assert abs(error) < 1e-9
        np.testing.assert_allclose(m.com, p + r @ COM_IN_BASE, atol=1e-9)
    else:
        # The gyro sees no turn: the attitude filter follows the drifting heading a time constant late.
        assert error == pytest.approx(drift * (t - 0.2), rel=0.01)


def test_a_foot_lands_after_a_swing_and_not_after_a_scuff():
    robot = RigidRobot(FEET)
    e = estimator(robot)
    p, r, zero = np.array([0.1, 0.0, 0.75]), rot(0.0, 0.0, 0.2), np.zeros(3)
    weight = MASS * G
    landings = []

    def run(t0: float, t1: float, right: float) -> None:
        for k in range(round(t0 / DT), round(t1 / DT)):
            m = e.update(robot.readings(k * DT, p, r, zero, zero, zero, (weight - right, right)))
            landings.extend(m.landings)

    run(0.0, 0.1, 0.5 * weight)
    run(0.1, 0.12, 0.0)  # a scuff: 20 ms in the air
    run(0.12, 0.2, 0.5 * weight)
    assert landings == []
    run(0.2, 0.5, 0.0)  # a swing
    run(0.5, 0.6, 0.5 * weight)
    assert len(landings) == 1
    landing = landings[0]
    assert landing.side == "right" and landing.t == pytest.approx(0.5)
    assert (landing.x, landing.y, landing.yaw) == pytest.approx((FEET[1][0], FEET[1][1], FEET[1][3]), abs=1e-9)


def test_the_anchors_take_a_disagreement_between_the_feet_by_their_loads():
    # The right foot's anchor is placed 10 mm off where the kinematics put it: the base goes by the feet's loads.
    robot = RigidRobot(FEET)
    e = estimator(robot)
    p, r, zero = np.array([0.1, 0.0, 0.75]), rot(0.0, 0.0, 0.0), np.zeros(3)
    e.update(robot.readings(0.0, p, r, zero, zero, zero, (200.0, 200.0)))
    poses = e.anchors.poses
    x, y, z, yaw = poses[1]
    poses[1] = (x + 0.01, y, z, yaw)
    m = e.update(robot.readings(DT, p, r, zero, zero, zero, (300.0, 100.0)))
    assert m.com[0] - (p + COM_IN_BASE)[0] == pytest.approx(0.25 * 0.01, abs=1e-12)
    # The disagreement left after the tick: (1 - w_l^2 - w_r^2) of it.
    gap = e.anchors.poses[1][0] - e.anchors.poses[0][0] - (FEET[1][0] - FEET[0][0])
    assert gap == pytest.approx((1.0 - 0.75**2 - 0.25**2) * 0.01, abs=1e-12)


def test_a_foot_sensor_above_the_sole_with_the_foot_below_it():
    # The sensor 0.1 m above the sole, turned 90 deg about z; 1.5 kg of foot below it, centred 4 cm above the sole.
    from rtgait.estimation.sole_wrenches import sensor_wrench

    turn = rot(0.0, 0.0, math.pi / 2)
    mount = ForceSensorMount((0.0, 0.0, 0.1), tuple(turn.ravel()), 1.5, (0.01, 0.0, 0.04))
    gravity = np.array([0.0, 0.0, -G])  # the sole level
    # The ground pushes 500 N up at (0.03, -0.01) on the sole: the wrench about the sole origin.
    ground_force, point = np.array([0.0, 0.0, 500.0]), np.array([0.03, -0.01, 0.0])
    ground_moment = np.cross(point, ground_force)
    # What the leg receives through the sensor: the ground's wrench plus the foot's weight, about the sensor.
    weight, weight_at = 1.5 * gravity, np.array(mount.com)
    sensor_at = np.array(mount.position)
    force = ground_force + weight
    moment = ground_moment + np.cross(weight_at, weight) - np.cross(sensor_at, force)
    reading = Wrench(tuple(turn.T @ force), tuple(turn.T @ moment))
    out = sensor_wrench(reading, mount, tuple(gravity))
    np.testing.assert_allclose(out, (*ground_force, *ground_moment), atol=1e-9)
    # A foot in the air: the sensor carries its weight alone, the ground nothing.
    hanging_moment = np.cross(weight_at, weight) - np.cross(sensor_at, weight)
    hanging = Wrench(tuple(turn.T @ weight), tuple(turn.T @ hanging_moment))
    np.testing.assert_allclose(sensor_wrench(hanging, mount, tuple(gravity)), np.zeros(6), atol=1e-9)
    # A sensor off by a wrench known in the sole frame, its zero: taken off, the ground's wrench again.
    offset = np.array([1.5, -2.0, 4.0, 0.2, -0.3, 0.1])
    off_reading = Wrench(tuple(turn.T @ (force + offset[:3])), tuple(turn.T @ (moment + offset[3:])))
    zero = tuple(offset + np.concatenate([np.zeros(3), np.cross(sensor_at, offset[:3])]))  # about the sole origin
    out = sensor_wrench(off_reading, mount, tuple(gravity), zero)
    np.testing.assert_allclose(out, (*ground_force, *ground_moment), atol=1e-9)


def test_joint_torques_give_the_sole_wrench_through_the_legs_jacobian():
    from rtgait.estimation.sole_wrenches import torque_wrenches

    rng = np.random.default_rng(3)
    jacobians = rng.normal(size=(2, 6, 6))
    needed = rng.normal(size=(2, 6))
    wrenches = rng.normal(size=(2, 6)) * 100.0
    # The leg's dynamics: tau = tau_id - J^T F.
    torques = needed - np.einsum("lij,li->lj", jacobians, wrenches)
    out = torque_wrenches(jacobians, needed, torques)
    np.testing.assert_allclose(out, wrenches, atol=1e-9)
    # A straight knee: a Jacobian without rank along the leg, the least-squares wrench, the others recovered.
    singular = jacobians.copy()
    singular[0, :, 3] = singular[0, :, 2]
    torques = needed - np.einsum("lij,li->lj", singular, wrenches)
    left, right = torque_wrenches(singular, needed, torques)
    np.testing.assert_allclose(singular[0].T @ left, needed[0] - torques[0], atol=1e-9)
    np.testing.assert_allclose(right, wrenches[1], atol=1e-9)


def test_bad_settings_and_readings_are_refused():
    robot = RigidRobot(FEET)
    with pytest.raises(ValueError, match="yaw"):
        estimator(robot, yaw="compass")
    with pytest.raises(ValueError, match="omega"):
        KinematicInertialEstimator(robot, 0.0)
    with pytest.raises(ValueError, match="start_feet"):
        KinematicInertialEstimator(robot, W, start_feet=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
    e = estimator(robot)
    zero = np.zeros(3)
    readings = robot.readings(0.0, np.array([0.1, 0.0, 0.75]), np.eye(3), zero, zero, zero, (300.0, 288.6))
    with pytest.raises(ValueError, match="IMU"):
        e.update(readings._replace(imu=None))
    with pytest.raises(ValueError, match="force sensors"):
        e.update(readings._replace(left_foot=None))


def test_the_estimation_layer_runs_without_mujoco_or_pinocchio():
    # In a fresh interpreter where importing MuJoCo or Pinocchio fails: the estimator imports and updates.
    code = """
import sys
class Refuse:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("mujoco", "pinocchio", "example_robot_data"):
            raise ImportError(f"{name} is blocked")
sys.meta_path.insert(0, Refuse())
import rtgait.estimation.kinematic_inertial, rtgait.estimation.kinematics, rtgait.estimation.ground_truth
import test_kinematic_inertial as t
robot = t.RigidRobot(t.FEET)
e = t.estimator(robot)
z = t.np.zeros(3)
m = e.update(robot.readings(0.0, t.np.array([0.1, 0.0, 0.75]), t.np.eye(3), z, z, z, (300.0, 288.6)))
assert not any(name.split(".")[0] in ("mujoco", "pinocchio") for name in sys.modules), "imported"
print(round(m.com[2], 6))
"""
    here = __file__.rsplit("/", 1)[0]
    root = here.rsplit("/", 2)[0]
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=here,
        env={"PYTHONPATH": f"{root}:{here}", "PATH": ""}, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert float(result.stdout) == pytest.approx(0.85)


def test_a_robot_in_flight_moves_on_as_its_accelerometer_says():
    # The robot leaves the ground (a hop after a push) and flies for 0.1 s with its joints still, pushed sideways as
    # it falls: nothing anchors it, the accelerometer alone carries it.
    robot = RigidRobot(FEET)
    e = estimator(robot)
    r, zero = rot(0.0, 0.0, 0.2), np.zeros(3)
    p0, v0 = np.array([0.1, 0.0, 0.75]), np.array([0.3, -0.2, 0.5])
    a = np.array([1.0, 2.0, -G])  # the push's acceleration and gravity
    # Standing, the base moves at v0 over the feet until the take-off at 0.1 s, from p0.
    for k in range(101):
        t = k * DT
        e.update(robot.readings(t, p0 + v0 * (t - 0.1), r, v0, zero, zero, (300.0, 288.6)))
    robot.place(p0, r, zero, zero)
    standing = robot.state  # the legs as they were at the take-off, still relative to the base from now on
    assert standing is not None
    still = [FrameMotion(sole.position, sole.rotation, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)) for sole in standing[2:4]]
    flying = standing._replace(left_sole=still[0], right_sole=still[1])
    specific = r.T @ (a + np.array([0.0, 0.0, G]))
    for k in range(1, 101):
        t = 0.1 + k * DT
        v = v0 + a * k * DT  # the truth
        imu = ImuReading(quat(r), (0.0, 0.0, 0.0), tuple(specific))
        robot.state = flying
        zeros = np.zeros(12)
        no_load = Wrench((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        m = e.update(SensorReadings(t, zeros, zeros, None, imu, no_load, no_load))
    p = p0 + v0 * 0.1 + 0.5 * a * 0.1**2
    # The tick at which the feet are seen to leave still blends in the legs' (zero) velocity: a fraction dt / tau of
    # the velocity, about 2 %, and what that costs the position over the flight.
    tau = 1.0 / (2.0 * math.pi * 3.5)
    np.testing.assert_allclose(m.com_vel, v, atol=2.0 * DT / tau * np.linalg.norm(v0))
    np.testing.assert_allclose(m.com, p + r @ COM_IN_BASE, atol=2.0 * DT / tau * np.linalg.norm(v0) * 0.1)
    assert not m.left.loaded and not m.right.loaded


def test_a_bounce_on_still_feet_moves_the_base_once():
    # Both feet's loads drop to nothing for 20 ms while the feet stay on the ground and the base moves on over them (a
    # stiff robot's bounce): the flight carries the base at its velocity from where it was, not on top of the legs'
    # motion relative to it (which would count the base's 6 mm over the bounce twice).
    robot = RigidRobot(FEET)
    e = estimator(robot)
    r, zero = rot(0.0, 0.0, 0.2), np.zeros(3)
    p0, v0 = np.array([0.1, 0.0, 0.75]), np.array([0.3, -0.1, 0.0])
    for k in range(301):
        t = k * DT
        loads = (0.0, 0.0) if 200 <= k < 220 else (300.0, 288.6)  # the bounce's ticks
        m = e.update(robot.readings(t, p0 + v0 * t, r, v0, zero, zero, loads))
        if k == 219:
            assert not m.left.loaded and not m.right.loaded  # still in the bounce
            np.testing.assert_allclose(m.com, p0 + v0 * t + r @ COM_IN_BASE, atol=1e-6)
    np.testing.assert_allclose(m.com, p0 + v0 * 0.3 + r @ COM_IN_BASE, atol=1e-6)
    assert m.left.loaded and m.right.loaded


def test_a_swinging_foot_loaded_high_above_the_ground_does_not_land():
    # The right foot swings 50 mm above the left's sole with a 300 N spike on its sensor (a whipped foot's inertia):
    # not loaded, no landing; back on the ground, its first load is a landing at once. A foot on a 20 mm step the plan
    # did not know of lands too.
    robot = RigidRobot(FEET)
    e = estimator(robot)
    p, r, zero = np.array([0.1, 0.0, 0.75]), rot(0.0, 0.0, 0.2), np.zeros(3)
    weight = MASS * G
    landings = []

    def run(t0: float, t1: float, right: float, height: float) -> list[bool]:
        x, y, _, yaw = FEET[1]
        robot.feet[1] = (np.array([x, y, height]), rot(0.0, 0.0, yaw))
        loaded = []
        for k in range(round(t0 / DT), round(t1 / DT)):
            m = e.update(robot.readings(k * DT, p, r, zero, zero, zero, (weight - right, right)))
            landings.extend(m.landings)
            loaded.append(m.right.loaded)
        return loaded

    run(0.0, 0.1, 0.5 * weight, 0.0)
    run(0.1, 0.2, 0.0, 0.05)
    assert not any(run(0.2, 0.205, 300.0, 0.05)) and landings == []
    run(0.205, 0.3, 0.0, 0.05)
    assert all(run(0.3, 0.35, 0.5 * weight, 0.0))
    assert [(landing.side, landing.t) for landing in landings] == [("right", pytest.approx(0.3))]
    run(0.35, 0.5, 0.0, 0.05)
    run(0.5, 0.55, 0.5 * weight, 0.02)
    assert len(landings) == 2 and landings[1].t == pytest.approx(0.5) and landings[1].z == pytest.approx(0.02)
