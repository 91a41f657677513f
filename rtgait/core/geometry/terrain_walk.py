"""A walk's footholds placed on terrain, and the checks that each step can be taken there.

:func:`place_walk` gives every footprint ``F[i]`` of a walk the height, pitch and roll of the terrain under it
(:func:`~rtgait.core.geometry.terrain.place_footstep`) and refuses, with one line naming the step:

* a sole cut by an edge of the terrain (a stair nose or a stone's side under it by more than
  :data:`~rtgait.core.geometry.terrain.EDGE_TOLERANCE`), or whose centre is off the surface (over a pit);
* on a height field (:class:`~rtgait.core.geometry.heightfield.Heightfield`), whose footholds take the least-squares
  plane under the sole (:func:`sole_plane`): a sole across a discontinuity or on ground too rough for it, the plane
  missing the terrain somewhere under the sole by more than ``EDGE_TOLERANCE``, and a plane steeper than
  :data:`~rtgait.core.limits.MAX_SURFACE_TILT`;
* a step beyond the robot's reach (:func:`check_reach`): a horizontal stride longer than ``max_length`` or a height
  change larger than ``max_rise`` (m), the robot's stride limits.

The standing feet ``F[0], F[1]`` must stand on level ground at height 0 (the planner starts from there).

:func:`sole_plane` fits ``z = a + b u + c v`` by least squares to the terrain's heights at a grid of
:data:`PLANE_SAMPLES` points over the sole (``u`` along the foot's heading, ``v`` to its left, m from the foot
frame): the foothold's height is ``a``, its pitch ``-atan(b)`` and roll ``atan(c)`` (the signs of
:func:`~rtgait.core.geometry.terrain.surface`), and the fit's largest ``|residual|`` says how far the terrain strays
from a flat sole laid on it (m).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.geometry.terrain import EDGE_TOLERANCE, PIT_DEPTH, Terrain, place_footstep, sole_gap, sole_points
from rtgait.core.limits import MAX_SURFACE_TILT

DEFAULT_MAX_RISE = 0.20
"""Largest height change of one step when a robot gives none (m): above the 18.5 cm stair risers humanoid
controllers climb in the field, below a knee's reach for an adult-sized humanoid."""


PLANE_SAMPLES = (9, 5)
"""Points of the sole's grid along its length and across it for :func:`sole_plane`: several per grid cell of a few
centimetres under a 20 cm sole."""


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


def sole_plane(terrain: Terrain, foot: Footstep, sole: SoleRect) -> tuple[float, float, float, float]:
    """``(z, pitch, roll, residual)`` (m, rad, rad, m): the least-squares plane of ``terrain`` under the sole of
    ``foot`` (its ``x, y, yaw`` and side; ``sole`` around the foot frame), its height at the foot frame and the fit's
    largest ``|residual|`` (module docstring)."""
    points = sole_points(Footstep(foot.x, foot.y, foot.yaw, foot.side), sole, *PLANE_SAMPLES)
    c, s = math.cos(foot.yaw), math.sin(foot.yaw)
    dx, dy = points[:, 0] - foot.x, points[:, 1] - foot.y
    basis = np.column_stack((np.ones(len(points)), c * dx + s * dy, c * dy - s * dx))
    ground = np.asarray(terrain.height(points[:, 0], points[:, 1]), float)
    if not ground.any():  # level ground at 0 (around a grid): exactly, not to the fit's round-off
        return 0.0, 0.0, 0.0, 0.0
    coefficients = np.linalg.lstsq(basis, ground, rcond=None)[0]
    residual = float(np.abs(ground - basis @ coefficients).max())
    a, b, c_lateral = (float(v) for v in coefficients)
    # + 0.0 and 0.0 -: no -0.0 in outputs (a level fit's zero slopes).
    return a + 0.0, 0.0 - math.atan(b), math.atan(c_lateral) + 0.0, residual


def _fit_footstep(terrain: Terrain, foot: Footstep, sole: SoleRect, name: str) -> Footstep:
    """``foot`` on the least-squares plane under its sole, or :class:`TerrainWalkError` naming it (``name``)."""
    z, pitch, roll, residual = sole_plane(terrain, foot, sole)
    where = f"{name} at x = {foot.x:.3g} m, y = {foot.y:.3g} m"
    if residual > EDGE_TOLERANCE:
        raise TerrainWalkError(
            f"{where} lands across a discontinuity or on ground too rough for the sole: the best plane under it misses "
            f"the terrain by {residual:.3g} m (at most {EDGE_TOLERANCE:g} m); move it"
        )
    if max(abs(pitch), abs(roll)) > MAX_SURFACE_TILT:
        raise TerrainWalkError(
            f"{where} lands on ground tilted {max(abs(pitch), abs(roll)):.3g} rad: steeper than a flat sole stands on "
            f"(at most {MAX_SURFACE_TILT:g} rad)"
        )
    return replace(foot, z=z, pitch=pitch, roll=roll)


def place_walk(
    terrain: Terrain,
    prints: Sequence[Footstep],
    sole: SoleRect,
    max_length: float,
    max_rise: float = DEFAULT_MAX_RISE,
) -> list[Footstep]:
    """Footprints ``prints`` (``F[0..N+1]``) placed on ``terrain``, each step checked (module docstring)."""
    if isinstance(terrain, Heightfield):
        placed = [_fit_footstep(terrain, foot, sole, step_name(index)) for index, foot in enumerate(prints)]
    else:
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


__all__ = [
    "DEFAULT_MAX_RISE", "PLANE_SAMPLES", "TerrainWalkError", "check_reach", "place_walk", "sole_plane", "step_name",
]  # fmt: skip
