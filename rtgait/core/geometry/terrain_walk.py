"""A walk's footholds placed on terrain, and the checks that each step can be taken there.

:func:`place_walk` gives every footprint ``F[i]`` of a walk the height, pitch and roll of the terrain under it
(:func:`~rtgait.core.geometry.terrain.place_footstep`) and refuses, with one line naming the step:

* a sole cut by an edge of the terrain (a stair nose or a stone's side under it by more than
  :data:`~rtgait.core.geometry.terrain.EDGE_TOLERANCE`), or whose centre is off the surface (over a pit);
* a step beyond the robot's reach (:func:`check_reach`): a horizontal stride longer than ``max_length`` or a height
  change larger than ``max_rise`` (m), the robot's stride limits.

The standing feet ``F[0], F[1]`` must stand on level ground at height 0 (the planner starts from there).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.terrain import EDGE_TOLERANCE, PIT_DEPTH, Terrain, place_footstep, sole_gap

DEFAULT_MAX_RISE = 0.20
"""Largest height change of one step when a robot gives none (m): above the 18.5 cm stair risers humanoid
controllers climb in the field, below a knee's reach for an adult-sized humanoid."""


class TerrainWalkError(ValueError):
    """A walk cannot be placed on its terrain; the message names the step."""


def step_name(index: int) -> str:
    """How messages name footprint ``F[index]``: ``"step k"`` for the landing of step ``k = index - 1``."""
    return f"step {index - 1}" if index >= 2 else f"standing foot F[{index}]"


def check_reach(stance: Footstep, landing: Footstep, step: int, max_length: float, max_rise: float) -> None:
    """``step`` (1-based) from ``stance`` to ``landing`` is within ``max_length`` horizontally (the distance along
    the stance foot's heading) and ``max_rise`` vertically (m), else :class:`TerrainWalkError`."""
    c, s = math.cos(stance.yaw), math.sin(stance.yaw)
    length = abs(c * (landing.x - stance.x) + s * (landing.y - stance.y))
    rise = landing.z - stance.z
    if length > max_length + 1e-9:
        raise TerrainWalkError(
            f"step {step} is {length:.3g} m long: beyond the robot's reach (at most {max_length:g} m per step)"
        )
    if abs(rise) > max_rise + 1e-9:
        way = "up" if rise > 0 else "down"
        raise TerrainWalkError(
            f"step {step} goes {abs(rise):.3g} m {way}: beyond the robot's reach (at most {max_rise:g} m per step)"
        )


def place_walk(
    terrain: Terrain,
    prints: Sequence[Footstep],
    sole: SoleRect,
    max_length: float,
    max_rise: float = DEFAULT_MAX_RISE,
) -> list[Footstep]:
    """Footprints ``prints`` (``F[0..N+1]``) placed on ``terrain``, each step checked (module docstring)."""
    placed = [place_footstep(terrain, foot) for foot in prints]
    for index, foot in enumerate(placed):
        name = step_name(index)
        if index < 2 and not (foot.level and foot.z == 0.0):
            raise TerrainWalkError(
                f"{name} must stand on level ground at height 0: start the terrain farther ahead (got z = "
                f"{foot.z:.3g} m, pitch {foot.pitch:.3g} rad)"
            )
        if getattr(terrain, "kind", None) == "stones" and foot.z <= -PIT_DEPTH + EDGE_TOLERANCE:  # in a stone's pit
            raise TerrainWalkError(f"{name} lands off the surface at x = {foot.x:.3g} m, y = {foot.y:.3g} m")
        lowest, _ = sole_gap(terrain, foot, sole)
        if lowest < -EDGE_TOLERANCE:
            raise TerrainWalkError(
                f"{name} at x = {foot.x:.3g} m lands across an edge of the terrain (it cuts {-lowest:.3g} m into the "
                "sole): move it onto one tread"
            )
        if index >= 2:
            check_reach(placed[index - 1], foot, index - 1, max_length, max_rise)
    return placed


__all__ = ["DEFAULT_MAX_RISE", "TerrainWalkError", "check_reach", "place_walk", "step_name"]
