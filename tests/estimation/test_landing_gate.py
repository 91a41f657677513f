"""The landing gate (rtgait.estimation.landing_gate, rtgait.estimation.load): a load on a swinging foot high above
the ground is not a landing, a real one is seen at once; the soles' lowest corners against numpy's corners."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.landing_gate import DEFAULT_LANDING_CLEARANCE, lowest_sole_height, near_ground
from rtgait.estimation.load import LoadHysteresis


def _rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))  # fmt: skip
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


@pytest.mark.parametrize("angles", [(0.0, 0.0, 0.3), (0.05, -0.1, 1.0), (-0.2, 0.15, -2.0), (0.0, 0.3, 0.0)])
def test_the_lowest_corner_is_the_lowest_of_the_four(angles):
    r = _rot(*angles)
    extents = (-0.1, 0.15, -0.05, 0.07)
    corners = [r @ np.array([x, y, 0.0]) for x in extents[:2] for y in extents[2:]]
    expected = 0.2 + min(c[2] for c in corners)
    assert lowest_sole_height(0.2, tuple(r.ravel()), extents) == pytest.approx(expected, abs=1e-12)
    assert lowest_sole_height(0.2, tuple(r.ravel()), None) == 0.2


def test_a_foot_lands_only_near_the_stance_soles_height():
    c = DEFAULT_LANDING_CLEARANCE
    # The right foot stands; the left swings 50 mm, then 20 mm above it (an unseen step up), then 40 mm below.
    assert near_ground(c, (False, True), (0.05, 0.0)) == (False, True)
    assert near_ground(c, (False, True), (0.02, 0.0)) == (True, True)
    assert near_ground(c, (False, True), (-0.04, 0.0)) == (True, True)
    # Both feet unloaded (the stance foot's sensor ringing below the release force): the lower one is the reference.
    assert near_ground(c, (False, False), (0.048, 0.0)) == (False, True)
    # Both loaded: nothing to gate; no clearance: no gate.
    assert near_ground(c, (True, True), (0.3, 0.0)) == (True, True)
    assert near_ground(math.inf, (False, True), (0.3, 0.0)) == (True, True)


def _primed(sustain: float = 0.0) -> LoadHysteresis:
    load = LoadHysteresis(25.0, 12.5, 0.05, sustain)
    load.update(0, 400.0, 0.0)
    load.update(0, 0.0, 0.001)  # lifted off
    load.prime()
    return load


def test_a_force_spike_on_a_foot_high_above_the_ground_is_not_a_landing():
    load = _primed()
    # A whipped foot's ankle sensor 0.15 s into the swing: +330, -260, +64 N while the foot is far from the ground.
    for k, f in enumerate((330.0, -260.0, 64.0, 300.0)):
        assert load.update(0, f, 0.15 + 0.001 * k, near_ground=False) is False
    # The same foot near the ground later: the first load is its landing, at once.
    assert load.update(0, 5.0, 0.3, near_ground=True) is False
    assert load.update(0, 40.0, 0.301, near_ground=True) is None
    assert load.update(0, 40.0, 0.302, near_ground=False) is True  # a loaded foot is not gated


def test_a_sustained_load_counts_after_its_time_a_ringing_one_not():
    load = _primed(0.003)
    ringing = [330.0 if k % 2 == 0 else -260.0 for k in range(20)]
    assert all(load.update(0, f, 0.2 + 0.001 * k) is False for k, f in enumerate(ringing))
    states = [load.update(0, 100.0, 0.3 + 0.001 * k) for k in range(5)]
    assert states == [False, False, False, None, True]  # loaded 3 ms after the force rose
    with pytest.raises(ValueError, match="sustain_time"):
        LoadHysteresis(25.0, 12.5, 0.05, -1.0)


def test_a_planned_rise_lets_a_foot_down_onto_a_higher_tread_and_no_higher() -> None:
    # A foot 0.15 m above the other is far off level ground, but on a stair tread the plan has 0.15 m up it lands;
    # 0.15 m plus more than the clearance is still refused, and the other foot gets no allowance from the rise.
    clearance, unloaded = DEFAULT_LANDING_CLEARANCE, (False, False)
    assert near_ground(clearance, unloaded, (0.15, 0.0)) == (False, True)
    assert near_ground(clearance, unloaded, (0.15, 0.0), rise=0.15) == (True, True)
    assert near_ground(clearance, unloaded, (0.15 + clearance + 0.005, 0.0), rise=0.15) == (False, True)
    assert near_ground(clearance, unloaded, (0.0, 0.15), rise=0.15) == (True, False)
    assert near_ground(clearance, unloaded, (0.0, 0.15), rise=-0.15) == (True, True)


def test_a_planned_drop_keeps_a_foot_swinging_down_a_stair_from_landing_above_the_lower_tread() -> None:
    # The right foot stands on the upper tread; the left swings to a tread 0.15 m lower. Its toe 2 cm above the upper
    # tread is no landing (without the planned drop it would be one), near the lower tread it is.
    clearance, stance = DEFAULT_LANDING_CLEARANCE, (False, True)
    assert near_ground(clearance, stance, (0.02, 0.0)) == (True, True)
    assert near_ground(clearance, stance, (0.02, 0.0), rise=-0.15) == (False, True)
    assert near_ground(clearance, stance, (-0.15 + clearance - 0.005, 0.0), rise=-0.15) == (True, True)
    assert near_ground(clearance, stance, (-0.15 + clearance + 0.005, 0.0), rise=-0.15) == (False, True)
