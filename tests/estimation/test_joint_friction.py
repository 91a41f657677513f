"""The joints' identified friction at their measured velocities: Coulomb with a tanh-smoothed sign, plus viscous."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.joint_friction import MEASURED_STICTION_SPEED, JointFriction


def test_friction_opposes_the_measured_motion_and_fades_at_rest() -> None:
    friction = JointFriction(np.array([2.4, 1.2, 1.0]), np.array([0.24, 0.12, 0.0]))
    velocity = np.array([3.0, -2.0, 0.5 * MEASURED_STICTION_SPEED])
    expected = [2.4 * math.tanh(30.0) + 0.24 * 3.0, -(1.2 * math.tanh(20.0) + 0.12 * 2.0), math.tanh(0.5)]
    np.testing.assert_allclose(friction.torques(velocity), expected, rtol=1e-12)
    np.testing.assert_array_equal(friction.torques(np.zeros(3)), 0.0)


@pytest.mark.parametrize(
    ("coulomb", "viscous", "speed"),
    [([-1.0], [0.0], 0.1), ([1.0], [0.0, 1.0], 0.1), ([math.nan], [0.0], 0.1), ([1.0], [0.0], 0.0)],
)
def test_bad_settings_are_refused(coulomb, viscous, speed) -> None:
    with pytest.raises(ValueError):
        JointFriction(np.array(coulomb), np.array(viscous), speed)
