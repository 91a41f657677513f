"""The scenario's obstacles in the MuJoCo model: one box geom each, standing on the floor
(:func:`~rtgait.core.geometry.scene_boxes.obstacle_box`, the box the replay draws too).

A box touches the soles as the floor does (the floor's contact bits, :data:`~rtgait.sim.contact_model.FLOOR_BITS`):
a sole that steps on it lands on it, and a swing that sweeps through it is stopped by it. The leg shapes do not touch
it (they touch only each other), so a shin brushing its edge is not a contact: the walk keeps the soles 3 cm and the
swings' ankle paths clear of it (:mod:`rtgait.core.obstacle.detour`).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

from rtgait.core.geometry.scene_boxes import OBSTACLE_RGBA, obstacle_box_name, obstacle_boxes
from rtgait.core.obstacle.box import Obstacle
from rtgait.sim.contact_model import FLOOR_BITS

__all__ = ["OBSTACLE_RGBA", "add_obstacles", "obstacle_geom_name"]

obstacle_geom_name = obstacle_box_name
"""The geom name of obstacle ``index`` (:func:`~rtgait.core.geometry.scene_boxes.obstacle_box_name`)."""


def add_obstacles(spec: mujoco.MjSpec, obstacles: Sequence[Obstacle]) -> list[str]:
    """Add a box geom per obstacle to the world (its centre at half its height); returns their names."""
    boxes = obstacle_boxes(obstacles)
    for box in boxes:
        spec.worldbody.add_geom(
            name=box.name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(box.half_size),
            pos=list(box.centre),
            quat=list(box.quaternion),
            contype=FLOOR_BITS[0],
            conaffinity=FLOOR_BITS[1],
            rgba=list(OBSTACLE_RGBA),
        )
    return [box.name for box in boxes]
