"""The scenario's terrain in the MuJoCo model, built from the same description the planner places footholds on.

The floor plane moves down to the terrain's lowest level ``z_min`` and every part higher than it becomes a box geom
standing on it (:mod:`rtgait.core.geometry.terrain` gives the heights ``h(x, y)``):

* level pieces, ``h = top`` over ``x0 <= x < x1``: a box from ``z_min`` to ``top`` (a stair tread, the landing
  before a step down, a stepping stone, the ground around the stones' pit);
* a slope of angle ``a`` over ``[start, start + length]``: a box :data:`SLOPE_THICKNESS` thick turned by ``-a``
  about the y axis (a right-hand pitch of ``-a`` raises its far end), its top face through ``(start, 0)`` and
  ``(start + length, tan(a) length)``.

The scene is finite where the height field is not: the level ground before and after the terrain reaches
:data:`REACH` (m) beyond it and :data:`HALF_WIDTH` (m) to each side of the walk's line. The boxes touch the soles as
the floor does (its contact bits and friction, :func:`~rtgait.sim.contact_model.add_floor`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from rtgait.core.geometry.terrain import (
    PIT_DEPTH,
    Flat,
    Slope,
    Stairs,
    Step,
    SteppingStones,
    Terrain,
    TerrainKind,
    surface,
)
from rtgait.sim.config import SimConfig
from rtgait.sim.contact_model import FLOOR_BITS, floor_contact_parameters

__all__ = [
    "HALF_WIDTH",
    "REACH",
    "SLOPE_THICKNESS",
    "TERRAIN_RGBA",
    "TerrainGeom",
    "add_terrain",
    "floor_level",
    "terrain_geoms",
]

REACH = 5.0
"""How far the level ground extends before the origin and after the terrain's last feature (m)."""
HALF_WIDTH = 2.0
"""Half the width of the terrain across the walk (m)."""
SLOPE_THICKNESS = 0.3
"""Thickness of a slope's box (m): solid under a sole, its underside below the floor."""
TERRAIN_RGBA = (0.62, 0.6, 0.55, 1.0)
"""The terrain's colour: stone, apart from the floor's lighter grey."""


@dataclass(frozen=True)
class TerrainGeom:
    """A box of the terrain: centre ``(x, y, z)`` (m), half sizes (m) and pitch about the world y axis (rad)."""

    name: str
    centre: tuple[float, float, float]
    half_size: tuple[float, float, float]
    pitch: float = 0.0


def _level(
    name: str, x0: float, x1: float, top: float, z_min: float, y: float = 0.0, half_width: float = HALF_WIDTH
) -> TerrainGeom:
    """A box over ``[x0, x1]`` x ``[y - half_width, y + half_width]`` from ``z_min`` to ``top``."""
    half_height = 0.5 * (top - z_min)
    return TerrainGeom(name, (0.5 * (x0 + x1), y, z_min + half_height), (0.5 * (x1 - x0), half_width, half_height))


def floor_level(terrain: TerrainKind) -> float:
    """The lowest level of ``terrain`` (m): where the floor plane goes."""
    if isinstance(terrain, Stairs):
        return -terrain.riser * terrain.count if terrain.direction == "down" else 0.0
    if isinstance(terrain, Slope):
        return min(0.0, math.tan(terrain.angle) * terrain.length)
    if isinstance(terrain, Step):
        return min(0.0, terrain.height_change)
    if isinstance(terrain, SteppingStones):
        return -PIT_DEPTH
    return 0.0


def _stairs(terrain: Stairs, z_min: float) -> list[TerrainGeom]:
    sign = 1.0 if terrain.direction == "up" else -1.0
    last = terrain.start + (terrain.count - 1) * terrain.tread  # the top (or bottom) landing starts here
    pieces = [(-REACH, terrain.start, 0.0)]
    pieces += [
        (terrain.start + (k - 1) * terrain.tread, terrain.start + k * terrain.tread, sign * terrain.riser * k)
        for k in range(1, terrain.count)
    ]
    pieces.append((last, last + REACH, sign * terrain.riser * terrain.count))
    return [_level(f"terrain_{i}", x0, x1, top, z_min) for i, (x0, x1, top) in enumerate(pieces) if top > z_min]


def _slope(terrain: Slope, z_min: float) -> list[TerrainGeom]:
    a, end = terrain.angle, terrain.start + terrain.length
    rise = math.tan(a) * terrain.length
    geoms = []
    if z_min < 0.0:  # a slope down: the ground before it stands on the lowered floor
        geoms.append(_level("terrain_0", -REACH, terrain.start, 0.0, z_min))
    if rise > z_min:
        geoms.append(_level("terrain_2", end, end + REACH, rise, z_min))
    # The ramp: its top face's midpoint, moved half the thickness down along the face's normal (-sin a, 0, cos a).
    half_length = 0.5 * terrain.length / math.cos(a)
    mid = (terrain.start + 0.5 * terrain.length, 0.5 * rise)
    t = 0.5 * SLOPE_THICKNESS
    centre = (mid[0] + t * math.sin(a), 0.0, mid[1] - t * math.cos(a))
    geoms.append(TerrainGeom("terrain_1", centre, (half_length, HALF_WIDTH, t), -a))
    return geoms


def _stones(terrain: SteppingStones, z_min: float) -> list[TerrainGeom]:
    geoms = [
        _level("terrain_0", -REACH, terrain.start, 0.0, z_min),
        _level("terrain_1", terrain.end, terrain.end + REACH, 0.0, z_min),
    ]
    for k in range(terrain.count):
        x0 = terrain.start + k * (terrain.length + terrain.gap)
        for row, y in enumerate((0.5 * terrain.row_spacing, -0.5 * terrain.row_spacing)):
            name = f"terrain_stone_{k}_{'left' if row == 0 else 'right'}"
            geoms.append(_level(name, x0, x0 + terrain.length, 0.0, z_min, y, 0.5 * terrain.width))
    return geoms


def terrain_geoms(terrain: TerrainKind) -> tuple[float, list[TerrainGeom]]:
    """``(z_min, boxes)``: the floor's level (m) and the boxes that build ``terrain`` on it (module docstring)."""
    z_min = floor_level(terrain)
    if isinstance(terrain, Flat):
        return z_min, []
    if isinstance(terrain, Stairs):
        return z_min, _stairs(terrain, z_min)
    if isinstance(terrain, Slope):
        return z_min, _slope(terrain, z_min)
    if isinstance(terrain, SteppingStones):
        return z_min, _stones(terrain, z_min)
    x = terrain.x_step
    pieces = [(-REACH, x, 0.0), (x, x + REACH, terrain.height_change)]
    return z_min, [_level(f"terrain_{i}", x0, x1, top, z_min) for i, (x0, x1, top) in enumerate(pieces) if top > z_min]


def add_terrain(spec: mujoco.MjSpec, terrain: TerrainKind, config: SimConfig, floor: str = "floor") -> list[str]:
    """Lower the floor plane ``floor`` to the terrain's lowest level and add the terrain's boxes to the world, with the
    floor's contact bits and contact parameters; returns the boxes' names."""
    z_min, geoms = terrain_geoms(terrain)
    spec.geom(floor).pos = [0.0, 0.0, z_min]
    for geom in geoms:
        spec.worldbody.add_geom(
            name=geom.name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(geom.half_size),
            pos=list(geom.centre),
            quat=[math.cos(0.5 * geom.pitch), 0.0, math.sin(0.5 * geom.pitch), 0.0],
            contype=FLOOR_BITS[0],
            conaffinity=FLOOR_BITS[1],
            rgba=list(TERRAIN_RGBA),
            **floor_contact_parameters(config),
        )
    return [geom.name for geom in geoms]


def surface_normal(terrain: Terrain, x: float, y: float) -> tuple[float, float, float]:
    """The unit normal of ``terrain``'s surface at ``(x, y)`` (m): ``(-h_x, -h_y, 1) / norm`` from the surface's
    pitch and roll (:func:`~rtgait.core.geometry.terrain.surface`, level on an edge)."""
    _, pitch, roll = surface(terrain, x, y, 0.0)
    hx, hy = -math.tan(pitch), math.tan(roll)
    norm = math.sqrt(hx * hx + hy * hy + 1.0)
    return -hx / norm, -hy / norm, 1.0 / norm
