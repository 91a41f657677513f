"""The least lateral detour around an obstacle (rtgait.core.obstacle), checked against geometry computed here: soles
and swings clear of the box, strides within the step limits, and no footprint that could move back toward its
planned place."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, place_footsteps, standing_feet
from rtgait.core.geometry.swing import blend
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.obstacle.detour import Detour, NoDetourError, StrideRules, blocked, plan_detour
from rtgait.core.obstacle.step_over import plan_step_over
from rtgait.core.walk.velocity_command import StepLimits

SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
LIMITS = StepLimits(length=0.29, lateral=0.25, turn=0.6, min_width=0.15)
RULES = StrideRules(LIMITS, step_width=0.19, step_height=0.05, margin=0.03, clearance=0.03)
BOX = Obstacle(x=1.71, y=-0.10, length=0.30, width=0.20, height=0.30)  # across the right foot's line
STEP = 0.24


def straight(steps: int = 16) -> list[Footstep]:
    return place_footsteps(standing_feet(0.19), [Stride(STEP, 0.19)] * steps + [Stride(0.0, 0.19)])


def sole_gap(foot: Footstep, box: Obstacle, xs: np.ndarray | None = None, ys: np.ndarray | None = None) -> float:
    """Smallest distance (m) between the sole of ``foot`` (or of its side with the ankle at each ``xs, ys``) and the
    box, both square to the world axes: positive apart, <= 0 overlapping."""
    assert foot.yaw == 0.0 and box.yaw == 0.0
    xs = np.array([foot.x]) if xs is None else xs
    ys = np.array([foot.y]) if ys is None else ys
    low, high = (-SOLE.inner, SOLE.outer) if foot.side == "left" else (-SOLE.outer, SOLE.inner)
    hl, hw = box.length / 2, box.width / 2
    gaps = np.max([box.x - hl - (xs + SOLE.front), xs - SOLE.back - (box.x + hl),
                   box.y - hw - (ys + high), ys + low - (box.y + hw)], axis=0)  # fmt: skip
    return float(gaps.min())


def swing_gap(start: Footstep, end: Footstep, box: Obstacle) -> float:
    """Smallest sole-to-box distance (m) along a swing, the sole carried by the ankle's quintic blend from lift-off
    to landing (rtgait.core.geometry.swing), sampled every 0.05 % of the swing."""
    k, _ = blend(np.linspace(0.0, 1.0, 2001))
    return sole_gap(end, box, start.x + k * (end.x - start.x), start.y + k * (end.y - start.y))


def check_clear_and_within_limits(before: list[Footstep], detour: Detour, box: Obstacle) -> None:
    prints = detour.footprints
    k0 = detour.first_open
    for j in range(k0 + 1, len(prints)):
        assert sole_gap(prints[j], box) >= RULES.margin - 1e-9
        assert swing_gap(prints[j - 2], prints[j], box) >= RULES.margin - 1e-9
    for i in range(k0, len(prints) - 1):
        width = abs(prints[i + 1].y - prints[i].y)
        sideways = abs(prints[i + 1].y - prints[i - 1].y)
        length = prints[i + 1].x - prints[i].x
        assert LIMITS.min_width - 1e-9 <= width <= 0.19 + LIMITS.lateral + 1e-9
        assert (length / LIMITS.length) ** 2 + (sideways / LIMITS.lateral) ** 2 <= 1.0 + 1e-9
        assert prints[i + 1].x == pytest.approx(before[i + 1].x, abs=1e-12)  # lengths and timing kept


def feasible(prints: list[Footstep], first_open: int, box: Obstacle) -> bool:
    try:
        check_clear_and_within_limits(straight(), Detour("left", tuple(prints), first_open, 0.0, 0, 0.0), box)
    except AssertionError:
        return False
    return True


@pytest.mark.parametrize("first_open", [3, 4])
def test_the_detour_keeps_soles_and_swings_off_the_box_within_the_step_limits(first_open: int) -> None:
    before = straight()
    assert blocked(before, 2, BOX, SOLE, RULES)  # the straight walk steps on it
    detour = plan_detour(before, first_open, BOX, SOLE, RULES, "left")
    check_clear_and_within_limits(before, detour, BOX)
    # The committed footprints stay where they are; the walk still ends with the feet side by side.
    assert detour.footprints[: first_open + 1] == tuple(before[: first_open + 1])
    assert detour.footprints[-1].x == pytest.approx(detour.footprints[-2].x)
    assert detour.moved > 0 and detour.cost == pytest.approx(
        sum((a.y - b.y) ** 2 for a, b in zip(before, detour.footprints, strict=True))
    )


def test_no_footprint_could_move_back_toward_its_planned_place() -> None:
    """The least change: moving any one changed footprint 1 mm back toward where it was planned breaks a bound."""
    before = straight()
    detour = plan_detour(before, 4, BOX, SOLE, RULES, "left")
    prints = list(detour.footprints)
    changed = [j for j in range(len(prints)) if abs(prints[j].y - before[j].y) > 1e-3]
    assert changed
    for j in changed:
        back = list(prints)
        step = math.copysign(1e-3, before[j].y - prints[j].y)
        back[j] = Footstep(prints[j].x, prints[j].y + step, 0.0, prints[j].side)
        assert not feasible(back, 4, BOX), f"F[{j}] could move back"


def test_a_box_beside_the_path_changes_nothing_and_one_too_wide_has_no_detour() -> None:
    before = straight()
    beside = Obstacle(x=1.7, y=0.6, length=0.3, width=0.2, height=0.3)
    assert blocked(before, 2, beside, SOLE, RULES) == []
    wall = Obstacle(x=1.7, y=0.0, length=0.3, width=3.0, height=0.3)
    for side in ("left", "right"):
        with pytest.raises(NoDetourError, match=f"passing {side} needs more sideways reach"):
            plan_detour(before, 4, wall, SOLE, RULES, side)


def test_a_low_box_is_stepped_over_a_high_one_is_not() -> None:
    """A box lower than the swing height less the clearance only keeps the soles off it; a higher one also the
    swings, which here (a box between two landings of the right foot) is what forces the detour."""
    before = straight()
    between = Obstacle(x=1.45, y=-0.095, length=0.10, width=0.10, height=0.30)  # between F[6] and F[8]
    assert blocked(before, 2, between, SOLE, RULES) == [8]  # the swing to F[8] passes over it
    low = Obstacle(x=1.45, y=-0.095, length=0.10, width=0.10, height=0.01)
    assert blocked(before, 2, low, SOLE, RULES) == []


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"width": 0.0}, "obstacle width must be within"),
        ({"height": -0.1}, "obstacle height must be within"),
        ({"yaw": 4.0}, "obstacle yaw must be within"),
        ({"seen_at": math.nan}, "obstacle seen_at must be a finite number"),
        ({"x": True}, "obstacle x must be a finite number"),
    ],
)
def test_bad_obstacles_are_refused_in_one_line(values: dict, message: str) -> None:
    fields = {"x": 1.0, "y": 0.0, "length": 0.3, "width": 0.2, "height": 0.3, **values}
    with pytest.raises(ValueError, match=message) as error:
        Obstacle(**fields)
    assert "\n" not in str(error.value)


def test_a_low_box_is_stepped_over_by_the_least_change_of_step_lengths() -> None:
    before = straight()
    low = Obstacle(x=1.71, y=-0.12, length=0.10, width=0.10, height=0.01)  # under the right foot's line
    assert blocked(before, 5, low, SOLE, RULES) == [8]
    detour = plan_step_over(before, 4, low, SOLE, RULES)
    prints = list(detour.footprints)
    assert detour.side == "over" and detour.moved > 0
    for j in range(5, len(prints)):
        assert sole_gap(prints[j], low) >= RULES.margin - 1e-9
        assert prints[j].y == before[j].y  # only the lengths change
    for i in range(4, len(prints) - 1):
        length = prints[i + 1].x - prints[i].x
        assert 0.0 <= length <= LIMITS.length + 1e-9
    assert prints[-1].x == pytest.approx(prints[-2].x)  # the closing step still brings the feet side by side
    # The least change: no changed footprint could move 1 mm back toward where it was planned.
    for j in (j for j in range(len(prints)) if abs(prints[j].x - before[j].x) > 1e-3):
        back = list(prints)
        back[j] = dataclasses.replace(prints[j], x=prints[j].x + math.copysign(1e-3, before[j].x - prints[j].x))
        lengths_ok = all(-1e-12 <= back[i + 1].x - back[i].x <= LIMITS.length + 1e-9 for i in range(4, len(back) - 1))
        closing_ok = abs(back[-1].x - back[-2].x) < 1e-9
        assert not (lengths_ok and closing_ok and all(sole_gap(f, low) >= RULES.margin - 1e-9 for f in back[5:]))
    high = dataclasses.replace(low, height=0.03)
    with pytest.raises(NoDetourError, match="too high to step over"):
        plan_step_over(before, 4, high, SOLE, RULES)
