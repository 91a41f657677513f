"""The ground of the 3D replay besides the flat floor: the terrain's boxes and the obstacles (meshcat paths under
``/rtgait/terrain`` and ``/rtgait/obstacles``, :mod:`rtgait.viz.replay_scene`).

The boxes are those MuJoCo's scene is built of (:mod:`rtgait.core.geometry.scene_boxes`), in the same colours: a
terrain box with its edges as dark lines (a stair's nose shows from any side, the faces being one colour); a height
field's grid as the triangles MuJoCo collides (two per cell, cut along the diagonal of increasing x and y,
:mod:`rtgait.core.geometry.heightfield`), one mesh; an
obstacle faint from the start (it stands in the physics all along) and solid from the time the walk sees it, its
solid box on a node whose position is animated: :data:`HIDDEN_DEPTH` under the scene before that, in place after.
"""

from __future__ import annotations

from dataclasses import dataclass

import meshcat
import meshcat.geometry as mg
import meshcat.transformations as mtf
import numpy as np

from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.geometry.scene_boxes import OBSTACLE_RGBA, TERRAIN_RGBA, SceneBox, terrain_boxes
from rtgait.core.geometry.terrain import Flat, TerrainKind

__all__ = ["FLAT_FLOOR", "OBSTACLE_COLOR", "TERRAIN_COLOR", "Ground", "draw_obstacles", "draw_terrain", "grid_mesh"]

GHOST_OPACITY = 0.3  # an obstacle not seen yet: in the physics, not yet in the walk's plan
GHOST_SHRINK = 0.001  # m: the faint box sits just inside the solid one, which hides it once the obstacle is seen
HIDDEN_DEPTH = 1000.0  # m: where an obstacle not yet seen waits, under the scene and out of the camera's view


def _hex(rgba: tuple[float, ...]) -> int:
    """0xRRGGBB of an RGBA colour (0..1)."""
    r, g, b = (round(255 * c) for c in rgba[:3])
    return (r << 16) | (g << 8) | b


TERRAIN_COLOR = _hex(TERRAIN_RGBA)
TERRAIN_EDGE_COLOR = 0x3A3833  # the boxes' edges, darker: a stair's nose shows from any side
OBSTACLE_COLOR = _hex(OBSTACLE_RGBA)


@dataclass(frozen=True)
class Ground:
    """What the robot walks on besides the flat floor: the ``terrain`` (``None``: the flat floor) and the
    ``obstacles``, each a box and when the walk sees it (s on the replay's clock, from 0)."""

    terrain: TerrainKind | None = None
    obstacles: tuple[tuple[SceneBox, float], ...] = ()

    @property
    def flat(self) -> bool:
        return self.terrain is None or isinstance(self.terrain, Flat)


FLAT_FLOOR = Ground()
"""The flat floor and no obstacle: a replay without ground."""


def _box_pose(box: SceneBox) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = box.rotation
    pose[:3, 3] = box.centre
    return pose


def _solid(box: SceneBox, shrink: float = 0.0) -> mg.Box:
    return mg.Box([2.0 * (h - shrink) for h in box.half_size])


def draw_terrain(vis: meshcat.Visualizer, ground: Ground, root: str) -> None:
    """The terrain's boxes under ``/<root>/terrain``, as MuJoCo's scene has them (none on the flat floor)."""
    if ground.flat:
        return
    _, boxes = terrain_boxes(ground.terrain)  # type: ignore[arg-type]
    material = mg.MeshLambertMaterial(color=TERRAIN_COLOR)
    edges = mg.LineBasicMaterial(color=TERRAIN_EDGE_COLOR)
    if isinstance(ground.terrain, Heightfield):
        vertices, faces = grid_mesh(ground.terrain)
        vis[f"/{root}/terrain/terrain_grid"].set_object(mg.TriangularMeshGeometry(vertices, faces), material)
    for box in boxes:
        node = vis[f"/{root}/terrain/{box.name}"]
        node.set_object(_solid(box), material)
        node.set_transform(_box_pose(box))
        node["edges"].set_object(mg.LineSegments(mg.PointsGeometry(_box_edges(box).T), edges))


def grid_mesh(terrain: Heightfield) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices, faces)``: the grid's samples ``(ny nx, 3)`` (m, world; row ``i`` of the grid first) and its
    triangles ``(2 (ny - 1) (nx - 1), 3)`` (vertex indices, counter-clockwise seen from above), two per cell."""
    ny, nx = terrain.heights.shape
    x = terrain.origin[0] + terrain.size[0] * np.arange(nx) / (nx - 1)
    y = terrain.origin[1] + terrain.size[1] * np.arange(ny) / (ny - 1)
    vertices = np.column_stack((np.tile(x, ny), np.repeat(y, nx), terrain.heights.ravel()))
    corner = (np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)[None, :]).ravel()  # (i, j) of each cell
    after, above = corner + 1, corner + nx  # (i, j + 1) and (i + 1, j)
    lower = np.column_stack((corner, after, above + 1))  # u >= v: (0, 0), (1, 0), (1, 1)
    upper = np.column_stack((corner, above + 1, above))  # u < v: (0, 0), (1, 1), (0, 1)
    return vertices, np.concatenate((lower, upper)).astype(np.uint32)


def _box_edges(box: SceneBox) -> np.ndarray:
    """The 12 edges of ``box`` in its own frame, as 24 segment end points ``(24, 3)`` (m)."""
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * box.half_size
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]  # differ in one sign
    return np.array([corners[i] for pair in pairs for i in pair])


def draw_obstacles(
    vis: meshcat.Visualizer, ground: Ground, frame_times: np.ndarray, root: str
) -> list[tuple[str, np.ndarray]]:
    """Each obstacle under ``/<root>/obstacles``, faint from the start and solid from when it is seen (module
    docstring); returns the animated nodes and their positions at the keyframes ``frame_times`` (s; m)."""
    ghost = mg.MeshLambertMaterial(color=OBSTACLE_COLOR, transparent=True, opacity=GHOST_OPACITY)
    solid = mg.MeshLambertMaterial(color=OBSTACLE_COLOR)
    animated = []
    for box, seen in ground.obstacles:
        group = f"/{root}/obstacles/{box.name}"
        vis[f"{group}/ghost"].set_object(_solid(box, GHOST_SHRINK), ghost)
        vis[f"{group}/ghost"].set_transform(_box_pose(box))
        node = f"{group}/seen"  # animated: its position only, the box's turn fixed below it
        turn = _box_pose(box)
        turn[:3, 3] = 0.0
        vis[f"{node}/box"].set_object(_solid(box), solid)
        vis[f"{node}/box"].set_transform(turn)
        positions = np.tile(box.centre, (len(frame_times), 1))
        positions[frame_times < seen - 1e-9, 2] -= HIDDEN_DEPTH
        vis[node].set_transform(mtf.translation_matrix(positions[0]))
        animated.append((node, positions))
    return animated
