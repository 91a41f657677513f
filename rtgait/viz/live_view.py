"""``rtgait play``'s window: MuJoCo's passive viewer (``mujoco.viewer.launch_passive``) showing a
:class:`~rtgait.sim.live.LiveWalk` in real time, with the keys fed to it.

The main thread runs the closed loop, paced to the wall clock (:class:`~rtgait.sim.live.Pacer`), and about
:data:`FRAME_RATE` times a second draws into the viewer's user scene and syncs it; the viewer renders on its own
thread, and its key callback only queues the key (:meth:`LiveWalk.press`), so that the walk changes between ticks.

Drawn in the scene (``mjvScene`` user geoms, on the ground): the plan's footprints around the step under way (sole
rectangles, blue left, orange right, at their footholds' height and tilt), the planned ZMP (blue), the measured ZMP
(red), the measured DCM (green) and the plan's DCM (pale green), on the terrain's surface
(:func:`~rtgait.core.geometry.scene_boxes.ground_heights`), and while a push acts an arrow onto the base along its
force. The terrain and the obstacles are the model's own geoms (:mod:`rtgait.sim.terrain`, :mod:`rtgait.sim.obstacles`),
drawn by the viewer as any geom. The top-left text line
is :meth:`LiveWalk.status` (command, phase, controller level, real-time factor); the bottom right lists the keys.

Two things of MuJoCo's passive viewer matter here. Its ``sync`` clears ``data.xfrc_applied`` (it applies the mouse
perturbation there), so pushes are rewritten every tick (:meth:`ClosedLoop.push`). Its Backspace resets the
simulation state: the run then ends, saying so, since the walk cannot go on from a reset robot.

A screenshot (:func:`save_screenshot`) is the last frame rendered again offscreen, after the window has closed,
with the viewer's camera and options, the same user geoms and text lines.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math
import os
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.geometry.scene_boxes import ground_heights
from rtgait.sim.live import LiveWalk, Pacer

if TYPE_CHECKING:
    import mujoco

    from rtgait.core.geometry.footsteps import SoleRect

__all__ = [
    "FRAME_RATE",
    "DisplayError",
    "PlayOutcome",
    "check_display",
    "draw_walk",
    "play",
    "save_screenshot",
    "software_renderer",
]

FRAME_RATE = 30.0
"""Frames per second handed to the viewer (s^-1)."""

BATCH = 5
"""Control ticks run at once when the loop is ahead of the wall clock (5 ms at 1 kHz, a sixth of a frame)."""

TEXT_RATE = 4.0
"""Updates of the on-screen text per second (s^-1): the viewer takes a new text only once it has drawn the last one,
so each update waits for a frame to be rendered, on a thread of its own (:class:`_TextLine`)."""

SCREENSHOT_SIZE = (960, 720)
"""Width and height of a screenshot (pixels)."""

_LEFT = (0.2, 0.45, 1.0, 0.45)
_RIGHT = (1.0, 0.55, 0.1, 0.45)
_ZMP_PLANNED = (0.1, 0.3, 1.0, 1.0)
_ZMP_MEASURED = (1.0, 0.1, 0.1, 1.0)
_DCM = (0.1, 0.8, 0.2, 1.0)
_DCM_PLANNED = (0.6, 1.0, 0.6, 0.6)
_PUSH = (1.0, 0.9, 0.1, 1.0)
_KEY_NAMES = "Up / Down\nLeft / Right\nDelete / Page Down\nSpace\nEnter\nInsert"
_KEY_HELP = "forward / backward\nturn left / right\nstep left / right\nstop\npush\ncontroller level"


class DisplayError(Exception):
    """No window can be opened: no display, or GLFW cannot initialise."""


@dataclass(frozen=True)
class PlayOutcome:
    """How a live run ended.

    Attributes:
        wall_time: wall-clock time from the first tick to the end (s).
        reason: ``"exit-after"``, ``"window closed"``, ``"walk over"`` (scripted runs end with the walk),
            ``"reset by the viewer"``.
        pacer: the pacing, with the time given up when the loop could not keep up.
        screenshot: the PNG written, or ``None``.
    """

    wall_time: float
    reason: str
    pacer: Pacer
    screenshot: Path | None


def check_display() -> str:
    """Refuse at once, in one line, when no window can be opened; else return the OpenGL renderer's name.

    Sets ``LP_NUM_THREADS`` (when not set) for Mesa's software rasteriser: one core fewer than the machine has.

    Raises:
        DisplayError: no ``DISPLAY`` (nor ``WAYLAND_DISPLAY``) on Linux, no GLFW, or GLFW cannot initialise or open a
            window (its own message says why).
    """
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise DisplayError("play needs a display and DISPLAY is not set: run it on a desktop, or under xvfb-run")
    # Mesa's software rasteriser (llvmpipe) draws on every core by default, and the viewer draws without pause:
    # leave one core to the physics (read when the first OpenGL context is made, so before the probe below).
    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))
    try:
        import glfw
    except ImportError as error:  # the package, or its shared library
        raise DisplayError(f"play needs GLFW (pip install glfw): {error}") from None
    messages: list[str] = []

    def collect(code: int, text: bytes) -> None:
        messages.append(text.decode(errors="replace"))

    previous = glfw.set_error_callback(collect)
    renderer = None
    try:
        if glfw.init():
            renderer = _renderer_name(glfw)
            glfw.terminate()  # the viewer initialises GLFW again, on its own thread
    finally:
        glfw.set_error_callback(previous)
    if renderer is None:
        why = messages[-1] if messages else "GLFW failed to initialise"
        raise DisplayError(f"play cannot open a window on display {os.environ.get('DISPLAY', '')!r}: {why}")
    return renderer


def _renderer_name(glfw: Any) -> str | None:
    """``GL_RENDERER`` of a hidden 1x1 window's context (e.g. ``"llvmpipe (LLVM 15.0.6, 256 bits)"``), ``""`` when it
    cannot be read, ``None`` when no window opens."""
    glfw.window_hint(glfw.VISIBLE, glfw.FALSE)
    window = glfw.create_window(1, 1, "rtgait", None, None)
    if not window:
        return None
    try:
        glfw.make_context_current(window)
        library = ctypes.util.find_library("GL") or "libGL.so.1"
        get_string = ctypes.CDLL(library).glGetString
        get_string.restype = ctypes.c_char_p
        name = get_string(0x1F01)  # GL_RENDERER
        return name.decode(errors="replace") if name else ""
    except OSError:
        return ""
    finally:
        glfw.make_context_current(None)
        glfw.destroy_window(window)
        glfw.default_window_hints()


def software_renderer(name: str) -> bool:
    """Whether an OpenGL renderer name is a software rasteriser (Mesa's llvmpipe or softpipe, SwiftShader)."""
    lowered = name.lower()
    return any(word in lowered for word in ("llvmpipe", "softpipe", "swiftshader", "software"))


# ----- the scene ---------------------------------------------------------------------------------------------------
def _add(scene: mujoco.MjvScene, kind: int, size: Sequence[float], pos: Sequence[float], rgba: Sequence[float],
         yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0) -> None:  # fmt: skip
    """One geom at the end of ``scene`` (ignored when the scene is full), turned ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    import mujoco

    if scene.ngeom >= scene.maxgeom:
        return
    c, s = math.cos(yaw), math.sin(yaw)
    mat = np.array([c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0])
    if pitch or roll:
        cp, sp, cr, sr = math.cos(pitch), math.sin(pitch), math.cos(roll), math.sin(roll)
        tilt = np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])  # Ry(pitch) Rx(roll)
        mat = (mat.reshape(3, 3) @ tilt).ravel()
    mujoco.mjv_initGeom(
        scene.geoms[scene.ngeom], kind, np.asarray(size, float), np.asarray(pos, float), mat,
        np.asarray(rgba, np.float32),
    )  # fmt: skip
    scene.ngeom += 1


def draw_walk(scene: mujoco.MjvScene, walk: LiveWalk, sole: SoleRect) -> None:
    """Append the walk's footprints, ZMPs, DCMs and push arrow (module docstring) to ``scene``'s geoms."""
    import mujoco

    loop = walk.loop
    values = loop.last
    box, sphere = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_SPHERE
    half = (0.5 * (sole.front + sole.back), 0.5 * (sole.inner + sole.outer), 0.001)
    ahead = 0.5 * (sole.front - sole.back)  # the sole's centre ahead of the ankle (m)
    outward = 0.5 * (sole.outer - sole.inner)  # ... and outward of it
    step = max(0, (values.phase + 1) // 2)  # the step under way: its stance foot is F[step]
    base = loop.planner.walk.base if loop.planner.started else 0
    prints = loop.footprints()
    for index, foot in enumerate(prints, start=base):
        if not step - 2 <= index <= step + 4:
            continue
        c, s = math.cos(foot.yaw), math.sin(foot.yaw)
        side = 1.0 if foot.side == "left" else -1.0
        x = foot.x + c * ahead - s * side * outward
        y = foot.y + s * ahead + c * side * outward
        # On a tilted foothold the sole's centre is off its frame's level: h = z - tan(pitch) u + tan(roll) v.
        z = foot.z - math.tan(foot.pitch) * ahead + math.tan(foot.roll) * side * outward if not foot.level else 0.0
        rgba = _LEFT if foot.side == "left" else _RIGHT
        _add(scene, box, half, (x, y, z + 0.001), rgba, foot.yaw, foot.pitch, foot.roll)
    points = [values.zmp_planned, values.zmp_measured, values.dcm, values.dcm_planned]
    terrain = loop.sim.terrain
    lowest = min((foot.z for foot in prints), default=None)
    heights = ground_heights(terrain, np.array([p[:2] for p in points], dtype=float), lowest)
    for point, height, rgba, radius in zip(points, heights, (_ZMP_PLANNED, _ZMP_MEASURED, _DCM, _DCM_PLANNED),
                                           (0.02, 0.02, 0.025, 0.015), strict=True):  # fmt: skip
        if math.isfinite(point[0]) and math.isfinite(point[1]):
            _add(scene, sphere, (radius, radius, radius), (point[0], point[1], height + 0.005), rgba)
    force = loop.push_acting
    if force is not None and scene.ngeom < scene.maxgeom:
        x, y, z = loop.base_position
        size = math.hypot(*force)
        length = 0.25 + size / 400.0  # m: an arrow that grows with the force
        ux, uy, uz = (f / size for f in force) if size > 0.0 else (1.0, 0.0, 0.0)
        start = np.array([x - ux * length, y - uy * length, z - uz * length])
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3), np.eye(3).ravel(),
                            np.asarray(_PUSH, np.float32))  # fmt: skip
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_ARROW, 0.03, start, np.array([x, y, z]))
        scene.ngeom += 1


def _texts(walk: LiveWalk, pacer: Pacer) -> list[tuple[int, int, str, str]]:
    """The status (top left: :meth:`LiveWalk.status`, one item a line) and the keys (bottom left)."""
    import mujoco

    status = walk.status(pacer.real_time_factor, pacer.lagging).split(" | ")
    if walk.message:
        status.append(walk.message)
    font = mujoco.mjtFont.mjFONT_NORMAL  # mjr_overlay's font (the viewer's set_texts passes it on as is)
    return [
        (font, mujoco.mjtGridPos.mjGRID_TOPLEFT, "\n".join(status), ""),
        (font, mujoco.mjtGridPos.mjGRID_BOTTOMRIGHT, _KEY_NAMES, _KEY_HELP),
    ]


class _TextLine:
    """Hands the viewer its text lines from a thread of its own: ``Handle.set_texts`` waits (spinning, the GIL
    released) until the render thread has drawn the previous ones, a frame (tens of milliseconds with software
    OpenGL) the closed loop must not wait for. Only the latest lines are sent; older ones not yet sent are dropped."""

    def __init__(self, viewer: mujoco.viewer.Handle) -> None:
        self._viewer = viewer
        self._lines: list[tuple[int, int, str, str]] | None = None
        self._ready = threading.Condition()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name="rtgait-play-text", daemon=True)
        self._thread.start()

    def show(self, lines: list[tuple[int, int, str, str]]) -> None:
        with self._ready:
            self._lines = lines
            self._ready.notify()

    def close(self) -> None:
        with self._ready:
            self._closed = True
            self._ready.notify()
        self._thread.join(timeout=2.0)

    def _run(self) -> None:
        while True:
            with self._ready:
                while self._lines is None and not self._closed:
                    self._ready.wait()
                if self._closed:
                    return
                lines, self._lines = self._lines, None
            if not self._viewer.is_running():
                return
            self._viewer.set_texts(lines)  # type: ignore[arg-type]


# ----- the run -----------------------------------------------------------------------------------------------------
def play(
    walk: LiveWalk, sole: SoleRect, *, exit_after: float | None = None, screenshot: Path | None = None
) -> PlayOutcome:
    """Show ``walk`` in MuJoCo's viewer and run it in real time until the window is closed, or the walk's clock
    reaches ``exit_after`` (s), or (with ``exit_after``) the walk is over; then write ``screenshot`` (PNG).

    Raises:
        DisplayError: no window can be opened (:func:`check_display`).
    """
    software = software_renderer(check_display())
    try:
        import mujoco
        import mujoco.viewer
    except (ImportError, RuntimeError) as error:  # mujoco.viewer: GLFW's library handle missing
        raise DisplayError(f"play cannot load MuJoCo's viewer: {error}") from None
    loop = walk.loop
    sim, data = loop.sim, loop.data
    # The model has no light but the viewer's headlight, whose default leaves the floor in the dark: a brighter one
    # (visual only; the physics does not read it).
    headlight = sim.model.vis.headlight
    headlight.ambient[:], headlight.diffuse[:] = 0.35, 0.55
    threads = set(threading.enumerate())
    viewer = mujoco.viewer.launch_passive(
        sim.model, data, key_callback=walk.press, show_left_ui=False, show_right_ui=False
    )
    viewer_threads = set(threading.enumerate()) - threads
    with viewer.lock():
        viewer.cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        viewer.cam.trackbodyid = sim.base_body
        viewer.cam.distance, viewer.cam.elevation, viewer.cam.azimuth = 4.0, -35.0, 150.0
        if software:  # shadows and reflections render each frame several times over: too slow on a CPU
            for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION):
                viewer.user_scn.flags[flag] = 0
    clock = time.perf_counter
    pacer = Pacer(loop.dt)
    began = clock()
    pacer.start()
    frame = 1.0 / FRAME_RATE
    next_frame = began
    last_time = float(data.time)
    reason = "window closed"
    texts = _TextLine(viewer)
    next_text = began
    try:
        while viewer.is_running():
            walk.handle_keys()
            if not loop.done and (exit_after is None or loop.t < exit_after):
                due, ran = pacer.due(), 0
                while ran < due and not loop.done and (exit_after is None or loop.t < exit_after):
                    walk.step()
                    ran += 1
                    if ran % 16 == 0 and clock() > next_frame + frame:  # behind: draw now and then all the same
                        break
                pacer.ran(ran)
            if exit_after is not None and (loop.t >= exit_after or loop.done):
                reason = "exit-after" if loop.t >= exit_after else "walk over"
                break
            now = clock()
            if now >= next_frame:
                walk.track()
                with viewer.lock():
                    viewer.user_scn.ngeom = 0
                    draw_walk(viewer.user_scn, walk, sole)
                if now >= next_text:
                    texts.show(_texts(walk, pacer))
                    next_text = now + 1.0 / TEXT_RATE
                viewer.sync()
                if data.time < last_time - 1e-9:
                    reason = "reset by the viewer"
                    break
                last_time = float(data.time)
                next_frame = max(next_frame + frame, now)
            pause = max(0.0, next_frame - clock())
            if not loop.done:  # ticks run in batches: a sleep per tick would cost more than the tick
                pause = min(pause, pacer.wait(BATCH))
            if pause > 0.0:
                time.sleep(pause)
    finally:
        wall = clock() - began
        lines = _texts(walk, pacer)
        camera, options = viewer.cam, viewer.opt
        texts.close()
        viewer.close()  # returns once the viewer's render loop is over
        for thread in viewer_threads:
            thread.join(timeout=2.0)
    written = None
    if screenshot is not None:
        written = save_screenshot(screenshot, walk, sole, camera, options, lines)
    return PlayOutcome(wall, reason, pacer, written)


def save_screenshot(
    path: Path,
    walk: LiveWalk,
    sole: SoleRect,
    camera: mujoco.MjvCamera,
    options: mujoco.MjvOption,
    texts: Sequence[tuple[int, int, str, str]] = (),
    size: tuple[int, int] = SCREENSHOT_SIZE,
) -> Path:
    """Render the walk's state offscreen with ``camera`` and ``options``, its user geoms and ``texts`` (font,
    grid position, left and right text), and write it to ``path`` as a PNG (atomically). Returns ``path``."""
    import matplotlib.image
    import mujoco

    from rtgait.outputs import write_atomic

    model, data = walk.loop.sim.model, walk.loop.data
    width, height = size
    visual = model.vis.global_
    visual.offwidth, visual.offheight = max(visual.offwidth, width), max(visual.offheight, height)
    context = mujoco.GLContext(width, height)
    context.make_current()
    try:
        con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, con)
        scene = mujoco.MjvScene(model, 2000)
        mujoco.mjv_updateScene(model, data, options, None, camera, mujoco.mjtCatBit.mjCAT_ALL, scene)
        draw_walk(scene, walk, sole)
        viewport = mujoco.MjrRect(0, 0, width, height)
        mujoco.mjr_render(viewport, scene, con)
        for font, grid, left, right in texts:
            mujoco.mjr_overlay(font, grid, viewport, left, right, con)
        pixels = np.empty((height, width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(pixels, None, viewport, con)
        con.free()
    finally:
        context.free()
    image = np.flipud(pixels)  # OpenGL's rows run bottom to top

    def write(target: Path) -> None:
        matplotlib.image.imsave(target, image, format="png")

    write_atomic(path, write)
    return path
