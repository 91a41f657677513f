"""Terrain height fields, the surface under a foot, reach checks and the swing over a height change, against
hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.swing import RISE_SHARE, swing_pose, swing_velocity, swing_vertical, up_ramp
from rtgait.core.geometry.terrain import PIT_DEPTH, Slope, Stairs, Step, SteppingStones, sole_gap, surface
from rtgait.core.geometry.terrain_walk import TerrainWalkError, check_reach

SOLE = SoleRect(0.105, 0.105, 0.065, 0.065)


def test_stairs_heights_step_at_each_nose():
    up = Stairs(0.15, 0.25, 3, "up", start=0.5)
    x = np.array([0.0, 0.4999, 0.5, 0.7499, 0.75, 1.0, 5.0])
    np.testing.assert_allclose(up.height(x, 0.0 * x), [0, 0, 0.15, 0.15, 0.3, 0.45, 0.45])
    down = Stairs(0.15, 0.25, 3, "down", start=0.5)
    assert down.height(1.0, 0.0) == pytest.approx(-0.45)


def test_slope_stone_and_step_heights():
    slope = Slope(0.2, 1.0, start=0.5)
    assert slope.height(1.0, 0.3) == pytest.approx(0.5 * math.tan(0.2))
    assert slope.height(3.0, 0.0) == pytest.approx(math.tan(0.2))
    stones = SteppingStones(0.2, 0.15, 0.1, 2, 0.19, start=0.3)
    assert stones.height(0.4, 0.095) == 0.0  # on the first stone of the left row
    assert stones.height(0.55, 0.095) == -PIT_DEPTH  # in the gap
    assert stones.height(0.4, 0.0) == -PIT_DEPTH  # between the rows
    assert stones.height(0.9, 0.0) == 0.0  # past the last stone: the ground again
    assert Step(-0.03, 0.7).height(0.8, 0.0) == pytest.approx(-0.03)


class _Banked:
    """Ground rising to the left (+y) at 0.1 m per m."""

    def height(self, x, y):
        return 0.1 * np.asarray(y, float) + 0.0 * np.asarray(x, float)


def test_surface_pitch_and_roll_signs():
    z, pitch, roll = surface(Slope(0.2, 2.0, start=0.0), 1.0, 0.0, 0.0)
    assert (z, pitch, roll) == pytest.approx((math.tan(0.2), -0.2, 0.0))  # rising ahead: toes up
    _, pitch, _ = surface(Slope(0.2, 2.0, start=0.0), 1.0, 0.0, math.pi)
    assert pitch == pytest.approx(0.2)  # facing back down the ramp: toes down
    _, pitch, roll = surface(_Banked(), 0.0, 0.0, 0.0)
    assert (pitch, roll) == pytest.approx((0.0, math.atan(0.1)))  # rising to the left lifts the left edge
    # A foot placed with that roll lies on the bank: no gap anywhere under its sole.
    lowest, highest = sole_gap(_Banked(), Footstep(0.0, 0.0, 0.0, "left", 0.0, 0.0, math.atan(0.1)), SOLE)
    assert max(abs(lowest), abs(highest)) < 1e-12


def test_sole_gap_sees_the_nose_under_a_foot():
    stairs = Stairs(0.15, 0.25, 3, start=0.5)
    lowest, _ = sole_gap(stairs, Footstep(0.45, 0.0, 0.0, "right"), SOLE)  # toe 5.5 cm past the nose
    assert lowest == pytest.approx(-0.15)


def test_reach_names_the_step():
    stance = Footstep(0.0, -0.1, 0.0, "right")
    with pytest.raises(TerrainWalkError, match=r"^step 4 goes 0\.25 m up: beyond the robot's reach"):
        check_reach(stance, Footstep(0.2, 0.1, 0.0, "left", z=0.25), 4, 0.3, 0.2)
    with pytest.raises(TerrainWalkError, match=r"^step 2 is 0\.35 m long: beyond the robot's reach"):
        check_reach(stance, Footstep(0.35, 0.1, 0.0, "left"), 2, 0.3, 0.2)
    check_reach(stance, Footstep(0.3, 0.1, 0.0, "left", z=-0.2), 3, 0.3, 0.2)  # at the limits: accepted


@pytest.mark.parametrize(("z0", "z1"), [(0.0, 0.15), (0.3, 0.15), (0.0, 0.0)])
def test_swing_height_ends_on_the_footholds_and_its_rate_is_its_derivative(z0, z1):
    h = 0.05
    start, end = Footstep(0.0, 0.0, 0.0, "left", z=z0), Footstep(0.25, 0.0, 0.0, "left", z=z1)
    assert swing_pose(start, end, 0.0, h)[2] == pytest.approx(z0)
    assert swing_pose(start, end, 1.0, h)[2] == pytest.approx(z1)
    assert swing_pose(start, end, 0.5, h)[2] == pytest.approx(max(z0, z1) + h)
    for s in np.linspace(0.01, 0.99, 23):
        d = 1e-6
        numeric = (swing_vertical(z0, z1, s + d, h)[0] - swing_vertical(z0, z1, s - d, h)[0]) / (2 * d)
        assert swing_vertical(z0, z1, s, h)[1] == pytest.approx(numeric, abs=1e-5)
        dx = (swing_pose(start, end, s + d, h)[0] - swing_pose(start, end, s - d, h)[0]) / (2 * d)
        assert swing_velocity(start, end, s, h, 1.0)[0] == pytest.approx(dx, abs=1e-5)
    for s in (0.0, 1.0):  # lift-off and touch-down at rest
        assert swing_velocity(start, end, s, h, 1.0) == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-12)
    if z0 != z1:  # the sole holds the top over the middle of the swing
        for s in np.linspace(RISE_SHARE, 1.0 - RISE_SHARE, 5):
            assert swing_pose(start, end, s, h)[2] == pytest.approx(max(z0, z1) + h)


def test_up_a_ramp_the_swing_lifts_off_the_line_between_the_footholds():
    # Up a 10 degree ramp: the sole point moves along the chord between the footholds and lifts h 64 s^3 (1 - s)^3
    # off it, the horizontal motion undelayed: at mid-swing it is halfway along and h above the chord's middle,
    # where the stair profile would still be rising toward z1 + h behind the body.
    pitch, h = -math.radians(10.0), 0.05
    start = Footstep(0.6, 0.1, 0.0, "left", z=0.2 * math.tan(-pitch), pitch=pitch)
    end = Footstep(1.0, 0.1, 0.0, "left", z=0.6 * math.tan(-pitch), pitch=pitch)
    assert up_ramp(start, end) and not up_ramp(end, start)  # down a ramp keeps the stair profile
    x, _, z, _ = swing_pose(start, end, 0.5, h)
    assert x == pytest.approx(0.8) and z == pytest.approx(0.5 * (start.z + end.z) + h)
    for s in np.linspace(0.01, 0.99, 23):
        d = 1e-6
        k = (s * s * s) * (10.0 - 15.0 * s + 6.0 * s * s)  # the quintic blend, the horizontal progress
        expected = start.z + k * (end.z - start.z) + h * 64.0 * s**3 * (1.0 - s) ** 3
        assert swing_pose(start, end, s, h)[2] == pytest.approx(expected, abs=1e-12)
        dz = (swing_pose(start, end, s + d, h)[2] - swing_pose(start, end, s - d, h)[2]) / (2 * d)
        assert swing_velocity(start, end, s, h, 1.0)[2] == pytest.approx(dz, abs=1e-5)
    for s in (0.0, 1.0):
        assert swing_velocity(start, end, s, h, 1.0) == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-12)
    # Onto level ground higher up (the ramp's top) from a ramp foothold: the same; between level footholds: not.
    assert up_ramp(start, Footstep(1.2, 0.1, 0.0, "left", z=0.3))
    assert not up_ramp(Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.4, 0.1, 0.0, "left", z=0.15))
