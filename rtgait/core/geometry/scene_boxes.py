"""The ground and the obstacles of a scenario as boxes: what MuJoCo builds and what the viewers draw.

One description, two users: the simulator's scene (:mod:`rtgait.sim.terrain`, :mod:`rtgait.sim.obstacles`) and the
replay and live viewer (:mod:`rtgait.viz.replay_scene`, :mod:`rtgait.viz.live_view`) take the same boxes, so what is
drawn is what the soles touch. The floor is a plane at the terrain's lowest level ``z_min`` and every part higher
than it is a box standing on it (:mod:`rtgait.core.geometry.terrain` gives the heights ``h(x, y)``):

* level pieces, ``h = top`` over ``x0 <= x < x1``: a box from ``z_min`` to ``top`` (a stair tread, the landing
  before a step down, a stepping stone, the ground around the stones' pit);
* a slope of angle ``a`` over ``[start, start + length]``: a box :data:`SLOPE_THICKNESS` thick turned by ``-a``
  about the y axis (a right-hand pitch of ``-a`` raises its far end), its top face through ``(start, 0)`` and
  ``(start + length, tan(a) length)``;
* a height field (:class:`~rtgait.core.geometry.heightfield.Heightfield`): not boxes (MuJoCo builds its grid as an
  ``hfield``, :mod:`rtgait.sim.terrain`); where it dips below the level ground at 0, four level boxes frame it;
* an obstacle: its box, centre at half its height on the level ground, turned ``yaw`` about z.

The scene is finite where the height field is not: the level ground before and after the terrain reaches
:data:`REACH` (m) beyond it and :data:`HALF_WIDTH` (m) to each side of the walk's line.

A point of the ground plane that a viewer draws on the terrain (the ZMP) is drawn at :func:`ground_heights`: the
terrain's height under it, ``max(h(x, y), z_low)`` with ``z_low`` the lowest foothold, so that a ZMP passing between
stepping stones in double support stays on their level rather than in the pit.

A box's orientation is ``R = Rz(yaw) Ry(pitch)``, its quaternion ``(w, x, y, z)`` the product of the two half-angle
quaternions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rtgait.core.geometry.terrain import PIT_DEPTH, Flat, Heightfield, Slope, Stairs, Step, SteppingStones, TerrainKind
from rtgait.core.obstacle.box import Obstacle

__all__ = [
    "FLAT_OBSTACLE", "HALF_WIDTH", "OBSTACLE_RGBA", "REACH", "SLOPE_THICKNESS", "TERRAIN_RGBA", "SceneBox",
    "floor_level", "ground_heights", "obstacle_box", "obstacle_box_name", "obstacle_boxes", "terrain_boxes",
]  # fmt: skip

REACH = 5.0
"""How far the level ground extends before the origin and after the terrain's last feature (m)."""
HALF_WIDTH = 2.0
"""Half the width of the terrain across the walk (m)."""
SLOPE_THICKNESS = 0.3
"""Thickness of a slope's box (m): solid under a sole, its underside below the floor."""
TERRAIN_RGBA = (0.62, 0.6, 0.55, 1.0)
"""The terrain's colour (RGBA, 0..1): stone, apart from the floor's lighter grey."""
OBSTACLE_RGBA = (0.55, 0.35, 0.2, 1.0)
"""The obstacles' colour (RGBA, 0..1): wood."""
FLAT_OBSTACLE = 1e-3
"""Half height given to an obstacle of height 0 (a mark on the floor), so that it is a solid to draw (m)."""


@dataclass(frozen=True)
class SceneBox:
    """A box of the scene: centre ``(x, y, z)`` (m), half sizes along its own axes (m), pitch about the world y axis
    and yaw about z (rad): ``R = Rz(yaw) Ry(pitch)``."""

    name: str
    centre: tuple[float, float, float]
    half_size: tuple[float, float, float]
    pitch: float = 0.0
    yaw: float = 0.0

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """``(w, x, y, z)`` of ``Rz(yaw) Ry(pitch)``."""
        cz, sz = math.cos(0.5 * self.yaw), math.sin(0.5 * self.yaw)
        cy, sy = math.cos(0.5 * self.pitch), math.sin(0.5 * self.pitch)
        return cz * cy, 0.0 - sz * sy, cz * sy, sz * cy  # 0.0 - : no -0.0

    @property
    def rotation(self) -> tuple[tuple[float, float, float], ...]:
        """The 3 x 3 rotation ``Rz(yaw) Ry(pitch)``, rows."""
        cz, sz = math.cos(self.yaw), math.sin(self.yaw)
        cy, sy = math.cos(self.pitch), math.sin(self.pitch)
        return (cz * cy, -sz, cz * sy), (sz * cy, cz, sz * sy), (-sy, 0.0, cy)


def _level(
    name: str, x0: float, x1: float, top: float, z_min: float, y: float = 0.0, half_width: float = HALF_WIDTH
) -> SceneBox:
    """A box over ``[x0, x1]`` x ``[y - half_width, y + half_width]`` from ``z_min`` to ``top``."""
    half_height = 0.5 * (top - z_min)
    return SceneBox(name, (0.5 * (x0 + x1), y, z_min + half_height), (0.5 * (x1 - x0), half_width, half_height))


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
    if isinstance(terrain, Heightfield):
        return min(0.0, float(terrain.heights.min()))
    return 0.0


def _pieces(pieces: list[tuple[float, float, float]], z_min: float) -> list[SceneBox]:
    """A level box per ``(x0, x1, top)`` above the floor, named by its place in ``pieces``."""
    return [_level(f"terrain_{i}", x0, x1, top, z_min) for i, (x0, x1, top) in enumerate(pieces) if top > z_min]


def _stairs(terrain: Stairs, z_min: float) -> list[SceneBox]:
    sign = 1.0 if terrain.direction == "up" else -1.0
    last = terrain.start + (terrain.count - 1) * terrain.tread  # the top (or bottom) landing starts here
    pieces = [(-REACH, terrain.start, 0.0)]
    pieces += [
        (terrain.start + (k - 1) * terrain.tread, terrain.start + k * terrain.tread, sign * terrain.riser * k)
        for k in range(1, terrain.count)
    ]
    pieces.append((last, last + REACH, sign * terrain.riser * terrain.count))
    return _pieces(pieces, z_min)


def _slope(terrain: Slope, z_min: float) -> list[SceneBox]:
    a, end = terrain.angle, terrain.start + terrain.length
    rise = math.tan(a) * terrain.length
    boxes = []
    if z_min < 0.0:  # a slope down: the ground before it stands on the lowered floor
        boxes.append(_level("terrain_0", -REACH, terrain.start, 0.0, z_min))
    if rise > z_min:
        boxes.append(_level("terrain_2", end, end + REACH, rise, z_min))
    # The ramp: its top face's midpoint, moved half the thickness down along the face's normal (-sin a, 0, cos a).
    half_length = 0.5 * terrain.length / math.cos(a)
    mid = (terrain.start + 0.5 * terrain.length, 0.5 * rise)
    t = 0.5 * SLOPE_THICKNESS
    centre = (mid[0] + t * math.sin(a), 0.0, mid[1] - t * math.cos(a))
    boxes.append(SceneBox("terrain_1", centre, (half_length, HALF_WIDTH, t), -a))
    return boxes


def _stones(terrain: SteppingStones, z_min: float) -> list[SceneBox]:
    boxes = [
        _level("terrain_0", -REACH, terrain.start, 0.0, z_min),
        _level("terrain_1", terrain.end, terrain.end + REACH, 0.0, z_min),
    ]
    for k in range(terrain.count):
        x0 = terrain.start + k * (terrain.length + terrain.gap)
        for row, y in enumerate((0.5 * terrain.row_spacing, -0.5 * terrain.row_spacing)):
            name = f"terrain_stone_{k}_{'left' if row == 0 else 'right'}"
            boxes.append(_level(name, x0, x0 + terrain.length, 0.0, z_min, y, 0.5 * terrain.width))
    return boxes


def _around_grid(terrain: Heightfield, z_min: float) -> list[SceneBox]:
    """Level ground at 0 around a grid that dips below it: four boxes framing the grid's rectangle."""
    if z_min >= 0.0:
        return []
    (x0, y0), (lx, ly) = terrain.origin, terrain.size
    x1, y1 = x0 + lx, y0 + ly
    side = 0.5 * HALF_WIDTH  # half the width of the strips beside the grid
    return [
        _level("terrain_before", x0 - REACH, x0, 0.0, z_min),
        _level("terrain_after", x1, x1 + REACH, 0.0, z_min),
        _level("terrain_left", x0, x1, 0.0, z_min, y1 + side, side),
        _level("terrain_right", x0, x1, 0.0, z_min, y0 - side, side),
    ]


def terrain_boxes(terrain: TerrainKind) -> tuple[float, list[SceneBox]]:
    """``(z_min, boxes)``: the floor's level (m) and the boxes that build ``terrain`` on it (module docstring)."""
    z_min = floor_level(terrain)
    if isinstance(terrain, Flat):
        return z_min, []
    if isinstance(terrain, Heightfield):
        return z_min, _around_grid(terrain, z_min)
    if isinstance(terrain, Stairs):
        return z_min, _stairs(terrain, z_min)
    if isinstance(terrain, Slope):
        return z_min, _slope(terrain, z_min)
    if isinstance(terrain, SteppingStones):
        return z_min, _stones(terrain, z_min)
    x = terrain.x_step
    return z_min, _pieces([(-REACH, x, 0.0), (x, x + REACH, terrain.height_change)], z_min)


def obstacle_box_name(index: int) -> str:
    """The name of obstacle ``index``'s box (and of its MuJoCo geom)."""
    return f"obstacle_{index}"


def obstacle_box(index: int, obstacle: Obstacle) -> SceneBox:
    """Obstacle ``index`` as a box standing on the level ground (module docstring)."""
    half_height = max(0.5 * obstacle.height, FLAT_OBSTACLE)
    return SceneBox(
        obstacle_box_name(index),
        (obstacle.x, obstacle.y, half_height),
        (0.5 * obstacle.length, 0.5 * obstacle.width, half_height),
        yaw=obstacle.yaw,
    )


def obstacle_boxes(obstacles: Sequence[Obstacle]) -> list[SceneBox]:
    """A box per obstacle, in their order."""
    return [obstacle_box(index, box) for index, box in enumerate(obstacles)]


def ground_heights(terrain: TerrainKind | None, xy: np.ndarray, lowest: float | None = None) -> np.ndarray:
    """Heights (m) at which points ``xy`` ``(n, 2)`` (m) of the ground are drawn on ``terrain`` (``None``: the flat
    floor, 0): ``max(h(x, y), lowest)``, ``lowest`` the lowest foothold's height (m; ``None``: no bound)."""
    xy = np.asarray(xy, dtype=float)
    if terrain is None or isinstance(terrain, Flat):
        return np.zeros(len(xy))
    heights = np.asarray(terrain.height(xy[:, 0], xy[:, 1]), dtype=float).reshape(len(xy))
    return heights if lowest is None else np.maximum(heights, lowest)
