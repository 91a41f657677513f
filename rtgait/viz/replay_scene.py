"""The scene of the 3D replay, as the data the page reads (see :mod:`rtgait.viz.replay_page`).

Meshcat paths, under ``/rtgait``::

    robot/<joint>            one group per joint that carries geometry, animated with the joint's world pose
    robot/<joint>/<geometry> the geometry, fixed in the joint frame (its placement, mesh scale and mirror)
    footprints/<i>_<side>    one flat box per footprint (left and right in their own colours), at its height and
                             tilt (z, pitch, roll) off the flat floor
    terrain/<name>           the terrain's boxes (:func:`rtgait.core.geometry.scene_boxes.terrain_boxes`: the
                             MuJoCo scene's), when the walk is not on the flat floor; terrain/<name>/edges, their
                             edges as dark lines (:mod:`rtgait.viz.replay_ground` draws these and the obstacles)
    obstacles/<name>/seen    an obstacle's box (:func:`~rtgait.core.geometry.scene_boxes.obstacle_box`, in
                             .../seen/box), animated: below the scene until the walk sees it, in place from then on;
                             obstacles/<name>/ghost, the same box faint from the start (in the physics all along)
    cog_path, zmp_path       lines; cog, zmp: markers that move with the robot
    planned_cog_path, planned_zmp_path   the planned lines, when a measured walk is drawn with its plan

Below ``/rtgait`` everything is in the world frame of the inputs (z up, the flat ground at z = 0); ``/rtgait``
itself, meshcat's grid and axes carry one translation that puts the middle of the walk at the origin of the page's
world, where the camera orbits. On a terrain the grid is the floor under it, at its lowest level, and the ZMP is
drawn on the terrain's surface (:func:`~rtgait.core.geometry.scene_boxes.ground_heights`).

Footprints, paths, markers, primitive shapes and meshes other than STL are meshcat commands, recorded here with
meshcat's own Python classes (no meshcat server is started). STL meshes go through
:class:`rtgait.viz.replay_meshes.MeshLibrary` to be shared and simplified. The animation is packed as float32
arrays rather than meshcat's dictionary per keyframe (sizes: ``docs/design/figures_and_replay.md``).
"""

from __future__ import annotations

import base64
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import meshcat
import meshcat.geometry as mg
import meshcat.transformations as mtf
import numpy as np
import pinocchio as pin
import umsgpack
from pinocchio.visualize import MeshcatVisualizer
from scipy.spatial.transform import Rotation

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.scene_boxes import SceneBox, floor_level, ground_heights
from rtgait.viz.replay_ground import FLAT_FLOOR, OBSTACLE_COLOR, TERRAIN_COLOR, Ground, draw_obstacles, draw_terrain
from rtgait.viz.replay_meshes import MeshLibrary, encode_mesh
from rtgait.viz.replay_page import LegendEntry

ROOT = "rtgait"
"""Top meshcat path of everything drawn."""
# Same colour per quantity as the matplotlib figures (rtgait.viz.figures), except the ZMP, which would vanish
# on the blue left footprints. Planned paths, drawn with measured ones, take the light tone of the same hue.
FOOT_COLORS = {"left": 0x1F77B4, "right": 0xFF7F0E}
COG_COLOR = 0xD62728
ZMP_COLOR = 0x2CA02C
PLANNED_COG_COLOR = 0xFF9896
PLANNED_ZMP_COLOR = 0x98DF8A

FOOTPRINT_THICKNESS = 0.002  # m: flat, yet drawn above the grid
PATH_LIFT = 0.004  # m: the ZMP path is drawn just above the footprints (the planned one just below it)
MAX_PATH_POINTS = 5000  # per line; a path sampled more densely is thinned (its last point always kept)
GRID_CELL = 0.5  # m: meshcat's grid (20 m, 40 cells), moved under the walk by whole cells
CAMERA_DIRECTION = (0.45, -0.8, 0.5)  # from the walk's middle toward the camera, walking along +x: front right, above
CAMERA_FOV = 45.0  # deg, vertical (meshcat's 75 deg bends the ends of a long walk)
CAMERA_MARGIN = 1.12  # the walk's box fills at most 1/1.12 of the view, leaving room for the legend and clock


@dataclass(frozen=True)
class Foot:
    """A validated footprint: position (m), yaw (rad), side, and its height (m) and tilt (rad) off the flat floor."""

    x: float
    y: float
    yaw: float
    side: str
    z: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0


@dataclass(frozen=True)
class Paths:
    """Validated paths (m), each at the samples (``(k, 3)`` COG, ``(k, 2)`` ZMP) and at the keyframes."""

    cog: np.ndarray | None = None
    zmp: np.ndarray | None = None
    planned_cog: np.ndarray | None = None
    planned_zmp: np.ndarray | None = None
    frame_cog: np.ndarray | None = None
    frame_zmp: np.ndarray | None = None
    source: str | None = None  # what cog and zmp are: "planned", "measured" or unsaid


class _Recorder:
    """Stands in for meshcat's window to a server: keeps each command, packed as the viewer receives it."""

    def __init__(self) -> None:
        self.commands: list[bytes] = []

    def send(self, command: Any) -> None:
        self.commands.append(umsgpack.packb(command.lower()))


class _GroupedVisualizer(MeshcatVisualizer):  # type: ignore[misc]
    """Pinocchio's meshcat loader (primitives, DAE/OBJ meshes, colours), placing each geometry below its joint."""

    def __init__(self, model: pin.Model, visual_model: pin.GeometryModel, node_names: dict[str, str]) -> None:
        super().__init__(model, None, visual_model)
        self._node_names = node_names

    def getViewerNodeName(  # noqa: N802 (Pinocchio's method name)
        self, geometry_object: pin.GeometryObject, geometry_type: pin.GeometryType
    ) -> str:
        return self._node_names[geometry_object.name]


@dataclass(frozen=True)
class Scene:
    """What the page needs, built by :func:`build_scene`: its JSON ``data`` (keys in
    :func:`rtgait.viz.replay_page.page_html`) and the ``legend``'s lines."""

    data: dict[str, Any]
    legend: list[LegendEntry]


def _node(name: str) -> str:
    """A meshcat path element: '/' would split the path."""
    return name.replace("/", "_") or "_"


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype="<f4").tobytes()).decode("ascii")


def _thin(points: np.ndarray) -> np.ndarray:
    if len(points) <= MAX_PATH_POINTS:
        return points
    stride = math.ceil(len(points) / MAX_PATH_POINTS)
    kept = points[::stride]
    return kept if np.array_equal(kept[-1], points[-1]) else np.vstack([kept, points[-1:]])


def build_scene(
    model: pin.Model,
    visual_model: pin.GeometryModel,
    frame_times: np.ndarray,
    frame_q: np.ndarray,
    *,
    repetitions: int | None,
    footprints: list[Foot],
    sole: SoleRect,
    paths: Paths,
    phases: list[tuple[float, str]],
    background: str,
    mesh_triangles: int | None,
    ground: Ground = FLAT_FLOOR,
) -> Scene:
    """The replay's scene: robot at each keyframe (``frame_times`` from 0 s, ``frame_q`` on ``model``),
    footprints, the terrain and obstacles of ``ground``, paths and markers, background, camera view and overlay."""
    recorder = _Recorder()
    vis = meshcat.Visualizer(window=recorder)
    data = model.createData()
    joints = sorted({g.parentJoint for g in visual_model.geometryObjects})
    joint_nodes = {j: f"/{ROOT}/robot/{_node(model.names[j])}" for j in joints}
    poses = np.empty((len(frame_q), len(joints), 4, 4))  # per frame and joint: world pose of the joint
    for f, qf in enumerate(frame_q):
        pin.forwardKinematics(model, data, qf)
        for n, j in enumerate(joints):
            poses[f, n] = data.oMi[j].homogeneous

    library = MeshLibrary(mesh_triangles)
    robot, corners = _robot(model, visual_model, library, vis, joint_nodes, poses, joints)
    _draw_footprints(vis, footprints, sole)
    draw_terrain(vis, ground, ROOT)
    lowest = min((foot.z for foot in footprints), default=None)
    markers = _draw_paths(vis, paths, lambda xy: ground_heights(ground.terrain, xy, lowest))
    markers += draw_obstacles(vis, ground, frame_times, ROOT)
    if background == "white":
        for key in ("top_color", "bottom_color"):
            vis["/Background"].set_property(key, [1.0, 1.0, 1.0])

    box = _walk_box(corners, footprints, sole, paths, [box for box, _ in ground.obstacles])
    centre = 0.5 * (box[0] + box[1])
    # meshcat's orbit controls move the camera in the frame of its parent node but aim it with three.js' lookAt,
    # which reads the target in world coordinates: the two agree only for a target at the origin. So the world
    # moves instead: everything drawn here, meshcat's axes and its grid (by whole cells, so that its lines stay
    # on round coordinates) shift by -centre, and the camera orbits the middle of the walk.
    floor = 0.0 if ground.flat else floor_level(ground.terrain)  # type: ignore[arg-type]  # the grid: the floor
    cell = np.array([*(np.round(centre[:2] / GRID_CELL) * GRID_CELL), floor])
    for node, offset in ((f"/{ROOT}", np.zeros(3)), ("/Axes", np.zeros(3)), ("/Grid", cell)):
        vis[node].set_transform(mtf.translation_matrix(offset - centre))

    nodes = list(joint_nodes.values()) + [node for node, _ in markers]
    positions = np.concatenate([poses[:, :, :3, 3], *(p[:, None, :] for _, p in markers)], axis=1)
    rotations = np.zeros((len(frame_q), len(joints), 4))
    if joints:
        rotations = Rotation.from_matrix(poses[:, :, :3, :3].reshape(-1, 3, 3)).as_quat().reshape(rotations.shape)
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (len(frame_q), len(markers), 1))
    quaternions = np.concatenate([rotations, identity], axis=1)
    meshes = [encode_mesh(mesh) for mesh in library.meshes]
    scene_data = {
        "commands": [base64.b64encode(c).decode("ascii") for c in recorder.commands],
        "meshes": meshes,
        "robot": robot,
        "animation": {
            "nodes": nodes,
            "times": _b64(frame_times),
            "positions": _b64(positions.transpose(1, 0, 2)),
            "quaternions": _b64(quaternions.transpose(1, 0, 2)),
            "repetitions": repetitions,
        },
        "view": {
            "box": box.tolist(),
            "centre": centre.tolist(),
            "direction": _camera_direction(poses).tolist(),
            "fov": CAMERA_FOV,
            "margin": CAMERA_MARGIN,
        },
        "overlay": {"phases": [[t, label] for t, label in phases]},
    }
    return Scene(scene_data, _legend(footprints, paths, ground))


def _robot(
    model: pin.Model,
    visual_model: pin.GeometryModel,
    library: MeshLibrary,
    vis: meshcat.Visualizer,
    joint_nodes: dict[int, str],
    poses: np.ndarray,
    joints: list[int],
) -> tuple[list[dict[str, Any]], list[np.ndarray]]:
    """The robot's geometries: STL meshes as entries of the shared library, anything else drawn by Pinocchio's
    loader. Returns the mesh entries and, per geometry, its bounding-box corners over the frames (m, world)."""
    node_names = {g.name: f"{joint_nodes[g.parentJoint]}/{_node(g.name)}" for g in visual_model.geometryObjects}
    loader: _GroupedVisualizer | None = None
    entries = []
    corners = []
    column = {j: n for n, j in enumerate(joints)}
    for geometry in visual_model.geometryObjects:
        # Mesh scale (e.g. a mirrored right-leg mesh, -1 along y) stays in this fixed transform, so the animated
        # joint transform above it is a pure rotation and translation.
        placement = geometry.placement.homogeneous @ np.diag([*np.asarray(geometry.meshScale), 1.0])
        use = library.use(geometry.meshPath) if geometry.meshPath else None
        world = poses[:, column[geometry.parentJoint]]
        if use is None:
            if loader is None:
                loader = _GroupedVisualizer(model, visual_model, node_names)
                loader.initViewer(viewer=vis)
            loader.loadViewerGeometryObject(geometry, pin.GeometryType.VISUAL)
            vis[node_names[geometry.name]].set_transform(placement)
            corners.append(world[:, :3, 3])  # the joint's origin: the shape's size is not read here
            continue
        placement = placement @ np.diag([*np.diag(use.mirror), 1.0])
        rgba = np.clip(np.asarray(geometry.meshColor, dtype=float), 0.0, 1.0)
        entries.append({
            "path": node_names[geometry.name],
            "mesh": use.index,
            "matrix": placement.T.reshape(-1).tolist(),  # column-major, as three.js reads a 4x4
            "color": [round(float(c), 4) for c in rgba],
        })  # fmt: skip
        local = np.column_stack([library.bounds(use.index), np.ones(8)]) @ placement.T  # (8, 4)
        corners.append(np.einsum("fij,kj->fki", world, local)[..., :3].reshape(-1, 3))
    return entries, corners


def _draw_footprints(vis: meshcat.Visualizer, footprints: list[Foot], sole: SoleRect) -> None:
    length = sole.front + sole.back
    width = sole.inner + sole.outer
    materials = {s: mg.MeshLambertMaterial(color=c, transparent=True, opacity=0.8) for s, c in FOOT_COLORS.items()}
    for index, foot in enumerate(footprints):
        node = vis[f"/{ROOT}/footprints/{index:03d}_{foot.side}"]
        node.set_object(mg.Box([length, width, FOOTPRINT_THICKNESS]), materials[foot.side])
        node.set_transform(_footprint_pose(foot, sole))


def _footprint_pose(foot: Foot, sole: SoleRect) -> np.ndarray:
    """Pose of the footprint's box centre (world): the inner edge is toward the other foot (-y for a left foot)."""
    cx = 0.5 * (sole.front - sole.back)
    cy = 0.5 * (sole.outer - sole.inner) if foot.side == "left" else 0.5 * (sole.inner - sole.outer)
    pose = mtf.translation_matrix([foot.x, foot.y, foot.z + 0.5 * FOOTPRINT_THICKNESS]) @ mtf.rotation_matrix(
        foot.yaw, [0.0, 0.0, 1.0]
    )
    if foot.pitch or foot.roll:  # the footprint's R = Rz(yaw) Ry(pitch) Rx(roll)
        pose = pose @ mtf.rotation_matrix(foot.pitch, [0.0, 1.0, 0.0]) @ mtf.rotation_matrix(foot.roll, [1.0, 0.0, 0.0])
    return pose @ mtf.translation_matrix([cx, cy, 0.0])


def _line(vis: meshcat.Visualizer, node: str, points: np.ndarray, color: int) -> None:
    vis[f"/{ROOT}/{node}"].set_object(
        mg.Line(mg.PointsGeometry(_thin(points).T), mg.LineBasicMaterial(color=color, linewidth=2.0))
    )


def _on_ground(xy: np.ndarray, lift: float, heights: np.ndarray | None = None) -> np.ndarray:
    """Points ``xy`` ``lift`` (m) above the ground (at ``heights``, m; the flat floor without)."""
    z = np.full(len(xy), lift) if heights is None else heights + lift
    return np.column_stack([xy, z])


def _draw_paths(
    vis: meshcat.Visualizer, paths: Paths, ground: Callable[[np.ndarray], np.ndarray] | None = None
) -> list[tuple[str, np.ndarray]]:
    """Draw the COG and ZMP lines and their markers, the ZMP at the ``ground``'s heights under it (m; the flat
    floor without); return the markers' paths and per-frame positions (m)."""

    def lifted(xy: np.ndarray, lift: float) -> np.ndarray:
        return _on_ground(xy, lift, None if ground is None else ground(xy))

    markers = []
    if paths.planned_cog is not None:
        _line(vis, "planned_cog_path", paths.planned_cog, PLANNED_COG_COLOR)
    if paths.planned_zmp is not None:
        _line(vis, "planned_zmp_path", lifted(paths.planned_zmp, 0.75 * PATH_LIFT), PLANNED_ZMP_COLOR)
    if paths.cog is not None and paths.frame_cog is not None:
        _line(vis, "cog_path", paths.cog, COG_COLOR)
        vis[f"/{ROOT}/cog"].set_object(mg.Sphere(0.025), mg.MeshLambertMaterial(color=COG_COLOR))
        vis[f"/{ROOT}/cog"].set_transform(mtf.translation_matrix(paths.frame_cog[0]))
        markers.append((f"/{ROOT}/cog", paths.frame_cog))
    if paths.zmp is not None and paths.frame_zmp is not None:
        _line(vis, "zmp_path", lifted(paths.zmp, PATH_LIFT), ZMP_COLOR)
        # meshcat cylinders stand along three.js y; the rotation lays the disc flat on the ground.
        vis[f"/{ROOT}/zmp/disc"].set_object(mg.Cylinder(0.002, radius=0.02), mg.MeshLambertMaterial(color=ZMP_COLOR))
        vis[f"/{ROOT}/zmp/disc"].set_transform(mtf.rotation_matrix(math.pi / 2, [1.0, 0.0, 0.0]))
        positions = lifted(paths.frame_zmp, PATH_LIFT)
        vis[f"/{ROOT}/zmp"].set_transform(mtf.translation_matrix(positions[0]))
        markers.append((f"/{ROOT}/zmp", positions))
    return markers


def _legend(footprints: list[Foot], paths: Paths, ground: Ground = FLAT_FLOOR) -> list[LegendEntry]:
    entries = [
        LegendEntry(f"{side} footprints", FOOT_COLORS[side], "box")
        for side in ("left", "right") if any(f.side == side for f in footprints)
    ]  # fmt: skip
    source = paths.source or ("measured" if paths.planned_cog is not None or paths.planned_zmp is not None else None)
    suffix = f" ({source})" if source else ""
    if paths.cog is not None:
        entries.append(LegendEntry(f"COG path{suffix} and current COG (ball)", COG_COLOR, "marker"))
    if paths.planned_cog is not None:
        entries.append(LegendEntry("COG path (planned)", PLANNED_COG_COLOR, "line"))
    if paths.zmp is not None:
        entries.append(LegendEntry(f"ZMP path{suffix} and current ZMP (disc)", ZMP_COLOR, "marker"))
    if paths.planned_zmp is not None:
        entries.append(LegendEntry("ZMP path (planned)", PLANNED_ZMP_COLOR, "line"))
    if ground.terrain is not None and not ground.flat:
        entries.append(LegendEntry(f"terrain ({ground.terrain.kind}, as in MuJoCo)", TERRAIN_COLOR, "box"))
    for _, seen in ground.obstacles:
        entries.append(LegendEntry(f"obstacle (faint until seen at {seen:.2f} s)", OBSTACLE_COLOR, "box"))
    return entries


def _walk_box(
    corners: list[np.ndarray], footprints: list[Foot], sole: SoleRect, paths: Paths, boxes: Sequence[SceneBox] = ()
) -> np.ndarray:
    """Lowest and highest corner (m, world, shape ``(2, 3)``) of everything drawn but the terrain, over the whole
    replay (the terrain reaches metres beyond the walk)."""
    points = list(corners)
    for box in boxes:
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        points.append(box.centre + (signs * box.half_size) @ np.asarray(box.rotation).T)
    for foot in footprints:
        pose = _footprint_pose(foot, sole)
        half = np.array([0.5 * (sole.front + sole.back), 0.5 * (sole.inner + sole.outer)])
        local = np.array([[sx * half[0], sy * half[1], 0.0, 1.0] for sx in (-1, 1) for sy in (-1, 1)])
        points.append((local @ pose.T)[:, :3])
    for path in (paths.cog, paths.planned_cog):
        if path is not None:
            points.append(path)
    for path in (paths.zmp, paths.planned_zmp):
        if path is not None:
            points.append(_on_ground(path, 0.0))
    everything = np.vstack(points)
    low, high = everything.min(axis=0), everything.max(axis=0)
    low[2] = min(low[2], 0.0)  # the ground is in view
    return np.array([low, high])


def _camera_direction(poses: np.ndarray) -> np.ndarray:
    """:data:`CAMERA_DIRECTION` turned with the walk: about the heading from the first to the last position of the
    robot's first joint (the free flyer of a walking robot), or about its first yaw for a walk that ends near where
    it started (m, rad)."""
    heading = 0.0
    if poses.shape[1] > 0:
        root = poses[:, 0]
        travel = root[-1, :2, 3] - root[0, :2, 3]
        if float(np.linalg.norm(travel)) > 0.3:
            heading = math.atan2(float(travel[1]), float(travel[0]))
        else:
            heading = math.atan2(float(root[0, 1, 0]), float(root[0, 0, 0]))
    c, s = math.cos(heading), math.sin(heading)
    x, y, z = CAMERA_DIRECTION
    return np.array([c * x - s * y, s * x + c * y, z])
