"""The estimator's kinematics kept for the feed-forward at the sensed state: what the wrapped kinematics computed,
and none for an estimator without them."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from rtgait.robot.kinematics import PinocchioKinematics
from rtgait.robot.model import RobotModel
from rtgait.stack.estimators import SharedKinematics, make_estimator, shared_kinematics


def test_the_last_update_is_kept_and_the_rest_is_the_wrapped_kinematics():
    g1 = RobotModel.load("g1")
    estimator = make_estimator("estimated", g1, 3.5)
    kinematics = shared_kinematics(estimator)
    assert isinstance(kinematics, SharedKinematics) and kinematics.last is None
    joints = g1.q_half_sitting[7:] + 0.05
    velocities = np.full(len(joints), 0.2)
    body = kinematics.update(joints, velocities)
    assert kinematics.last is body
    own = PinocchioKinematics(g1).update(joints, velocities)  # the same frames from a kinematics of its own
    np.testing.assert_allclose(body.left_sole.position, own.left_sole.position, atol=1e-12)
    np.testing.assert_allclose(body.right_sole.velocity, own.right_sole.velocity, atol=1e-12)
    assert kinematics.joint_count == len(joints)  # the wrapped kinematics' attributes


def test_an_estimator_without_kinematics_shares_none():
    assert shared_kinematics(make_estimator("truth", RobotModel.load("g1"), 3.5)) is None


def test_the_landing_threshold_follows_the_sensor_noise_only_without_foot_sensors():
    g1, talos = RobotModel.load("g1"), RobotModel.load("talos")
    described = make_estimator("estimated", g1, 3.5).load.landing_force
    assert make_estimator("estimated", g1, 3.5, sensor_noise=0.5).load.landing_force == described
    assert make_estimator("estimated", g1, 3.5, sensor_noise=2.0).load.landing_force == pytest.approx(2.0 * described)
    # Talos's feet carry force sensors: their threshold is the sensors', whatever the noise.
    talos_force = make_estimator("estimated", talos, 3.5).load.landing_force
    assert make_estimator("estimated", talos, 3.5, sensor_noise=2.0).load.landing_force == talos_force


def test_the_heading_comes_from_where_the_description_says():
    # Talos's AHRS drifts 0.1 mrad/s in yaw, G1's IMU ten times that: Talos steers by its IMU, G1 by its feet.
    talos, g1 = RobotModel.load("talos"), RobotModel.load("g1")
    assert talos.description.sensors.imu.yaw_source == "imu"
    assert make_estimator("estimated", talos, 3.5).yaw == "imu"
    assert make_estimator("estimated", g1, 3.5).yaw == "feet"
