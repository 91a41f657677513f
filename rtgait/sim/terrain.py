"""The scenario's terrain in the MuJoCo model, built from the same description the planner places footholds on.

The floor plane moves down to the terrain's lowest level ``z_min`` and every part higher than it becomes a box geom
standing on it: the boxes of :func:`~rtgait.core.geometry.scene_boxes.terrain_boxes` (its docstring says how each
terrain is cut into boxes), the same the replay and the live viewer draw. The boxes touch the soles as the floor does
(its contact bits and friction, :func:`~rtgait.sim.contact_model.add_floor`).
"""

from __future__ import annotations

import math

import mujoco

from rtgait.core.geometry.scene_boxes import TERRAIN_RGBA, terrain_boxes
from rtgait.core.geometry.terrain import Terrain, TerrainKind, surface
from rtgait.sim.config import SimConfig
from rtgait.sim.contact_model import FLOOR_BITS, floor_contact_parameters

__all__ = ["add_terrain", "surface_normal"]


def add_terrain(spec: mujoco.MjSpec, terrain: TerrainKind, config: SimConfig, floor: str = "floor") -> list[str]:
    """Lower the floor plane ``floor`` to the terrain's lowest level and add the terrain's boxes to the world, with the
    floor's contact bits and contact parameters; returns the boxes' names."""
    z_min, geoms = terrain_boxes(terrain)
    spec.geom(floor).pos = [0.0, 0.0, z_min]
    for geom in geoms:
        spec.worldbody.add_geom(
            name=geom.name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(geom.half_size),
            pos=list(geom.centre),
            quat=list(geom.quaternion),
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
