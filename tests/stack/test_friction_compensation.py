"""The friction compensation of the feed-forward: a fraction of the description's friction, opposing nothing at rest
and along the reference's motion when it moves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.stack.friction_compensation import IDENTIFIED_FRACTION, STICTION_SPEED, FrictionCompensation


def test_moving_joints_get_the_fraction_of_coulomb_and_viscous_friction() -> None:
    compensation = FrictionCompensation(np.array([2.4, 1.2]), np.array([0.24, 0.12]), fraction=0.5)
    velocity = np.array([2.0, -3.0])  # 40 and 60 times the stiction speed: tanh is 1 to 1e-30
    expected = 0.5 * np.array([2.4 + 0.24 * 2.0, -(1.2 + 0.12 * 3.0)])
    np.testing.assert_allclose(compensation.torques(velocity), expected, rtol=1e-12)


def test_rest_gets_none_and_the_sign_is_smoothed() -> None:
    compensation = FrictionCompensation(np.array([1.0]), np.array([0.0]))
    assert compensation.torques(np.zeros(1))[0] == 0.0
    at_speed = compensation.torques(np.array([STICTION_SPEED]))[0]
    assert at_speed == pytest.approx(IDENTIFIED_FRACTION * math.tanh(1.0))
    assert compensation.torques(np.array([-STICTION_SPEED]))[0] == pytest.approx(-at_speed)


def test_the_robots_motor_types_give_the_friction() -> None:
    pytest.importorskip("pinocchio")
    from rtgait.robot.model import RobotModel

    g1 = RobotModel.load("g1")
    compensation = FrictionCompensation.of(g1)
    knee = g1.joint_names.index("left_knee_joint")
    assert compensation.coulomb[knee] == pytest.approx(IDENTIFIED_FRACTION * 2.4)  # N7520-22.5's 2.4 N m
    assert compensation.viscous[knee] == pytest.approx(IDENTIFIED_FRACTION * 0.24)
    assert len(compensation.coulomb) == len(g1.joint_names)


@pytest.mark.parametrize(
    ("coulomb", "viscous", "fraction", "speed"),
    [([-1.0], [0.0], 0.7, 0.05), ([1.0], [0.0, 1.0], 0.7, 0.05), ([1.0], [0.0], 1.5, 0.05), ([1.0], [0.0], 0.7, 0.0)],
)
def test_bad_settings_are_refused(coulomb, viscous, fraction, speed) -> None:
    with pytest.raises(ValueError):
        FrictionCompensation(np.array(coulomb), np.array(viscous), fraction, speed)
