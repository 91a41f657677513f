"""The upper body's lean on Talos and G1: the IK's leaned targets and the lean's inertia (rtgait.robot.lean)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from rtgait.interface.task_targets import IKTargets
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.lean import hip_strategy_limits, lean_inertia
from rtgait.robot.model import RobotModel


@pytest.fixture(scope="module", params=["talos", "g1"])
def robot(request: pytest.FixtureRequest) -> RobotModel:
    return RobotModel.load(request.param)


def _rest(robot: RobotModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """COM, soles, torso and pelvis orientations at half-sitting."""
    data = robot.model.createData()
    q = robot.q_half_sitting
    com = pin.centerOfMass(robot.model, data, q).copy()
    pin.framesForwardKinematics(robot.model, data, q)
    left = data.oMf[robot.left_sole_id].translation.copy()
    right = data.oMf[robot.right_sole_id].translation.copy()
    return com, left, right, data.oMf[robot.torso_id].rotation.copy(), data.oMi[1].rotation.copy()


def _leaned(robot: RobotModel, lean: tuple[float, float, float]) -> np.ndarray:
    com, left, right, _, _ = _rest(robot)
    ik = WholeBodyIK(robot)
    q, _ = ik.solve(IKTargets(com, (*left, 0.0), (*right, 0.0), lean), robot.q_half_sitting, 60, 1e-10)
    return q


@pytest.mark.parametrize("lean", [(0.2, 0.0, 0.0), (0.0, -0.2, 0.0), (0.12, 0.12, 0.0)])
def test_the_ik_leans_torso_and_pelvis_with_the_com_and_soles_held(robot: RobotModel, lean: tuple) -> None:
    com, left, right, torso, pelvis = _rest(robot)
    q = _leaned(robot, lean)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    turn = pin.exp3(np.array(lean))
    # Each orientation is the upright one turned by the lean in the world frame (heading 0 here), to the bias the
    # tiny damping and posture pull leave on the lightly weighted pelvis task.
    assert np.linalg.norm(pin.log3(data.oMf[robot.torso_id].rotation @ torso.T @ turn.T)) < 1e-5
    assert np.linalg.norm(pin.log3(data.oMi[1].rotation @ pelvis.T @ turn.T)) < 1e-5
    assert np.linalg.norm(pin.centerOfMass(robot.model, data, q) - com) < 1e-6
    assert np.linalg.norm(data.oMf[robot.left_sole_id].translation - left) < 1e-6
    assert np.linalg.norm(data.oMf[robot.right_sole_id].translation - right) < 1e-6
    assert np.all(q[7:] >= robot.model.lowerPositionLimit[7:] - 1e-9)
    assert np.all(q[7:] <= robot.model.upperPositionLimit[7:] + 1e-9)


def test_the_lean_inertia_is_the_momentum_of_a_small_lean(robot: RobotModel) -> None:
    """Against finite differences: the configuration the IK reaches for a 1 mrad lean, as a velocity over one
    second, times Pinocchio's centroidal momentum matrix, has the angular momentum ``I`` per rad/s about the lean's
    axis and next to no linear momentum (the COM stays)."""
    forward, sideways = lean_inertia(robot)
    small = 1e-3
    for axis, expected in (((0.0, 1.0, 0.0), forward), ((1.0, 0.0, 0.0), sideways)):
        q = _leaned(robot, tuple(small * a for a in axis))  # type: ignore[arg-type]
        v = pin.difference(robot.model, robot.q_half_sitting, q) / small
        data = robot.model.createData()
        momentum = pin.computeCentroidalMap(robot.model, data, robot.q_half_sitting) @ v
        assert float(np.dot(momentum[3:6], axis)) == pytest.approx(expected, rel=0.02)
        assert np.linalg.norm(momentum[0:3]) < 1e-3 * robot.mass


def test_the_limits_come_from_the_hips(robot: RobotModel) -> None:
    limits = hip_strategy_limits(robot)
    assert limits.inertia == pytest.approx(lean_inertia(robot))
    # Half the hip's rated torque over the inertia: Talos's and G1's hip pitch and roll joints are rated 88-160 N m.
    for inertia, acceleration in zip(limits.inertia, limits.max_acceleration, strict=True):
        torque = 2.0 * inertia * acceleration
        assert 80.0 <= torque <= 170.0
    assert lean_inertia(RobotModel.load("talos"))[1] > 3 * lean_inertia(RobotModel.load("g1"))[1]


def test_the_servo_bound_is_the_hip_servos_natural_frequency_at_the_robots_gains(robot: RobotModel) -> None:
    """At the robot's own gains the lean carries sqrt(robot_kp / (I + armature)) of the hip joint about each axis
    (the description's numbers, read here by joint name); with the stiff gains none."""
    stiff, own = hip_strategy_limits(robot), hip_strategy_limits(robot, gains="robot")
    assert stiff.servo_bandwidth is None
    assert own.servo_bandwidth is not None
    hips = {"talos": ("leg_left_3_joint", "leg_left_2_joint"), "g1": ("left_hip_pitch_joint", "left_hip_roll_joint")}
    for joint, inertia, bandwidth in zip(hips[robot.name], own.inertia, own.servo_bandwidth, strict=True):
        spec = robot.description.joint_actuation(joint)
        assert spec.robot_kp is not None and spec.armature is not None
        assert bandwidth == pytest.approx(np.sqrt(spec.robot_kp / (inertia + spec.armature)), rel=1e-12)
    with pytest.raises(ValueError, match="gains"):
        hip_strategy_limits(robot, gains="soft")
