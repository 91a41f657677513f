"""A self-contained HTML 3D replay of a whole-body walk, on meshcat's viewer.

:func:`write_replay_html` draws a Pinocchio model's visual meshes moving along a joint trajectory, the footprints
as flat rectangles on the ground, the COG and ZMP paths as lines, and the terrain and obstacles when the walk has
them (the boxes MuJoCo's scene is built of: :mod:`rtgait.core.geometry.scene_boxes`), into one HTML file that any
browser opens from disk with no network access: meshcat's viewer (three.js included) and every mesh are inlined. A
legend names the colours, a clock shows the replay's time (and the walking phase, when given), and the camera starts
framing the whole walk.

The page stays light (its size: ``docs/design/figures_and_replay.md``): the robot's meshes are shared between the
links that use the same or a mirrored mesh, simplified to a triangle budget, and packed as 16-bit integers
(:mod:`rtgait.viz.replay_meshes`); the animation is packed as float32 arrays (:mod:`rtgait.viz.replay_scene`).
Nothing needs a display or a server: the scene is built in Python and the page is written directly
(:mod:`rtgait.viz.replay_page`).
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pinocchio as pin

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.scene_boxes import obstacle_box
from rtgait.core.geometry.terrain import TERRAIN_CLASSES, TerrainKind
from rtgait.core.obstacle.box import Obstacle
from rtgait.outputs import write_text_atomic
from rtgait.viz.replay_ground import Ground
from rtgait.viz.replay_meshes import MESH_TRIANGLES
from rtgait.viz.replay_page import BACKGROUNDS, page_html
from rtgait.viz.replay_scene import COG_COLOR, FOOT_COLORS, ROOT, ZMP_COLOR, Foot, Paths, build_scene

__all__ = [
    "BACKGROUNDS",
    "COG_COLOR",
    "DEFAULT_FPS",
    "DEFAULT_SOLE",
    "FOOT_COLORS",
    "MESH_TRIANGLES",
    "PATH_SOURCES",
    "ROOT",
    "ZMP_COLOR",
    "write_replay_html",
]

DEFAULT_FPS = 25.0
"""Animation keyframes per second of replay (Hz); three.js interpolates between them when it draws."""
PATH_SOURCES = ("planned", "measured")
"""What the ``cog`` and ``zmp`` of a replay can be said to be, in the legend."""


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
    planned_cog: np.ndarray | None = None,
    planned_zmp: np.ndarray | None = None,
    path_source: str | None = None,
    phases: Sequence[str] | np.ndarray | None = None,
    background: str = "sky",
    mesh_triangles: int | None = MESH_TRIANGLES,
    terrain: TerrainKind | None = None,
    obstacles: Sequence[Obstacle] = (),
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
            drawn as flat rectangles on the ground, one colour per side; at their ``z`` (m), ``pitch`` and ``roll``
            (rad) when they have them (footholds off the flat floor), else at z = 0.
        sole: object with ``front``, ``back``, ``inner``, ``outer`` (m from the foot frame, >= 0); the inner
            side is toward the other foot (-y of a left foot). Defaults to :data:`DEFAULT_SOLE`.
        cog: COG positions, shape ``(k, 3)`` (m), drawn as a line and a moving sphere.
        zmp: ZMP positions on the ground, shape ``(k, 2)`` (m), drawn as a line and a moving disc.
        title: the page title, also shown above the clock.
        fps: animation keyframes per second of replay (Hz, > 0); the trajectory is interpolated at these times
            (configurations on the model's manifold).
        repetitions: how many times the replay plays; ``None`` loops forever.
        planned_cog: the planned COG, shape ``(k, 3)`` (m), drawn as a light red line beside a measured ``cog``.
        planned_zmp: the planned ZMP, shape ``(k, 2)`` (m), drawn as a light green line beside a measured ``zmp``.
        path_source: what ``cog`` and ``zmp`` are, for the legend: ``"planned"``, ``"measured"``, or ``None``
            (unsaid; ``"measured"`` when a planned path is given too).
        phases: one label per sample, shape ``(k,)`` (e.g. ``"left support"``), shown under the clock; the label
            of a sample holds until the next sample whose label differs.
        background: ``"sky"`` (meshcat's blue gradient) or ``"white"`` (for figures and print).
        mesh_triangles: triangle budget per distinct mesh (STL meshes above it are simplified); ``None`` keeps
            every triangle (a page several times larger).
        terrain: the terrain walked on (:mod:`rtgait.core.geometry.terrain`), drawn as MuJoCo builds it, with the
            ZMP on its surface and the grid on the floor under it; ``None`` or flat: the flat floor, as without.
        obstacles: boxes on the ground (:class:`~rtgait.core.obstacle.box.Obstacle`), each drawn faint from the
            start and solid from its ``seen_at`` (s on the clock of ``times``).

    Returns:
        The path of the written file.

    Raises:
        ValueError: a shape, value or attribute is invalid (named in the message); nothing is written then.
        FileNotFoundError: the folder of ``path`` does not exist.
    """
    out = Path(path)
    t = _times(times)
    qs = _configurations(q, len(t), model)
    cog_arr = _path_array(cog, len(t), 3, "cog")
    zmp_arr = _path_array(zmp, len(t), 2, "zmp")
    planned_cog_arr = _path_array(planned_cog, len(t), 3, "planned_cog")
    planned_zmp_arr = _path_array(planned_zmp, len(t), 2, "planned_zmp")
    labels = _phases(phases, t)
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
    if path_source is not None and path_source not in PATH_SOURCES:
        raise ValueError(f"path_source must be None, 'planned' or 'measured', got {path_source!r}")
    if background not in BACKGROUNDS:
        raise ValueError(f"background must be one of {', '.join(map(repr, BACKGROUNDS))}, got {background!r}")
    if mesh_triangles is not None and (
        isinstance(mesh_triangles, bool) or not isinstance(mesh_triangles, numbers.Integral) or mesh_triangles < 4
    ):
        raise ValueError(f"mesh_triangles must be None (keep all) or an integer >= 4, got {mesh_triangles!r}")
    ground = _ground(terrain, obstacles, float(t[0]))
    if not out.parent.is_dir():
        raise FileNotFoundError(f"replay folder does not exist: {out.parent}")

    frame_times = _frame_times(t, fps)
    paths = Paths(
        cog=cog_arr, zmp=zmp_arr, planned_cog=planned_cog_arr, planned_zmp=planned_zmp_arr,
        frame_cog=_interpolate(t, cog_arr, frame_times), frame_zmp=_interpolate(t, zmp_arr, frame_times),
        source=path_source,
    )  # fmt: skip
    scene = build_scene(
        model, visual_model, frame_times - t[0], _interpolate_configurations(model, t, qs, frame_times),
        repetitions=None if repetitions is None else int(repetitions), footprints=feet, sole=rect, paths=paths,
        phases=labels, background=background, mesh_triangles=None if mesh_triangles is None else int(mesh_triangles),
        ground=ground,
    )  # fmt: skip
    page = page_html(
        title=title, data=scene.data, legend=scene.legend, duration=float(t[-1] - t[0]), background=background,
        has_phases=bool(labels),
    )  # fmt: skip
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


def _phases(phases: Sequence[str] | np.ndarray | None, t: np.ndarray) -> list[tuple[float, str]]:
    """``(start time (s) from t[0], label)`` for each run of equal labels, or [] without phases."""
    if phases is None:
        return []
    if isinstance(phases, str):
        raise ValueError("phases must be a sequence of labels, one per sample, not a single string")
    labels = list(phases)
    if len(labels) != len(t):
        raise ValueError(f"phases must have one label per sample: {len(t)} to match times, got {len(labels)}")
    runs: list[tuple[float, str]] = []
    for index, (time, label) in enumerate(zip(t, labels, strict=True)):
        if not isinstance(label, str):
            raise ValueError(f"phases[{index}] must be a string, got {label!r}")
        if not runs or runs[-1][1] != label:
            runs.append((float(time - t[0]), label))
    return runs


def _ground(terrain: Any, obstacles: Any, start: float) -> Ground:
    """The terrain and obstacles checked, the obstacles' sight times on the replay's clock (s from ``start``)."""
    if terrain is not None and not isinstance(terrain, tuple(TERRAIN_CLASSES.values())):
        raise ValueError(f"terrain must be None or a terrain of rtgait.core.geometry.terrain, got {terrain!r}")
    boxes = []
    for index, box in enumerate(obstacles):
        if not isinstance(box, Obstacle):
            raise ValueError(f"obstacles[{index}] must be an rtgait.core.obstacle.box.Obstacle, got {box!r}")
        boxes.append((obstacle_box(index, box), box.seen_at - start))
    return Ground(terrain, tuple(boxes))


def _footprint(foot: Any, index: int) -> Foot:
    values = {}
    for name in ("x", "y", "yaw", "z", "pitch", "roll"):
        if name in ("z", "pitch", "roll") and not hasattr(foot, name):
            values[name] = 0.0  # a footprint on the flat floor
            continue
        value = getattr(foot, name, None)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise ValueError(f"footprints[{index}].{name} must be a number, got {value!r}")
        if not math.isfinite(float(value)):
            raise ValueError(f"footprints[{index}].{name} must be finite, got {value!r}")
        values[name] = float(value)
    side = getattr(foot, "side", None)
    if side not in FOOT_COLORS:
        raise ValueError(f"footprints[{index}].side must be 'left' or 'right', got {side!r}")
    return Foot(side=str(side), **values)


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
