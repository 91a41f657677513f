"""A self-contained HTML 3D replay of a whole-body walk (meshcat's static HTML export).

:func:`write_replay_html` draws a Pinocchio model's visual meshes moving along a joint trajectory, the footprints
as flat rectangles on the ground, and the COG and ZMP paths as lines, into one HTML file that any browser opens
from disk with no network access: the meshcat viewer's JavaScript (three.js included) and every mesh are inlined.

The scene is built by a private meshcat server on 127.0.0.1 that lives only while the file is written; nothing
needs a display. Scene layout (meshcat paths, under ``/rtgait``)::

    robot/<joint>            one group per joint that carries geometry, animated with the joint's world pose
    robot/<joint>/<geometry> the mesh, fixed in the joint frame (its placement and mesh scale)
    footprints/<i>_<side>    one flat box per footprint (left and right in their own colours)
    cog_path, zmp_path       lines; cog, zmp: markers that move with the robot

``/rtgait`` (and meshcat's grid and axes) carry one fixed translation that puts the middle of the walk where the
camera orbits; positions relative to ``/rtgait`` are the world coordinates of the inputs.
"""

from __future__ import annotations

import contextlib
import html
import io
import math
import numbers
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import meshcat
import meshcat.geometry as mg
import meshcat.transformations as mtf
import numpy as np
import pinocchio as pin
import zmq
from meshcat.animation import Animation
from pinocchio.visualize import MeshcatVisualizer

from rtgait.core.footsteps import SoleRect
from rtgait.outputs import write_text_atomic

__all__ = [
    "COG_COLOR",
    "DEFAULT_FPS",
    "DEFAULT_SOLE",
    "FOOT_COLORS",
    "ROOT",
    "ZMP_COLOR",
    "write_replay_html",
]

ROOT = "rtgait"
"""Top meshcat path of everything this module draws."""
DEFAULT_FPS = 25.0
"""Animation keyframes per second of replay (Hz); three.js interpolates between them when it draws."""
# Same colour per quantity as the matplotlib figures (rtgait.viz.figures), except the ZMP, which would vanish
# on the blue left footprints.
FOOT_COLORS = {"left": 0x1F77B4, "right": 0xFF7F0E}
COG_COLOR = 0xD62728
ZMP_COLOR = 0x2CA02C

FOOTPRINT_THICKNESS = 0.002  # m: flat, yet drawn above the grid
PATH_LIFT = 0.004  # m: the ZMP path is drawn just above the footprints
MAX_PATH_POINTS = 5000  # per line; a path sampled more densely is thinned (its last point always kept)
VIEW_HEIGHT = 0.6  # m above the ground: the camera orbits the middle of the walk at this height
SERVER_TIMEOUT_MS = 60_000  # a meshcat server that stops answering raises instead of hanging the caller


class _Footprint(Protocol):
    x: float
    y: float
    yaw: float
    side: str


class _Sole(Protocol):
    front: float
    back: float
    inner: float
    outer: float


DEFAULT_SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
"""Sole drawn when none is given (m from the foot frame): an HRP-2-like 0.23 x 0.14 m sole."""


def write_replay_html(
    path: str | os.PathLike[str],
    model: pin.Model,
    visual_model: pin.GeometryModel,
    times: Sequence[float] | np.ndarray,
    q: np.ndarray,
    *,
    footprints: Iterable[_Footprint] = (),
    sole: _Sole | None = None,
    cog: np.ndarray | None = None,
    zmp: np.ndarray | None = None,
    title: str = "",
    fps: float = DEFAULT_FPS,
    repetitions: int | None = None,
) -> Path:
    """Write a self-contained HTML page that replays ``q`` on the robot in 3D; return its path.

    Args:
        path: the HTML file to write. Its folder must exist; the file is written under a temporary name and
            renamed when complete, so an existing file is replaced only by a complete one.
        model: the robot's kinematic model (a free-flyer root for a walking robot; any Pinocchio model works).
        visual_model: its VISUAL geometry model (meshes resolved to files, e.g. with ``package_dirs``).
        times: sample times, shape ``(k,)`` (s), strictly increasing and finite; the replay's clock shows
            ``times - times[0]``.
        q: configurations, shape ``(k, model.nq)`` (m and rad; free-flyer quaternion ``x, y, z, w``).
        footprints: objects with ``x``, ``y`` (m), ``yaw`` (rad) and ``side`` (``"left"``/``"right"``),
            drawn as flat rectangles on the ground (z = 0), one colour per side.
        sole: object with ``front``, ``back``, ``inner``, ``outer`` (m from the foot frame, >= 0); the inner
            side is toward the other foot (-y of a left foot). Defaults to :data:`DEFAULT_SOLE`.
        cog: COG positions, shape ``(k, 3)`` (m), drawn as a line and a moving sphere.
        zmp: ZMP positions on the ground, shape ``(k, 2)`` (m), drawn as a line and a moving disc.
        title: the page title.
        fps: animation keyframes per second of replay (Hz, > 0); the trajectory is interpolated at these times
            (configurations on the model's manifold).
        repetitions: how many times the replay plays; ``None`` loops forever.

    Returns:
        The path of the written file.

    Raises:
        ValueError: a shape, value or attribute is invalid (named in the message); nothing is written then.
        FileNotFoundError: the folder of ``path`` does not exist.
        RuntimeError: the meshcat server failed; nothing is written then.
    """
    out = Path(path)
    t = _times(times)
    qs = _configurations(q, len(t), model)
    cog_arr = _path_array(cog, len(t), 3, "cog")
    zmp_arr = _path_array(zmp, len(t), 2, "zmp")
    feet = [_footprint(f, i) for i, f in enumerate(footprints)]
    rect = _sole(DEFAULT_SOLE if sole is None else sole)
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (math.isfinite(fps) and fps > 0.0):
        raise ValueError(f"fps must be a finite frame rate > 0 Hz, got {fps!r}")
    fps = float(fps)
    if repetitions is not None and (
        isinstance(repetitions, bool) or not isinstance(repetitions, numbers.Integral) or repetitions < 1
    ):
        raise ValueError(f"repetitions must be None (loop forever) or an integer >= 1, got {repetitions!r}")
    if not isinstance(title, str):
        raise ValueError(f"title must be a string, got {title!r}")
    if not out.parent.is_dir():
        raise FileNotFoundError(f"replay folder does not exist: {out.parent}")

    frame_times = _frame_times(t, fps)
    frame_q = _interpolate_configurations(model, t, qs, frame_times)
    page = _render(
        model, visual_model, frame_times - t[0], frame_q, fps=fps, repetitions=repetitions, footprints=feet,
        sole=rect, cog=cog_arr, zmp=zmp_arr, frame_cog=_interpolate(t, cog_arr, frame_times),
        frame_zmp=_interpolate(t, zmp_arr, frame_times),
    )
    page = page.replace("<title>MeshCat</title>", f"<title>{html.escape(title or 'rtgait replay')}</title>", 1)
    write_text_atomic(out, page)
    return out


# ---------------------------------------------------------------------------------------------- validation


def _times(times: Sequence[float] | np.ndarray) -> np.ndarray:
    try:
        t = np.asarray(times, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"times must be an array of numbers (s): {exc}") from None
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"times must have shape (k,) with k >= 1 samples, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("times must be finite (s)")
    if np.any(np.diff(t) <= 0.0):
        raise ValueError("times must be strictly increasing (s)")
    return t


def _configurations(q: np.ndarray, k: int, model: pin.Model) -> np.ndarray:
    """``q`` as float64 ``(k, nq)`` with unit quaternions (an IK's drift from unit length is removed)."""
    nq = model.nq
    arr = _finite_array(q, (k, nq), "q", "an array of numbers", "(k, nq)", "times and the model", "")
    unit = np.array([pin.normalize(model, row) for row in arr]).reshape(k, nq)
    for index, row in enumerate(unit):
        if not pin.isNormalized(model, row, 1e-9):  # normalize leaves a zero-length quaternion at zero
            raise ValueError(f"q[{index}] has a zero-length quaternion: no rotation can be read from it")
    return unit


def _path_array(values: np.ndarray | None, k: int, dim: int, name: str) -> np.ndarray | None:
    if values is None:
        return None
    return _finite_array(values, (k, dim), name, "an array of positions (m)", f"(k, {dim})", "times", " (m)")


def _finite_array(
    values: object, shape: tuple[int, int], name: str, kind: str, symbolic: str, match: str, unit: str
) -> np.ndarray:
    """``values`` as a finite float64 array of ``shape``, or a ``ValueError`` naming ``name`` and what it must be."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be {kind}: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {symbolic} = {shape} to match {match}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite{unit}")
    return arr


@dataclass(frozen=True)
class _Foot:
    x: float
    y: float
    yaw: float
    side: str


def _footprint(foot: Any, index: int) -> _Foot:
    values = {}
    for name in ("x", "y", "yaw"):
        value = getattr(foot, name, None)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ValueError(f"footprints[{index}].{name} must be a number, got {value!r}")
        if not math.isfinite(float(value)):
            raise ValueError(f"footprints[{index}].{name} must be finite, got {value!r}")
        values[name] = float(value)
    side = getattr(foot, "side", None)
    if side not in FOOT_COLORS:
        raise ValueError(f"footprints[{index}].side must be 'left' or 'right', got {side!r}")
    return _Foot(values["x"], values["y"], values["yaw"], str(side))


def _sole(sole: Any) -> SoleRect:
    values = {}
    for name in ("front", "back", "inner", "outer"):
        value = getattr(sole, name, None)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ValueError(f"sole.{name} must be a distance in m, got {value!r}")
        if not (math.isfinite(float(value)) and value >= 0.0):
            raise ValueError(f"sole.{name} must be a finite distance >= 0 m, got {value!r}")
        values[name] = float(value)
    if values["front"] + values["back"] <= 0.0 or values["inner"] + values["outer"] <= 0.0:
        raise ValueError("sole rectangle must have a positive length and width (m)")
    return SoleRect(**values)


# ---------------------------------------------------------------------------------------------- sampling


def _frame_times(t: np.ndarray, fps: float) -> np.ndarray:
    """Keyframe times (s): every 1/fps from the first sample, plus the last sample if it falls between."""
    span = float(t[-1] - t[0])
    count = math.floor(span * fps + 1e-9) + 1
    frames = t[0] + np.arange(count) / fps
    if t[-1] - frames[-1] > 1e-9:
        frames = np.append(frames, t[-1])
    return np.minimum(frames, t[-1])


def _bracket(t: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the sample at or before each time and the fraction (0..1) toward the next one."""
    if len(t) == 1:
        return np.zeros(len(at), dtype=int), np.zeros(len(at))
    i = np.clip(np.searchsorted(t, at, side="right") - 1, 0, len(t) - 2)
    u = np.clip((at - t[i]) / (t[i + 1] - t[i]), 0.0, 1.0)
    return i, u


def _interpolate_configurations(model: pin.Model, t: np.ndarray, q: np.ndarray, at: np.ndarray) -> np.ndarray:
    i, u = _bracket(t, at)
    if len(t) == 1:
        return np.repeat(q[:1], len(at), axis=0)
    # pin.interpolate follows each joint's manifold, so the free-flyer quaternion stays a rotation.
    return np.array([pin.interpolate(model, q[j], q[j + 1], float(s)) for j, s in zip(i, u, strict=True)])


def _interpolate(t: np.ndarray, values: np.ndarray | None, at: np.ndarray) -> np.ndarray | None:
    if values is None:
        return None
    if len(t) == 1:
        return np.repeat(values[:1], len(at), axis=0)
    return np.column_stack([np.interp(at, t, values[:, d]) for d in range(values.shape[1])])


def _thin(points: np.ndarray) -> np.ndarray:
    if len(points) <= MAX_PATH_POINTS:
        return points
    stride = math.ceil(len(points) / MAX_PATH_POINTS)
    kept = points[::stride]
    return kept if np.array_equal(kept[-1], points[-1]) else np.vstack([kept, points[-1:]])


# ---------------------------------------------------------------------------------------------- scene


class _GroupedVisualizer(MeshcatVisualizer):  # type: ignore[misc]
    """Pinocchio's meshcat loader (meshes, primitives, colours), placing each geometry below its joint's node.

    Binary STL meshes are sent as indexed triangle meshes instead of the STL file: the same float32 vertices
    without the per-triangle normals and repeated corners, about a third of the bytes. Flat shading draws them
    exactly as three.js draws the STL (one normal per facet).
    """

    def __init__(self, model: pin.Model, visual_model: pin.GeometryModel, node_names: dict[str, str]) -> None:
        super().__init__(model, None, visual_model)
        self._node_names = node_names
        self._meshes: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}

    def getViewerNodeName(  # noqa: N802 (Pinocchio's method name)
        self, geometry_object: pin.GeometryObject, geometry_type: pin.GeometryType
    ) -> str:
        return self._node_names[geometry_object.name]

    def loadViewerGeometryObject(  # noqa: N802 (Pinocchio's method name)
        self, geometry_object: pin.GeometryObject, geometry_type: pin.GeometryType, color: Any = None
    ) -> None:
        path = geometry_object.meshPath
        mesh = None
        if path.lower().endswith(".stl"):
            if path not in self._meshes:
                self._meshes[path] = _read_binary_stl(path)
            mesh = self._meshes[path]
        if mesh is None:  # primitives, OBJ/DAE, ASCII STL: Pinocchio's own loader
            super().loadViewerGeometryObject(geometry_object, geometry_type, color)
            return
        rgba = np.clip(np.asarray(geometry_object.meshColor if color is None else color, dtype=float), 0.0, 1.0)
        material = mg.MeshPhongMaterial(
            color=int(rgba[0] * 255) << 16 | int(rgba[1] * 255) << 8 | int(rgba[2] * 255),
            opacity=float(rgba[3]), flatShading=True,
        )
        self.viewer[self.getViewerNodeName(geometry_object, geometry_type)].set_object(
            mg.TriangularMeshGeometry(*mesh), material
        )


_STL_TRIANGLE = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def _read_binary_stl(path: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices ``(n, 3)`` float32 (file units) and triangles ``(m, 3)`` uint32 of a binary STL file, or None
    when the file is not one (ASCII STL, unreadable or empty)."""
    try:
        data = Path(path).read_bytes()
    except OSError:
        return None
    if len(data) < 84:
        return None
    count = int.from_bytes(data[80:84], "little")
    if count == 0 or len(data) != 84 + _STL_TRIANGLE.itemsize * count:
        return None
    corners = np.frombuffer(data, dtype=_STL_TRIANGLE, count=count, offset=84)["corners"].reshape(-1, 3)
    vertices, index = np.unique(corners, axis=0, return_inverse=True)
    return vertices, index.reshape(-1, 3).astype(np.uint32)


def _node(name: str) -> str:
    """A meshcat path element: '/' would split the path."""
    return name.replace("/", "_") or "_"


def _render(
    model: pin.Model,
    visual_model: pin.GeometryModel,
    frame_times: np.ndarray,
    frame_q: np.ndarray,
    *,
    fps: float,
    repetitions: int | None,
    footprints: list[_Foot],
    sole: SoleRect,
    cog: np.ndarray | None,
    zmp: np.ndarray | None,
    frame_cog: np.ndarray | None,
    frame_zmp: np.ndarray | None,
) -> str:
    """Build the scene in a private meshcat server and return its static HTML; the server is always stopped."""
    data = model.createData()
    joints = sorted({g.parentJoint for g in visual_model.geometryObjects})
    joint_nodes = {j: f"/{ROOT}/robot/{_node(model.names[j])}" for j in joints}
    node_names = {g.name: f"{joint_nodes[g.parentJoint]}/{_node(g.name)}" for g in visual_model.geometryObjects}
    poses = []  # per frame: joint index -> 4x4 world pose of the joint
    for qf in frame_q:
        pin.forwardKinematics(model, data, qf)
        poses.append({j: data.oMi[j].homogeneous.copy() for j in joint_nodes})

    with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints the server's URL
        vis = meshcat.Visualizer()
    try:
        vis.window.zmq_socket.setsockopt(zmq.RCVTIMEO, SERVER_TIMEOUT_MS)
        vis.window.zmq_socket.setsockopt(zmq.SNDTIMEO, SERVER_TIMEOUT_MS)
        loader = _GroupedVisualizer(model, visual_model, node_names)
        loader.initViewer(viewer=vis)
        for geometry in visual_model.geometryObjects:
            loader.loadViewerGeometryObject(geometry, pin.GeometryType.VISUAL)
            # Mesh scale (e.g. a mirrored right-leg mesh, -1 along y) stays in this fixed transform, so the
            # animated joint transform above it is a pure rotation and translation.
            placement = geometry.placement.homogeneous @ np.diag([*np.asarray(geometry.meshScale), 1.0])
            vis[node_names[geometry.name]].set_transform(placement)
        for j, node in joint_nodes.items():
            vis[node].set_transform(poses[0][j])

        _draw_footprints(vis, footprints, sole)
        markers = _draw_paths(vis, cog, zmp, frame_cog, frame_zmp)
        _place_camera(vis, *_view_centre(frame_q, footprints))

        animation = Animation(default_framerate=fps)
        keys = frame_times * fps  # meshcat keyframe "frames" are in units of 1/fps s
        for index, key in enumerate(keys):
            with animation.at_frame(vis, float(key)) as frame:
                for j, node in joint_nodes.items():
                    frame[node].set_transform(poses[index][j])
                for node, positions in markers:
                    frame[node].set_transform(mtf.translation_matrix(positions[index]))
        vis.set_animation(animation, play=True, repetitions=math.inf if repetitions is None else int(repetitions))
        return vis.static_html()
    except zmq.ZMQError as exc:
        raise RuntimeError(f"the meshcat server did not answer: {exc}") from exc
    finally:
        _close(vis)


def _draw_footprints(vis: meshcat.Visualizer, footprints: list[_Foot], sole: SoleRect) -> None:
    length = sole.front + sole.back
    width = sole.inner + sole.outer
    materials = {s: mg.MeshLambertMaterial(color=c, transparent=True, opacity=0.8) for s, c in FOOT_COLORS.items()}
    for index, foot in enumerate(footprints):
        # Centre of the rectangle in the foot frame: the inner edge is toward the other foot (-y for a left foot).
        cx = 0.5 * (sole.front - sole.back)
        cy = 0.5 * (sole.outer - sole.inner) if foot.side == "left" else 0.5 * (sole.inner - sole.outer)
        pose = mtf.translation_matrix([foot.x, foot.y, 0.5 * FOOTPRINT_THICKNESS]) @ mtf.rotation_matrix(
            foot.yaw, [0.0, 0.0, 1.0]
        )
        pose = pose @ mtf.translation_matrix([cx, cy, 0.0])
        node = vis[f"/{ROOT}/footprints/{index:03d}_{foot.side}"]
        node.set_object(mg.Box([length, width, FOOTPRINT_THICKNESS]), materials[foot.side])
        node.set_transform(pose)


def _draw_paths(
    vis: meshcat.Visualizer,
    cog: np.ndarray | None,
    zmp: np.ndarray | None,
    frame_cog: np.ndarray | None,
    frame_zmp: np.ndarray | None,
) -> list[tuple[str, np.ndarray]]:
    """Draw the COG and ZMP lines and their markers; return the markers' paths and per-frame positions (m)."""
    markers = []
    if cog is not None and frame_cog is not None:
        vis[f"/{ROOT}/cog_path"].set_object(
            mg.Line(mg.PointsGeometry(_thin(cog).T), mg.LineBasicMaterial(color=COG_COLOR, linewidth=2.0))
        )
        vis[f"/{ROOT}/cog"].set_object(mg.Sphere(0.025), mg.MeshLambertMaterial(color=COG_COLOR))
        vis[f"/{ROOT}/cog"].set_transform(mtf.translation_matrix(frame_cog[0]))
        markers.append((f"/{ROOT}/cog", frame_cog))
    if zmp is not None and frame_zmp is not None:
        ground = np.column_stack([_thin(zmp), np.full(len(_thin(zmp)), PATH_LIFT)])
        vis[f"/{ROOT}/zmp_path"].set_object(
            mg.Line(mg.PointsGeometry(ground.T), mg.LineBasicMaterial(color=ZMP_COLOR, linewidth=2.0))
        )
        # meshcat cylinders stand along three.js y; the rotation lays the disc flat on the ground.
        disc = mg.Cylinder(0.002, radius=0.02)
        vis[f"/{ROOT}/zmp/disc"].set_object(disc, mg.MeshLambertMaterial(color=ZMP_COLOR))
        vis[f"/{ROOT}/zmp/disc"].set_transform(mtf.rotation_matrix(math.pi / 2, [1.0, 0.0, 0.0]))
        positions = np.column_stack([frame_zmp, np.full(len(frame_zmp), PATH_LIFT)])
        vis[f"/{ROOT}/zmp"].set_transform(mtf.translation_matrix(positions[0]))
        markers.append((f"/{ROOT}/zmp", positions))
    return markers


def _view_centre(frame_q: np.ndarray, footprints: list[_Foot]) -> tuple[np.ndarray, float]:
    """The point the camera orbits (m, world) and its distance to the camera (m), to see the whole walk."""
    xy = frame_q[:, :2]
    if footprints:
        xy = np.vstack([xy, [[f.x, f.y] for f in footprints]])
    low, high = xy.min(axis=0), xy.max(axis=0)
    return np.array([*(0.5 * (low + high)), VIEW_HEIGHT]), 2.6 + 0.7 * float(np.max(high - low))


def _place_camera(vis: meshcat.Visualizer, centre: np.ndarray, distance: float) -> None:
    """Orbit ``centre`` from the front right at ``distance`` (m).

    meshcat 0.3's camera always orbits the three.js origin, so the world is shifted instead: everything drawn
    here, and meshcat's grid and axes, move by -centre, which keeps them where they belong relative to each
    other while the camera turns around the middle of the walk.
    """
    shift = mtf.translation_matrix(-centre)
    for node in (f"/{ROOT}", "/Grid", "/Axes"):
        vis[node].set_transform(shift)
    direction = np.array([0.45, -0.85, 0.3])
    offset = distance * direction / np.linalg.norm(direction)
    # The camera object lives in meshcat's y-up frame below /Cameras/default/rotated: (x, z, -y) of the world.
    vis["/Cameras/default/rotated/<object>"].set_property("position", [offset[0], offset[2], -offset[1]])


def _close(vis: meshcat.Visualizer) -> None:
    """Stop the private meshcat server and close the socket to it (meshcat 0.3's ``close`` does neither)."""
    window = vis.window
    socket = getattr(window, "zmq_socket", None)
    if socket is not None:
        socket.close(linger=0)
    proc = getattr(window, "server_proc", None)
    if proc is not None:
        proc.kill()
        proc.wait(timeout=10)
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()
