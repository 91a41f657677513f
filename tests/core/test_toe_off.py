"""Toe-off on stairs (rtgait.core.geometry.toe_off): the toe stays on its foothold while the heel is up, the pitch is
continuous, and the planner's ZMP lies in the reduced support (the toe line of the rolled foot with the other foot)
whenever a foot is on its toe; down a stair the swing keeps its toe down past the stance foot and lands flat; a flat
walk is unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.analysis.rollout import Rollout, rollout
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.toe_off import THETA, changes_height, toe_off_feet
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.planner.sample import SampleColumns
from rtgait.scenario.loading import load_scenario

spatial = pytest.importorskip("scipy.spatial")

FRONT = 0.105  # m: Talos's toe ahead of its sole point (the scenarios' sole)
TALOS_ANKLE_PITCH_SPEED = 5.8  # rad/s: leg_*_5_joint's velocity limit in talos_data's URDF


def _walk(name: str) -> Rollout:
    scenario = load_scenario(name)
    return rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole)


def _feet(walk: Rollout) -> list[tuple[tuple[float, ...], tuple[float, ...]]]:
    level = [(0.0, 0.0)] * len(walk.times)
    left = [(*a, *t) for a, t in zip(walk.values[:, SampleColumns.left_foot].tolist(), level, strict=True)]
    right = [(*b, *t) for b, t in zip(walk.values[:, SampleColumns.right_foot].tolist(), level, strict=True)]
    zmp = walk.values[:, SampleColumns.zmp].tolist()
    return [toe_off_feet(walk.footprints, FRONT, a, b, z) for a, b, z in zip(left, right, zmp, strict=True)]


def _corners(foot: tuple[float, ...], sole: tuple[float, float, float]) -> np.ndarray:
    """The sole rectangle's corners (x, y) of a level foot at ``foot``: ``sole = (front, back, half width)``."""
    c, s = math.cos(foot[3]), math.sin(foot[3])
    front, back, half = sole
    local = [(front, half), (front, -half), (-back, -half), (-back, half)]
    return np.array([(foot[0] + c * u - s * v, foot[1] + s * u + c * v) for u, v in local])


def _toe_line(foot: tuple[float, ...], half: float) -> np.ndarray:
    """Both ends (x, y) of a rolled foot's toe line: the sole's front edge, ``FRONT`` ahead of the level sole point."""
    c, s = math.cos(foot[3]), math.sin(foot[3])
    x = foot[0] - FRONT * math.cos(foot[4]) * c + FRONT * c  # back to the level sole point, then to the toe
    y = foot[1] - FRONT * math.cos(foot[4]) * s + FRONT * s
    return np.array([(x - s * half, y + c * half), (x + s * half, y - c * half)])


def _inside(point: np.ndarray, vertices: np.ndarray) -> bool:
    hull = spatial.ConvexHull(vertices)
    return bool((hull.equations[:, :2] @ point + hull.equations[:, 2] <= 1e-9).all())


def test_a_flat_walk_is_unchanged() -> None:
    walk = _walk("fig8")
    assert not changes_height(walk.footprints)
    for (left, right), a, b in zip(
        _feet(walk), walk.values[:, SampleColumns.left_foot], walk.values[:, SampleColumns.right_foot], strict=True
    ):
        assert left == (*a, 0.0, 0.0) and right == (*b, 0.0, 0.0)


def test_a_single_step_up_rolls_the_rear_foot_about_its_toe() -> None:
    prints = [
        Footstep(0.0, -0.1, 0.0, "right"),
        Footstep(0.0, 0.1, 0.0, "left"),
        Footstep(0.3, -0.1, 0.0, "right", z=0.15),
    ]
    rear, front = (0.0, 0.1, 0.0, 0.0, 0.0, 0.0), (0.3, -0.1, 0.15, 0.0, 0.0, 0.0)
    # ZMP behind the rear toe: the heel stays down; on the front foot (the lift-off): fully rolled.
    assert toe_off_feet(prints, FRONT, rear, (0.0, -0.1, 0.0, 0.0, 0.0, 0.0), (0.05, 0.0))[0] == rear
    prints = [prints[0], prints[1], Footstep(0.3, -0.1, 0.0, "right"), Footstep(0.6, 0.1, 0.0, "left", z=0.15)]
    rolled, same = toe_off_feet(prints, FRONT, rear, (*front[:2], 0.0, 0.0, 0.0, 0.0), (0.3, -0.1))
    assert same == (0.3, -0.1, 0.0, 0.0, 0.0, 0.0)
    assert rolled[4] == pytest.approx(THETA)
    # The sole point rose and moved forward on a circle about the toe line at (FRONT, z = 0).
    assert rolled[0] - FRONT == pytest.approx(-FRONT * math.cos(THETA))
    assert rolled[2] == pytest.approx(FRONT * math.sin(THETA))


@pytest.mark.parametrize("name", ["stairs-up", "stairs-down"])
def test_on_stairs_the_zmp_stays_in_the_support_left_while_a_heel_is_up(name: str) -> None:
    walk = _walk(name)
    feet = _feet(walk)
    half = 0.065  # Talos's sole, the scenarios' (inner = outer)
    zmp = walk.values[:, SampleColumns.zmp]
    rolled_ticks = 0
    for k, (left, right) in enumerate(feet):
        if walk.support[k] != "double":
            continue
        pitched = [foot for foot in (left, right) if foot[4] > 1e-9]
        if not pitched:
            continue
        assert len(pitched) == 1, f"both heels up at t={walk.times[k]:.3f} s"
        rolled_ticks += 1
        flat = right if pitched[0] is left else left
        support = np.vstack([_toe_line(pitched[0], half), _corners(flat, (FRONT, FRONT, half))])
        assert _inside(zmp[k], support), f"ZMP {zmp[k]} outside the toe-line support at t={walk.times[k]:.3f} s"
        # The toe stays on its foothold: its height is the flat sole's.
        toe_z = pitched[0][2] - FRONT * math.sin(pitched[0][4])
        assert any(abs(toe_z - step.z) < 1e-9 for step in walk.footprints)
    assert rolled_ticks > 0  # the stairs do make the heels rise


def test_the_pitch_is_continuous_and_bounded() -> None:
    walk = _walk("stairs-up")
    pitch = np.array([[left[4], right[4]] for left, right in _feet(walk)])
    assert pitch.max() == pytest.approx(THETA, abs=1e-6)
    assert pitch.min() >= 0.0
    # Never a jump between ticks: the sole turns slower than Talos's ankle pitch joint may (its URDF's limit).
    dt = walk.times[1] - walk.times[0]
    assert np.abs(np.diff(pitch, axis=0)).max() / dt < TALOS_ANKLE_PITCH_SPEED


def test_down_a_stair_the_swing_keeps_its_toe_down_and_lands_flat() -> None:
    walk = _walk("stairs-down")
    feet = _feet(walk)
    prints = walk.footprints
    phase = walk.phase.astype(int)
    descents = 0
    for q in range(3, int(phase.max()), 2):  # single supports 2i - 1: step i swings F[i - 1] to F[i + 1]
        i = (q + 1) // 2
        if i + 1 >= len(prints) or prints[i + 1].z > prints[i - 1].z - 0.01:
            continue
        descents += 1
        ticks = np.flatnonzero(phase == q)
        side = 0 if prints[i + 1].side == "left" else 1
        start, end = prints[i - 1], prints[i + 1]
        for k in ticks:
            foot = feet[k][side]
            u = (foot[0] - FRONT + FRONT * math.cos(foot[4]) - start.x) / (end.x - start.x)  # the level sole point
            if 0.3 <= u <= 0.7:
                assert foot[4] == pytest.approx(THETA)  # toe down as it passes the stance foot
        assert feet[ticks[-1]][side][4] == pytest.approx(0.0, abs=1e-9)  # flat at the touch-down
        landed = np.flatnonzero(phase == q + 1)
        assert max(feet[k][side][4] for k in landed) == 0.0  # and flat through the double support that follows
    assert descents >= 5
