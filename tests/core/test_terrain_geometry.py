"""Terrain height fields, the surface under a foot, reach checks and the swing over a height change, against
hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.swing import (
    DESCENT_REACH,
    DESCENT_RISE,
    RISE_SHARE,
    down_stair,
    swing_pose,
    swing_velocity,
    swing_vertical,
    up_ramp,
)
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
    down = down_stair(start, end)
    assert down == (z1 < z0)
    assert swing_pose(start, end, 0.0, h)[2] == pytest.approx(z0)
    assert swing_pose(start, end, 1.0, h)[2] == pytest.approx(z1)
    assert swing_pose(start, end, 0.5, h)[2] == pytest.approx(max(z0, z1) + h)
    for s in np.linspace(0.01, 0.99, 23):
        d = 1e-6
        for stair_down in (False, True):  # both profiles: the rate is the height's derivative
            numeric = (
                swing_vertical(z0, z1, s + d, h, stair_down=stair_down)[0]
                - swing_vertical(z0, z1, s - d, h, stair_down=stair_down)[0]
            ) / (2 * d)
            assert swing_vertical(z0, z1, s, h, stair_down=stair_down)[1] == pytest.approx(numeric, abs=1e-5)
        dz = (swing_pose(start, end, s + d, h)[2] - swing_pose(start, end, s - d, h)[2]) / (2 * d)
        assert swing_velocity(start, end, s, h, 1.0)[2] == pytest.approx(dz, abs=1e-5)
        dx = (swing_pose(start, end, s + d, h)[0] - swing_pose(start, end, s - d, h)[0]) / (2 * d)
        assert swing_velocity(start, end, s, h, 1.0)[0] == pytest.approx(dx, abs=1e-5)
    for s in (0.0, 1.0):  # lift-off and touch-down at rest
        assert swing_velocity(start, end, s, h, 1.0) == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-12)
    if z0 < z1:  # up: the sole holds the top over the middle of the swing
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


def test_down_a_stair_the_swing_moves_forward_at_the_top_then_comes_straight_down():
    # From the upper tread (z0 = 0) to two treads down: the foot is over its landing by DESCENT_REACH of the swing, h
    # above the upper tread from DESCENT_RISE on, and only then comes down, vertically.
    h = 0.05
    start, end = Footstep(0.24, -0.085, 0.0, "right"), Footstep(0.72, -0.085, 0.0, "right", z=-0.37)
    for s in np.linspace(DESCENT_RISE, DESCENT_REACH, 7):
        assert swing_pose(start, end, s, h)[2] == pytest.approx(h)
    for s in np.linspace(DESCENT_REACH, 1.0, 7):
        x, y, z, _ = swing_pose(start, end, s, h)
        assert (x, y) == pytest.approx((end.x, end.y)) and end.z <= z <= h
    heights = [swing_pose(start, end, s, h)[2] for s in np.linspace(0.0, 1.0, 201)]
    assert max(heights) == pytest.approx(h)  # never above the clearance over the upper tread
    # At the lift-off the sole rises about as steeply as it moves forward (10 h (s/sigma)^3 against 10 L (s/R)^3).
    s = 0.02
    x, _, z, _ = swing_pose(start, end, s, h)
    assert 0.7 < z / (x - start.x) < 1.5
    # A ramp's footholds keep the stair profile (not a stair: tilted), ascents theirs.
    assert not down_stair(Footstep(0.0, 0.0, 0.0, "left", z=0.1, pitch=0.2), Footstep(0.3, 0.0, 0.0, "left"))
    assert not down_stair(end, start)


@pytest.mark.parametrize(
    ("riser", "tread", "first_nose", "length", "sole"),
    [
        (0.185, 0.24, 0.36, 0.24, SOLE),  # stairs-down-185 (Talos)
        (0.15, 0.25, 0.375, 0.25, SOLE),  # stairs-down (Talos)
        (0.10, 0.22, 0.365, 0.22, SoleRect(0.13, 0.06, 0.03, 0.03)),  # stairs-down-g1 (G1)
    ],
)
def test_down_the_built_in_stairs_every_nose_is_cleared_by_the_swing_height(riser, tread, first_nose, length, sole):
    # The footholds one per tread, mid-tread; each nose is a point (x_n, z_n) on the stairs' profile. Wherever the
    # swept sole (level, front ahead and back behind its sole point) spans a nose below the tread it left, its
    # underside is at least the swing height h above it; over the nose of that tread it never cuts in, and is h above
    # it once risen (s >= DESCENT_RISE).
    h = 0.05
    noses = [(first_nose + i * tread, -i * riser) for i in range(6)]
    xs = [k * length for k in range(8)]  # the scenarios' footholds: one step a tread
    zs = [-riser * sum(x > xn for xn, _ in noses) for x in xs]
    assert zs[1] == 0.0 and zs[-1] == -6 * riser
    for i in range(len(xs) - 2):
        start = Footstep(xs[i], 0.0, 0.0, "left", z=zs[i])
        end = Footstep(xs[i + 2], 0.0, 0.0, "left", z=zs[i + 2])
        assert down_stair(start, end) == (zs[i + 2] < zs[i])
        if zs[i + 2] == zs[i]:
            continue
        below, own, own_risen = np.inf, np.inf, np.inf
        for s in np.linspace(0.0, 1.0, 2001):
            x, _, z, _ = swing_pose(start, end, s, h)
            for xn, zn in noses:
                if x - sole.back <= xn <= x + sole.front:
                    if zn < zs[i] - 1e-9:
                        below = min(below, z - zn)
                    elif zn == zs[i]:
                        own = min(own, z - zn)
                        own_risen = min(own_risen, z - zn) if s >= DESCENT_RISE else own_risen
        assert below >= h - 1e-9 and own >= 0.0 and own_risen >= h - 1e-9, (i, below, own, own_risen)
