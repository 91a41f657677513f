"""The scenario's terrain in the MuJoCo model, built from the same description the planner places footholds on.

The floor plane moves down to the terrain's lowest level ``z_min`` and every part higher than it becomes a box geom
standing on it: the boxes of :func:`~rtgait.core.geometry.scene_boxes.terrain_boxes` (its docstring says how each
terrain is cut into boxes), the same the replay and the live viewer draw. The boxes touch the soles as the floor does
(its contact bits and friction, :func:`~rtgait.sim.contact_model.add_floor`).

A height field (:class:`~rtgait.core.geometry.heightfield.Heightfield`) is a MuJoCo ``hfield`` asset of the same grid
(:func:`hfield_asset`), the boxes framing it where it dips below the level ground. MuJoCo's conventions: the asset's
``size`` is ``(rx, ry, elevation_z, base_z)``, the grid spanning ``2 rx x 2 ry`` around the geom's position, its rows
along y from ``-ry`` and its columns along x from ``-rx``; the data are normalised to ``[0, 1]`` and scaled by
``elevation_z`` above the geom, a box ``base_z`` deep below; each cell is two triangles cut along the diagonal of
increasing x and y, as the planner interpolates. So the geom stands at the grid's centre at its lowest height
``h_min``, ``elevation_z = h_max - h_min`` and the data are ``(H - h_min) / elevation_z``. MuJoCo keeps at most 50
contacts per pair of geoms: a grid much finer than a sole (2 x 2 cm under a 21 x 13 cm sole) loses contacts and the
sole slides; a coarse one (5 cm) leaves them short of the sole's edges (``docs/cli_and_scenarios.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.geometry.scene_boxes import TERRAIN_RGBA, terrain_boxes
from rtgait.core.geometry.terrain import Terrain, TerrainKind, surface
from rtgait.sim.config import SimConfig
from rtgait.sim.contact_model import FLOOR_BITS, floor_contact_parameters

__all__ = ["HFIELD_BASE", "HfieldAsset", "add_terrain", "hfield_asset", "surface_normal"]

HFIELD_BASE = 0.1
"""Depth of a height field's base box below the floor (m): solid under a sole wherever the grid is lowest."""
FLAT_ELEVATION = 1e-6
"""``elevation_z`` of a grid of equal heights (m): MuJoCo needs a height range to scale by."""


@dataclass(frozen=True)
class HfieldAsset:
    """A MuJoCo height field: ``size`` ``(rx, ry, elevation_z, base_z)`` (m), ``data`` ``(nrow, ncol)`` in
    ``[0, 1]`` (row-major, rows along y), and the position of the geom that places it (m)."""

    size: tuple[float, float, float, float]
    data: np.ndarray
    position: tuple[float, float, float]


def hfield_asset(terrain: Heightfield, z_min: float) -> HfieldAsset:
    """The ``hfield`` of ``terrain`` on a floor at ``z_min`` (m), its base reaching :data:`HFIELD_BASE` below it
    (module docstring)."""
    grid = terrain.heights
    low, high = float(grid.min()), float(grid.max())
    elevation = high - low
    data = (grid - low) / elevation if elevation > 0.0 else np.zeros_like(grid)
    rx, ry = 0.5 * terrain.size[0], 0.5 * terrain.size[1]
    centre = (terrain.origin[0] + rx, terrain.origin[1] + ry, low)
    return HfieldAsset((rx, ry, max(elevation, FLAT_ELEVATION), low - z_min + HFIELD_BASE), data, centre)


def add_terrain(spec: mujoco.MjSpec, terrain: TerrainKind, config: SimConfig, floor: str = "floor") -> list[str]:
    """Lower the floor plane ``floor`` to the terrain's lowest level and add the terrain's boxes (and a height field's
    grid) to the world, with the floor's contact bits and contact parameters; returns the geoms' names."""
    z_min, geoms = terrain_boxes(terrain)
    spec.geom(floor).pos = [0.0, 0.0, z_min]
    contact = {"contype": FLOOR_BITS[0], "conaffinity": FLOOR_BITS[1], **floor_contact_parameters(config)}
    names = []
    if isinstance(terrain, Heightfield):
        asset = hfield_asset(terrain, z_min)
        nrow, ncol = asset.data.shape
        spec.add_hfield(name="terrain_hfield", size=list(asset.size), nrow=nrow, ncol=ncol,
                        userdata=asset.data.ravel().tolist())  # fmt: skip
        spec.worldbody.add_geom(name="terrain_grid", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="terrain_hfield",
                                pos=list(asset.position), rgba=list(TERRAIN_RGBA), **contact)  # fmt: skip
        names.append("terrain_grid")
    for geom in geoms:
        spec.worldbody.add_geom(
            name=geom.name,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(geom.half_size),
            pos=list(geom.centre),
            quat=list(geom.quaternion),
            rgba=list(TERRAIN_RGBA),
            **contact,
        )
    return names + [geom.name for geom in geoms]


def surface_normal(terrain: Terrain, x: float, y: float) -> tuple[float, float, float]:
    """The unit normal of ``terrain``'s surface at ``(x, y)`` (m): ``(-h_x, -h_y, 1) / norm`` from the surface's
    pitch and roll (:func:`~rtgait.core.geometry.terrain.surface`, level on an edge)."""
    _, pitch, roll = surface(terrain, x, y, 0.0)
    hx, hy = -math.tan(pitch), math.tan(roll)
    norm = math.sqrt(hx * hx + hy * hy + 1.0)
    return -hx / norm, -hy / norm, 1.0 / norm
