"""Step adjustment on terrain: a moved landing stays on its own tread or stone and takes the terrain's height and
tilt where it lands (rtgait.core.geometry.terrain_landing).

Independent truths: the terrain's own geometry (a tread spans ``[start + k tread, start + (k + 1) tread)``, a stone
``length`` x ``width`` around its centre, a ramp rises ``tan(angle)`` per metre), and the sole's rectangle.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.terrain import Flat, Slope, Stairs, SteppingStones, place_footstep
from rtgait.core.geometry.terrain_landing import SOLE_GRID, land_on_terrain
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario

SOLE = SoleRect(0.105, 0.105, 0.065, 0.065)  # Talos's, as the built-in terrain scenarios have it
STAIRS_UP = Stairs(riser=0.15, tread=0.25, count=6, direction="up", start=0.375)
STAIRS_DOWN = dataclasses.replace(STAIRS_UP, direction="down")
RAMP = Slope(angle=math.radians(10.0), length=2.0, start=0.5)


def _tread(stairs: Stairs, x: float) -> tuple[float, float]:
    """The tread under ``x``: its near and far edge (m)."""
    k = math.floor((x - stairs.start) / stairs.tread)
    return stairs.start + k * stairs.tread, stairs.start + (k + 1) * stairs.tread


@pytest.mark.parametrize("stairs", [STAIRS_UP, STAIRS_DOWN], ids=["up", "down"])
def test_a_move_toward_the_stair_nose_is_clamped_inside_the_tread_at_its_height(stairs: Stairs) -> None:
    nominal = place_footstep(stairs, Footstep(0.75, 0.085, 0.0, "left"))  # mid-tread, 2 cm from each edge
    near, far = _tread(stairs, nominal.x)
    landed = land_on_terrain(stairs, nominal, nominal.x + 0.12, nominal.y + 0.04, SOLE)
    foot = landed.footprint
    assert landed.clamped and landed.asked == pytest.approx(math.hypot(0.12, 0.04))
    assert foot.x + SOLE.front < far, "the toes stay short of the nose"
    assert foot.x + SOLE.front > far - SOLE_GRID, "the move is shrunk no more than the sole's grid"
    assert foot.y == pytest.approx(nominal.y + 0.04), "the tread runs across the stairs: the lateral move is kept"
    assert foot.z == pytest.approx(stairs.height(foot.x, foot.y)) == pytest.approx(nominal.z)
    assert (foot.pitch, foot.roll) == (0.0, 0.0)
    back = land_on_terrain(stairs, nominal, nominal.x - 0.1, nominal.y, SOLE).footprint
    assert near - 1e-9 <= back.x - SOLE.back < near + SOLE_GRID, "backward: the heel stops at the tread's near edge"


def test_a_move_within_the_tread_is_taken_whole() -> None:
    nominal = place_footstep(STAIRS_UP, Footstep(0.75, -0.085, 0.0, "right"))
    landed = land_on_terrain(STAIRS_UP, nominal, nominal.x + 0.01, nominal.y - 0.1, SOLE)
    assert not landed.clamped
    assert (landed.footprint.x, landed.footprint.y) == pytest.approx((nominal.x + 0.01, nominal.y - 0.1))
    assert landed.footprint.z == nominal.z


@pytest.mark.parametrize("ramp", [RAMP, dataclasses.replace(RAMP, angle=-RAMP.angle)], ids=["up", "down"])
def test_on_a_slope_the_moved_landing_s_height_follows_the_slope(ramp: Slope) -> None:
    nominal = place_footstep(ramp, Footstep(1.2, 0.085, 0.0, "left"))
    dx = 0.08
    landed = land_on_terrain(ramp, nominal, nominal.x + dx, nominal.y + 0.03, SOLE)
    foot = landed.footprint
    assert not landed.clamped, "a ramp is one surface: nothing to clamp mid-ramp"
    assert foot.z - nominal.z == pytest.approx(math.tan(ramp.angle) * dx, rel=1e-6)
    assert foot.pitch == pytest.approx(-ramp.angle) and foot.roll == 0.0


def test_the_terrain_s_height_change_is_added_to_a_foothold_offset_from_it() -> None:
    # A foothold re-anchored 4 mm below the ramp (the walk's frame follows the measured feet) keeps that offset.
    placed = place_footstep(RAMP, Footstep(1.2, 0.085, 0.0, "left"))
    nominal = dataclasses.replace(placed, z=placed.z - 0.004)
    foot = land_on_terrain(RAMP, nominal, nominal.x - 0.05, nominal.y, SOLE).footprint
    assert foot.z == pytest.approx(RAMP.height(foot.x, foot.y) - 0.004)


def test_a_move_off_a_stepping_stone_is_kept_on_the_stone() -> None:
    stones = SteppingStones(length=0.2, width=0.15, gap=0.1, count=6, row_spacing=0.19, start=0.2)
    nominal = place_footstep(stones, Footstep(stones.centre(2), 0.095, 0.0, "left"))
    landed = land_on_terrain(stones, nominal, nominal.x + 0.15, nominal.y + 0.06, SOLE)
    foot = landed.footprint
    # The 13 cm wide sole on the 15 cm stone: 1 cm to either side; the 21 cm sole on the 20 cm stone: its 5 mm
    # overhang at each end may shift, within the sole's grid.
    assert foot.y + SOLE.outer <= 0.095 + 0.5 * stones.width + 1e-9
    assert abs(foot.x - nominal.x) <= 0.5 * (SOLE.front + SOLE.back - stones.length) + SOLE_GRID
    assert foot.z == 0.0, "on the stone's top, not in the pit"


def test_on_the_flat_floor_the_move_is_taken_whole_and_level() -> None:
    nominal = Footstep(0.3, 0.1, 0.2, "left")
    landed = land_on_terrain(Flat(), nominal, 0.5, 0.25, SOLE)
    assert not landed.clamped and landed.footprint == Footstep(0.5, 0.25, 0.2, "left")
    # A move within round-off is taken to the coordinates asked, as the flat floor's step adjustment takes them.
    tread = place_footstep(STAIRS_UP, Footstep(0.75, 0.085, 0.0, "left"))
    y = float(np.nextafter(tread.y, 1.0))
    assert land_on_terrain(STAIRS_UP, tread, tread.x, y, SOLE).footprint.y == y != tread.y


def _pushed(name: str, push: tuple[float, float], with_terrain: bool) -> tuple[OnlinePlanner, object]:
    """The built-in scenario ``name`` planned from the measured state, pushed mid single support of step 3 (its
    landing, on the second tread or on the ramp, moves)."""
    scenario = load_scenario(name)
    limits = SteppingLimits(max_length=0.29, min_width=0.15, max_width=0.4)  # Talos's [stepping]
    adjust = StepAdjustment(scenario.sole, limits, terrain=scenario.placed_on if with_terrain else None)
    planner = OnlinePlanner(
        dataclasses.replace(scenario.planner_config(), feedback="measured", step_adjustment=adjust), scenario.strides()
    )
    planner.start(0.0)
    dt, t_push = 0.005, planner.phase_start(5) + 0.3 * scenario.timing.single_support
    for t in np.arange(0.0, t_push, dt):
        s = planner.sample(float(t))
        planner.observe(float(t), s.cog[:2], s.cog_vel[:2])
    s = planner.sample(t_push)
    planner.observe(t_push, s.cog[:2], s.cog_vel[:2] + np.asarray(push))
    planner.replan_now(t_push)
    return planner, scenario.terrain.terrain


def test_the_planner_keeps_a_landing_moved_toward_the_stair_nose_on_its_tread() -> None:
    plain, stairs = _pushed("stairs-up", (0.25, 0.0), with_terrain=False)
    moved = plain.footprints()[plain.step_adjustments[-1].step + 1]
    assert stairs.height(moved.x + SOLE.front, moved.y) > moved.z, "without the terrain the toes go past the nose"
    planner, _ = _pushed("stairs-up", (0.25, 0.0), with_terrain=True)
    decision = planner.step_adjustments[-1]
    foot = planner.footprints()[decision.step + 1]
    assert (foot.x, foot.y) == pytest.approx(decision.landing)
    assert decision.landing[0] > decision.nominal[0], "still moved toward the push"
    assert foot.x + SOLE.front < _tread(stairs, decision.nominal[0])[1]
    assert foot.z == pytest.approx(stairs.height(foot.x, foot.y)) == pytest.approx(0.3)
    assert "kept on its foothold's surface" in decision.reason


def test_the_planner_gives_a_landing_moved_up_a_ramp_the_ramp_s_height() -> None:
    planner, ramp = _pushed("slope-up", (0.25, 0.0), with_terrain=True)
    decision = planner.step_adjustments[-1]
    foot = planner.footprints()[decision.step + 1]
    assert decision.landing[0] - decision.nominal[0] > 0.02
    assert foot.z == pytest.approx(ramp.height(foot.x, foot.y), abs=1e-9)
    assert foot.pitch == pytest.approx(-ramp.angle)
