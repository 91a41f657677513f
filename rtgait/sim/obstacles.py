"""The scenario's obstacles in the MuJoCo model: one box geom each, standing on the floor.

A box touches the soles as the floor does (the floor's contact bits, :data:`~rtgait.sim.contact_model.FLOOR_BITS`):
a sole that steps on it lands on it, and a swing that sweeps through it is stopped by it. The leg shapes do not touch
it (they touch only each other), so a shin brushing its edge is not a contact: the walk keeps the soles 3 cm and the
swings' ankle paths clear of it (:mod:`rtgait.core.obstacle.detour`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco

from rtgait.core.obstacle.box import Obstacle
from rtgait.sim.contact_model import FLOOR_BITS

__all__ = ["OBSTACLE_RGBA", "add_obstacles", "obstacle_geom_name"]

OBSTACLE_RGBA = (0.55, 0.35, 0.2, 1.0)
"""The boxes' colour: wood, apart from the grey floor."""
_FLAT = 1e-3  # m: half height given to a box of height 0 (a mark on the floor), so that MuJoCo has a solid to draw


def obstacle_geom_name(index: int) -> str:
    """The geom name of obstacle ``index``."""
    return f"obstacle_{index}"


def add_obstacles(spec: mujoco.MjSpec, obstacles: Sequence[Obstacle]) -> list[str]:
    """Add a box geom per obstacle to the world (its centre at half its height); returns their names."""
    names = []
    for index, box in enumerate(obstacles):
        half_height = max(0.5 * box.height, _FLAT)
        name = obstacle_geom_name(index)
        spec.worldbody.add_geom(
            name=name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.5 * box.length, 0.5 * box.width, half_height],
            pos=[box.x, box.y, half_height],
            quat=[math.cos(0.5 * box.yaw), 0.0, 0.0, math.sin(0.5 * box.yaw)],
            contype=FLOOR_BITS[0],
            conaffinity=FLOOR_BITS[1],
            rgba=list(OBSTACLE_RGBA),
        )
        names.append(name)
    return names
