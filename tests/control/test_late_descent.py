"""The late foot's descent profile (rtgait.control.late_descent) against finite differences of itself."""

from __future__ import annotations

import itertools

import pytest

from rtgait.control.late_descent import descent_depth, descent_ramp
from rtgait.core.lipm.closed_form import GRAVITY

DT = 1e-4  # s: finer than a control tick, so that the differences resolve the ramp


def differences(speed: float, limit: float, span: float) -> tuple[list[float], list[float], list[float]]:
    """Depths, rates and accelerations of the profile sampled every DT from before its start to ``span``."""
    depths = [descent_depth(k * DT, speed, limit) for k in range(-5, round(span / DT))]
    rates = [(b - a) / DT for a, b in itertools.pairwise(depths)]
    accelerations = [(b - a) / DT for a, b in itertools.pairwise(rates)]
    return depths, rates, accelerations


@pytest.mark.parametrize(("speed", "limit"), [(0.3, 0.02), (0.3, 0.005), (0.1, 0.05), (1.0, 0.02)])
def test_descent_is_continuous_in_velocity_and_ends_at_rest_at_the_limit(speed, limit):
    depths, rates, accelerations = differences(speed, limit, 3.0 * descent_ramp(speed) + limit / speed)
    assert depths[:6] == [0.0] * 6, "at rest before it starts"
    assert rates[5] < GRAVITY * DT, "leaves rest without a step in velocity"
    # Gravity's acceleration at most (the quintic's peak), to the sampling's second order.
    assert max(abs(a) for a in accelerations) <= GRAVITY * 1.001
    assert max(rates) <= speed * (1.0 + 1e-9)
    assert depths[-1] == pytest.approx(limit, abs=1e-12) and rates[-1] == pytest.approx(0.0, abs=1e-9)
    assert all(b >= a - 1e-15 for a, b in itertools.pairwise(depths)), "only down"


def test_descent_reaches_its_speed_when_there_is_room_and_lags_half_a_ramp():
    speed, limit = 0.3, 0.05
    ramp = descent_ramp(speed)
    assert ramp == pytest.approx(15.0 / 8.0 * speed / GRAVITY)
    assert descent_ramp(speed, 2.0 * GRAVITY) == pytest.approx(0.5 * ramp)
    _, rates, _ = differences(speed, limit, 2.0 * ramp)
    assert max(rates) == pytest.approx(speed, rel=1e-6)
    tau = 1.5 * ramp  # at full speed: half a ramp behind a descent at full speed from the start
    assert descent_depth(tau, speed, limit) == pytest.approx(speed * (tau - 0.5 * ramp), rel=1e-12)


def test_a_short_descent_peaks_below_its_speed():
    speed, limit = 0.3, 0.005  # shorter than speed * ramp (17 mm)
    _, rates, _ = differences(speed, limit, 2.5 * descent_ramp(speed))
    assert max(rates) == pytest.approx(limit / descent_ramp(speed), rel=1e-3) and max(rates) < speed


@pytest.mark.parametrize(("tau", "speed", "limit"), [(-1.0, 0.3, 0.02), (0.1, 0.0, 0.02), (0.1, 0.3, 0.0)])
def test_no_descent(tau, speed, limit):
    assert descent_depth(tau, speed, limit) == 0.0
