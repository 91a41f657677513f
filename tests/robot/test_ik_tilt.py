"""The IK's tilted sole targets: the error to ``Rz(yaw) Ry(pitch) Rx(roll)`` against Pinocchio's log, and a solved
pose whose sole lies on a 10 degree slope (checked by forward kinematics of the full model)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.interface.task_targets import IKTargets  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.robot.rotation_errors import _foot_error  # noqa: E402


def _target(yaw: float, pitch: float, roll: float) -> np.ndarray:
    return pin.utils.rotate("z", yaw) @ pin.utils.rotate("y", pitch) @ pin.utils.rotate("x", roll)


def test_the_tilted_foot_error_is_the_log_to_the_tilted_target() -> None:
    rng = np.random.default_rng(3)
    for _ in range(100):
        rotation = pin.exp3(rng.uniform(-0.6, 0.6, 3))
        yaw, pitch, roll = rng.uniform(-math.pi, math.pi), rng.uniform(-0.4, 0.4), rng.uniform(-0.3, 0.3)
        h = np.eye(4)
        h[:3, :3] = rotation
        expected = pin.log3(_target(yaw, pitch, roll) @ rotation.T)
        got = _foot_error(h.tolist(), (0.0, 0.0, 0.0, yaw, pitch, roll), yaw)
        np.testing.assert_allclose(got, expected, atol=1e-9)
    # Without a tilt (or with a zero one) it is the level target's error.
    level = pin.log3(pin.utils.rotate("z", 0.2) @ rotation.T)
    np.testing.assert_allclose(_foot_error(h.tolist(), (0.0, 0.0, 0.0, 0.2), 0.2), level, atol=1e-9)
    np.testing.assert_allclose(_foot_error(h.tolist(), (0.0, 0.0, 0.0, 0.2, 0.0, 0.0), 0.2), level, atol=1e-9)


def test_a_sole_turned_to_a_slope_is_reached(g1) -> None:
    ik = WholeBodyIK(g1)
    data = g1.full_model.createData()
    pin.framesForwardKinematics(g1.full_model, data, g1.full_configuration(g1.q_half_sitting))
    left0 = data.oMf[g1.full_left_sole_id].translation
    right0 = data.oMf[g1.full_right_sole_id].translation
    com0 = pin.centerOfMass(g1.full_model, data, g1.full_configuration(g1.q_half_sitting))
    pitch = -math.radians(10.0)  # toes up: a slope rising ahead
    left = (left0[0] + 0.05, left0[1], left0[2] + 0.01, 0.0, pitch, 0.0)
    right = (right0[0], right0[1], right0[2], 0.0)
    targets = IKTargets((com0[0] + 0.02, 0.5 * (left0[1] + right0[1]), com0[2] - 0.02), left, right)
    q, _ = ik.solve(targets, g1.q_half_sitting, 100, 1e-10)
    pin.framesForwardKinematics(g1.full_model, data, g1.full_configuration(q))
    sole = data.oMf[g1.full_left_sole_id]
    np.testing.assert_allclose(sole.translation, left[:3], atol=1e-6)
    normal = sole.rotation[:, 2]
    np.testing.assert_allclose(normal, [math.sin(pitch), 0.0, math.cos(pitch)], atol=1e-6)  # the slope's normal
    np.testing.assert_allclose(data.oMf[g1.full_right_sole_id].rotation, np.eye(3), atol=1e-6)  # still level
