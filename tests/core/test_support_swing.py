"""Support polygons, the signed ZMP margin, sole rectangles, footstep geometry and swing-foot trajectories."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtgait.core.geometry.footsteps import (
    Footstep,
    SoleRect,
    Stride,
    place_footsteps,
    place_step,
    standing_feet,
    stride_between,
    wrap_angle,
)
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.geometry.swing import swing_pose, swing_velocity

SETTINGS = settings(max_examples=60, deadline=None)
SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # counter-clockwise unit square


# ----- signed margin --------------------------------------------------------------------------------------
def square_margin(x: float, y: float) -> float:
    """Signed distance to the unit square's boundary, by cases: inside the nearest edge, outside the nearest
    point of the closed square (clamping each coordinate to [0, 1])."""
    if 0.0 <= x <= 1.0 and 0.0 <= y <= 1.0:
        return min(x, 1.0 - x, y, 1.0 - y)
    return -math.hypot(x - min(max(x, 0.0), 1.0), y - min(max(y, 0.0), 1.0))


@SETTINGS
@given(st.floats(-2.0, 3.0), st.floats(-2.0, 3.0))
def test_signed_margin_on_a_square(x, y):
    assert signed_margin(np.array([[x, y]]), SQUARE)[0] == pytest.approx(square_margin(x, y), abs=1e-12)


@pytest.mark.parametrize(
    ("point", "expected"),
    [
        ((0.5, 0.5), 0.5),  # centre
        ((0.1, 0.5), 0.1),  # near the left edge
        ((0.5, 0.97), 0.03),  # near the top edge
        ((1.0, 0.5), 0.0),  # on an edge
        ((1.3, 0.5), -0.3),  # outside an edge
        ((1.3, 1.4), -0.5),  # outside a corner: 3-4-5 triangle
        ((-0.6, -0.8), -1.0),  # outside the opposite corner
    ],
)
def test_signed_margin_known_points(point, expected):
    assert signed_margin(np.array(point), SQUARE)[0] == pytest.approx(expected, abs=1e-12)


@SETTINGS
@given(st.floats(-math.pi, math.pi), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.integers(0, 2**32 - 1))
def test_signed_margin_is_invariant_under_rigid_motion(angle, dx, dy, seed):
    points = np.random.default_rng(seed).uniform(-1.0, 2.0, (20, 2))
    c, s = math.cos(angle), math.sin(angle)
    R = np.array([[c, -s], [s, c]])
    moved = signed_margin(points @ R.T + [dx, dy], SQUARE @ R.T + [dx, dy])
    expected = [square_margin(x, y) for x, y in points]
    np.testing.assert_allclose(moved, expected, rtol=0, atol=1e-9)


def test_signed_margin_on_a_triangle():
    triangle = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    # Inside: the hypotenuse x + y = 2 is at distance (2 - x - y) / sqrt(2).
    assert signed_margin(np.array([0.9, 0.9]), triangle)[0] == pytest.approx(0.2 / math.sqrt(2.0), abs=1e-12)
    # Outside beyond the hypotenuse's middle: distance to that line.
    assert signed_margin(np.array([1.5, 1.5]), triangle)[0] == pytest.approx(-1.0 / math.sqrt(2.0), abs=1e-12)
    # Outside beyond a vertex: distance to the vertex, not to the edge lines' extensions.
    assert signed_margin(np.array([3.0, -1.0]), triangle)[0] == pytest.approx(-math.sqrt(2.0), abs=1e-12)


# ----- soles and support polygons -------------------------------------------------------------------------
SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)


@pytest.mark.parametrize("side", ["left", "right"])
def test_sole_corners_of_an_unrotated_foot(side):
    sole = SoleRect(front=0.2, back=0.1, inner=0.03, outer=0.05)
    corners = sole.corners(Footstep(1.0, 2.0, 0.0, side))
    # Outer edge away from the other foot: +y for the left foot, -y for the right one.
    y_lo, y_hi = (2.0 - 0.03, 2.0 + 0.05) if side == "left" else (2.0 - 0.05, 2.0 + 0.03)
    assert corners[:, 0].min() == pytest.approx(0.9) and corners[:, 0].max() == pytest.approx(1.2)
    assert corners[:, 1].min() == pytest.approx(y_lo) and corners[:, 1].max() == pytest.approx(y_hi)
    # Counter-clockwise: positive shoelace area equal to the rectangle's.
    x, y = corners[:, 0], corners[:, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) == pytest.approx(0.3 * 0.08)


@SETTINGS
@given(st.floats(-math.pi, math.pi), st.floats(-1, 1), st.floats(-1, 1), st.sampled_from(["left", "right"]))
def test_rotated_sole_is_the_rotated_rectangle(yaw, x, y, side):
    corners = SOLE.corners(Footstep(x, y, yaw, side))
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    leftward = np.array([-math.sin(yaw), math.cos(yaw)])
    along = (corners - [x, y]) @ forward
    across = (corners - [x, y]) @ leftward
    np.testing.assert_allclose(sorted(set(np.round(along, 9))), [-0.10, 0.13], atol=1e-9)
    np.testing.assert_allclose(sorted(set(np.round(across, 9))), [-0.07, 0.07], atol=1e-9)


@SETTINGS
@given(
    st.floats(-0.3, 0.4),
    st.floats(0.15, 0.35),
    st.floats(-0.4, 0.4),
    st.floats(-math.pi, math.pi),
    st.sampled_from(["left", "right"]),
)
def test_double_support_polygon_contains_both_soles(length, width, turn, yaw, side):
    stance = Footstep(0.3, -0.2, yaw, side)
    landing = place_step(stance, Stride(length, width, turn))
    polygon = support_polygon([stance, landing], SOLE)
    x, y = polygon[:, 0], polygon[:, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0.0  # counter-clockwise
    corners = np.vstack([SOLE.corners(stance), SOLE.corners(landing)])
    # Every sole corner is in the polygon (margin ~0 or more) and every polygon vertex is a sole corner: the
    # polygon is exactly the convex hull of the two soles.
    assert np.all(signed_margin(corners, polygon) > -1e-12)
    assert all(np.min(np.abs(corners - vertex).sum(axis=1)) == 0.0 for vertex in polygon)
    # The middle of each sole is strictly inside.
    assert np.all(signed_margin(np.array([stance.position, landing.position]), polygon) > 0.0)


def test_single_support_polygon_is_the_sole():
    foot = Footstep(0.5, 0.1, 0.3, "left")
    polygon = support_polygon([foot], SOLE)
    np.testing.assert_allclose(polygon, SOLE.corners(foot))
    # The foot frame origin is 0.07 m from the inner and outer edges, 0.10 m from the heel, 0.13 from the toe.
    assert signed_margin(foot.position, polygon)[0] == pytest.approx(0.07, abs=1e-12)


def test_support_polygon_needs_a_foot():
    with pytest.raises(ValueError, match="at least one foot"):
        support_polygon([], SOLE)


@pytest.mark.parametrize("field", ["front", "back", "inner", "outer"])
def test_sole_rejects_negative_or_nan_sizes(field):
    for bad in (-0.01, math.nan):
        values = dict(front=0.1, back=0.1, inner=0.05, outer=0.05) | {field: bad}
        with pytest.raises(ValueError, match=field):
            SoleRect(**values)


# ----- footsteps --------------------------------------------------------------------------------------------
@SETTINGS
@given(
    st.floats(-0.3, 0.4),
    st.floats(0.15, 0.35),
    st.floats(-1.2, 1.2),
    st.floats(-math.pi, math.pi),
    st.sampled_from(["left", "right"]),
)
def test_place_step_follows_the_stride_definition(length, width, turn, yaw, side):
    stance = Footstep(1.0, 2.0, yaw, side)
    landing = place_step(stance, Stride(length, width, turn))
    assert landing.side != stance.side
    # In the frame of the mean heading of the two feet: forward = length, sideways = +-width.
    heading = yaw + 0.5 * turn
    d = landing.position - stance.position
    assert d @ [math.cos(heading), math.sin(heading)] == pytest.approx(length, abs=1e-12)
    lateral = d @ [-math.sin(heading), math.cos(heading)]
    assert lateral == pytest.approx(width if landing.side == "left" else -width, abs=1e-12)
    assert wrap_angle(landing.yaw - yaw - turn) == pytest.approx(0.0, abs=1e-12)
    back = stride_between(stance, landing)
    assert (back.length, back.width, back.turn) == pytest.approx((length, width, turn), abs=1e-12)


def test_standing_feet_and_footprint_numbering():
    first, second = standing_feet(0.2, "right")
    assert (first.side, first.y, second.side, second.y) == ("right", -0.1, "left", 0.1)
    prints = place_footsteps((first, second), [Stride(0.1, 0.2)] * 3)
    assert [p.side for p in prints] == ["right", "left", "right", "left", "right"]
    np.testing.assert_allclose([p.x for p in prints], [0.0, 0.0, 0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="step_width"):
        standing_feet(-0.2)


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: Footstep(math.nan, 0.0, 0.0, "left"), "footstep x"),
        (lambda: Footstep(0.0, 0.0, math.inf, "left"), "footstep yaw"),
        (lambda: Footstep(0.0, 0.0, 0.0, "middle"), "side"),
        (lambda: Stride(math.nan, 0.2), "stride length"),
        (lambda: Stride(0.1, 0.0), "stride width"),
        (lambda: Stride(0.1, 0.2, 2.0), "stride turn"),
    ],
)
def test_footstep_values_are_validated(make, field):
    with pytest.raises(ValueError, match=field):
        make()


def test_wrap_angle():
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-3 * math.pi / 2) == pytest.approx(math.pi / 2)
    assert wrap_angle(0.3) == pytest.approx(0.3)


# ----- swing foot -------------------------------------------------------------------------------------------
@SETTINGS
@given(
    st.floats(-0.4, 0.4),
    st.floats(-0.4, 0.4),
    st.floats(-3.0, 3.0),
    st.floats(-0.6, 0.6),
    st.floats(0.0, 0.15),
    st.floats(0.3, 1.5),
)
def test_swing_ends_at_the_footprints_with_zero_velocity(dx, dy, yaw, dyaw, height, duration):
    start = Footstep(0.1, -0.1, yaw, "right")
    end = Footstep(0.1 + dx, -0.1 + dy, wrap_angle(yaw + dyaw), "right")
    pose0 = np.array(swing_pose(start, end, 0.0, height))
    pose1 = np.array(swing_pose(start, end, 1.0, height))
    np.testing.assert_allclose(pose0, [start.x, start.y, 0.0, start.yaw], atol=1e-12)
    assert pose1[:3] == pytest.approx([end.x, end.y, 0.0], abs=1e-12)
    assert wrap_angle(pose1[3] - end.yaw) == pytest.approx(0.0, abs=1e-12)

    # Finite differences in time near both ends: position changes O(h^3) (zero velocity and acceleration).
    h = 1e-4  # s; a foot leaving with any real speed (0.01 m/s) would show 100 times the bound below
    for s0, s1 in ((0.0, h / duration), (1.0, 1.0 - h / duration)):
        a = np.array(swing_pose(start, end, s0, height))
        b = np.array(swing_pose(start, end, s1, height))
        b[3] = a[3] + wrap_angle(b[3] - a[3])
        assert np.max(np.abs((b - a) / h)) < 1e-4
        # The analytic velocity is zero at the ends.
        np.testing.assert_allclose(swing_velocity(start, end, s0, height, duration), 0.0, atol=1e-12)

    # Mid-swing: the analytic velocity matches a central finite difference of the pose.
    for s in (0.2, 0.5, 0.77):
        ds = 1e-6 / duration
        a = np.array(swing_pose(start, end, s - ds, height))
        b = np.array(swing_pose(start, end, s + ds, height))
        fd = (b - a) / 2e-6
        fd[3] = wrap_angle(b[3] - a[3]) / 2e-6
        np.testing.assert_allclose(swing_velocity(start, end, s, height, duration), fd, rtol=1e-5, atol=1e-6)


def test_swing_height_peaks_mid_swing_and_stays_above_ground():
    start, end = Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.3, 0.1, 0.0, "left")
    s = np.linspace(0.0, 1.0, 201)
    z = np.array([swing_pose(start, end, v, 0.05)[2] for v in s])
    assert z.max() == pytest.approx(0.05) and s[np.argmax(z)] == pytest.approx(0.5)
    assert np.all(z[1:-1] > 0.0)
    x = np.array([swing_pose(start, end, v, 0.05)[0] for v in s])
    assert np.all(np.diff(x) >= 0.0)  # no overshoot: monotone progress
    # Progress outside [0, 1] is clamped.
    assert swing_pose(start, end, -0.5, 0.05) == swing_pose(start, end, 0.0, 0.05)
    assert swing_pose(start, end, 1.5, 0.05) == swing_pose(start, end, 1.0, 0.05)


def test_swing_turns_the_short_way_across_pi():
    start = Footstep(0.0, 0.0, math.pi - 0.1, "left")
    end = Footstep(0.0, 0.0, -math.pi + 0.1, "left")  # 0.2 rad further counter-clockwise
    yaws = [swing_pose(start, end, s, 0.0)[3] for s in np.linspace(0.0, 1.0, 11)]
    steps = [wrap_angle(b - a) for a, b in itertools.pairwise(yaws)]
    assert all(step >= 0.0 for step in steps)
    assert sum(steps) == pytest.approx(0.2)


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("yaw", [0.0, 0.7])
def test_a_bent_swing_down_a_stair_passes_toward_the_other_foot_and_lands_on_its_foothold(side, yaw):
    # Down a 0.15 m stair, heading yaw: the bent path lies `bend` toward the other foot at mid-swing (a left foot to
    # its right, perpendicular to the heading), 64 s^3 (1 - s)^3 of it elsewhere, and ends where the straight one
    # does; its velocity is the derivative of its pose.
    bend, heading = 0.035, np.array([math.cos(yaw), math.sin(yaw)])
    start = Footstep(0.0, 0.0, yaw, side, z=0.3)
    end = Footstep(0.4 * heading[0], 0.4 * heading[1], yaw, side, z=0.15)
    towards_other = np.array([heading[1], -heading[0]]) * (1.0 if side == "left" else -1.0)
    for s in (0.0, 0.2, 0.5, 0.8, 1.0):
        bent, straight = swing_pose(start, end, s, 0.05, bend), swing_pose(start, end, s, 0.05)
        offset = np.subtract(bent[:2], straight[:2])
        assert offset == pytest.approx(bend * 64.0 * s**3 * (1.0 - s) ** 3 * towards_other, abs=1e-12)
        assert bent[2:] == straight[2:]
        h, duration = 1e-6, 0.9
        ahead = swing_pose(start, end, s + h, 0.05, bend) if s < 1.0 else bent
        behind = swing_pose(start, end, s - h, 0.05, bend) if s > 0.0 else bent
        step = (h if s in (0.0, 1.0) else 2.0 * h) * duration
        velocity = swing_velocity(start, end, s, 0.05, duration, bend)
        assert velocity[:2] == pytest.approx(np.subtract(ahead[:2], behind[:2]) / step, abs=1e-5)


def test_only_a_swing_down_a_stair_is_bent():
    flat = (Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.3, 0.1, 0.0, "left"))
    up = (Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.3, 0.1, 0.0, "left", z=0.15))
    for start, end in (flat, up):
        assert swing_pose(start, end, 0.5, 0.05, 0.035) == swing_pose(start, end, 0.5, 0.05)
