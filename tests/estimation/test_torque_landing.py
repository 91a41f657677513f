"""The landing threshold of torque-estimated feet wrenches scales with the sensors' noise beyond the described one."""

from __future__ import annotations

import math

import pytest

from rtgait.estimation.torque_landing import torque_landing_force


def test_the_described_noise_keeps_eight_percent_of_the_weight():
    assert torque_landing_force(327.1, 1.0) == pytest.approx(0.08 * 327.1)


def test_twice_the_noise_doubles_it_as_the_noise_s_standard_deviation_does():
    # Five standard deviations of a swinging leg's force error measured at twice G1's noise (10.06 N): 50.3 N.
    assert torque_landing_force(327.1, 2.0) == pytest.approx(2.0 * 0.08 * 327.1)
    assert torque_landing_force(327.1, 2.0) >= 5.0 * 10.06


def test_less_noise_does_not_lower_it():
    assert torque_landing_force(327.1, 0.0) == torque_landing_force(327.1, 0.5) == torque_landing_force(327.1, 1.0)


@pytest.mark.parametrize(("weight", "scale"), [(0.0, 1.0), (-1.0, 1.0), (math.nan, 1.0), (327.1, -0.1),
                                               (327.1, math.inf), (327.1, math.nan)])  # fmt: skip
def test_bad_inputs_are_refused(weight, scale):
    with pytest.raises(ValueError, match="must be"):
        torque_landing_force(weight, scale)
