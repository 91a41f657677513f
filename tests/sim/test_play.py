"""``rtgait play``: the keys and the velocity command they set, the pacing, the one-line errors, and the robot
walking where the keys said in MuJoCo's viewer under Xvfb, keys sent to the window with xdotool."""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest

from rtgait.core.geometry.footsteps import Timing
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.walk.walk import VelocityCommand
from rtgait.robot.controller_info import robot_info
from rtgait.sim.live import KEYS, CommandLimits, Increments, Pacer, command_after, key_action

RTGAIT = [sys.executable, "-m", "rtgait"]
ROOT = Path(__file__).resolve().parents[2]


# ----- keys -> command ---------------------------------------------------------------------------------------------
def test_the_keys_are_glfw_s_codes():
    glfw = pytest.importorskip("glfw")  # its constants, the codes mujoco.viewer's key_callback receives
    names = {
        "Up": "KEY_UP", "Down": "KEY_DOWN", "Left": "KEY_LEFT", "Right": "KEY_RIGHT", "Delete": "KEY_DELETE",
        "Page Down": "KEY_PAGE_DOWN", "Space": "KEY_SPACE", "Enter": "KEY_ENTER", "Insert": "KEY_INSERT",
    }  # fmt: skip
    for key in KEYS:
        assert key.code == getattr(glfw, names[key.name]), key.name
    assert key_action(glfw.KEY_W) is None, "letters are MuJoCo's viewer's"


def test_each_press_steps_one_component_within_the_limits():
    limits = CommandLimits(vx=0.3, vy=0.06, wz=0.25)
    steps = Increments(vx=0.05, vy=0.02, wz=0.05)
    command = VelocityCommand()
    for _ in range(3):
        command = command_after(command, "forward", limits, steps)
    assert (command.vx, command.vy, command.wz) == pytest.approx((0.15, 0.0, 0.0), abs=1e-15)
    command = command_after(command, "turn-left", limits, steps)
    command = command_after(command, "right", limits, steps)
    assert (command.vx, command.vy, command.wz) == pytest.approx((0.15, -0.02, 0.05), abs=1e-15)
    for _ in range(20):  # held at the limits, on the grid, signs kept
        command = command_after(command, "backward", limits, steps)
        command = command_after(command, "turn-right", limits, steps)
    assert (command.vx, command.vy, command.wz) == (-0.3, pytest.approx(-0.02), -0.25)
    for _ in range(6):  # and back exactly to zero, no round-off left
        command = command_after(command, "forward", limits, steps)
    assert command.vx == 0.0
    assert command_after(command, "stop", limits, steps) == VelocityCommand()
    assert command_after(command, "push", limits, steps) == command


def test_the_limits_are_the_planner_s_own():
    """At the limits the planner takes the command as it is; just beyond, it clamps it (and warns)."""
    from rtgait.core.planner.online import CommandClampedWarning, OnlinePlanner

    config = PlannerConfig(timing=Timing(0.7, 0.1))
    limits = CommandLimits.from_config(config)
    planner = OnlinePlanner(config, None)
    for vx, vy, wz in ((limits.vx, 0.0, 0.0), (0.0, limits.vy, 0.0), (0.0, 0.0, -limits.wz)):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            planner.set_velocity(vx, vy, wz)
        with pytest.warns(CommandClampedWarning):
            planner.set_velocity(vx * 1.01, vy * 1.01, wz * 1.01)


def test_the_pacer_runs_what_is_due_and_gives_up_a_backlog():
    now = [0.0]
    pacer = Pacer(0.001, max_lag=0.1, clock=lambda: now[0])
    pacer.start()
    now[0] = 0.0105
    assert pacer.due() == 10
    pacer.ran(10)
    assert pacer.due() == 0 and pacer.wait(5) == pytest.approx(0.014 - 0.0105)  # tick k is due at k dt
    now[0] = 1.0  # the loop stalled for a second: 0.1 s of it is made up, the rest given up
    assert pacer.due() == 100
    assert pacer.dropped == pytest.approx(1.0 - 0.0105 - 0.1 + 0.0005, abs=1e-9) and pacer.lagging
    pacer.ran(100)
    now[0] = 2.5
    pacer.ran(0)
    assert not pacer.lagging
    assert pacer.real_time_factor < 0.2  # 0.11 s simulated over the last 2.5 s of wall time


# ----- the command line --------------------------------------------------------------------------------------------
def run_play(*args: str, env: dict[str, str] | None = None, timeout: float = 60.0) -> subprocess.CompletedProcess:
    environment = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    return subprocess.run(
        [*RTGAIT, "play", *args], capture_output=True, text=True, env=environment, timeout=timeout, cwd=ROOT
    )


def test_without_a_display_it_says_so_in_one_line():
    pytest.importorskip("mujoco")
    pytest.importorskip("pinocchio")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([*RTGAIT, "play"], capture_output=True, text=True, env={**env, "PYTHONPATH": str(ROOT)},
                          timeout=60, cwd=ROOT)  # fmt: skip
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and "DISPLAY is not set" in done.stderr, done.stderr
    assert done.stdout == ""
    dead = run_play(env={"DISPLAY": ":987"})  # a display with no server
    assert dead.returncode == 1 and dead.stderr.count("\n") == 1 and "cannot open a window" in dead.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--exit-after", "-1"], "--exit-after must be a time"),
        (["--exit-after", "nan"], "--exit-after must be a time"),
        (["--screenshot", "shot.jpg"], "--screenshot must name a .png file"),
        (["--summary", "no/such/folder/s.json"], "its folder does not exist"),
        (["--push-force", "0"], "--push-force must be a force"),
        (["--controller", "closed"], "invalid choice"),
        (["--state", "guessed"], "invalid choice: 'guessed'"),
        (["--sensor-noise", "nan"], "--sensor-noise must be a finite factor >= 0"),
        (["--latency", "-1"], "--latency must be a whole number"),
        (["--model-error", "-1"], "--model-error must be an integer seed >= 0"),
        (["guided"], "led by the hand"),
        (["no-such-scenario"], "no-such-scenario"),
    ],
)
def test_bad_options_give_one_line_errors(args, message):
    done = run_play(*args, env={"DISPLAY": ":987"})
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and message in done.stderr, done.stderr
    assert done.stderr.startswith("rtgait: error: ")


# ----- for real, under Xvfb ----------------------------------------------------------------------------------------
@contextlib.contextmanager
def xvfb():
    """A virtual X display (Debian's xvfb), 800 x 600 so that software OpenGL draws quickly."""
    number = next(n for n in range(90, 200) if not Path(f"/tmp/.X{n}-lock").exists())
    server = subprocess.Popen(
        ["Xvfb", f":{number}", "-screen", "0", "800x600x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        for _ in range(100):
            if Path(f"/tmp/.X11-unix/X{number}").exists():
                break
            time.sleep(0.05)
        yield f":{number}"
    finally:
        server.terminate()
        server.wait(timeout=10)


def xdotool(display: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["xdotool", *args], capture_output=True, text=True, env={**os.environ, "DISPLAY": display})


def window(display: str, process: subprocess.Popen, timeout: float = 30.0) -> str:
    """The id of MuJoCo's viewer window once it is mapped."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and process.poll() is None:
        found = xdotool(display, "search", "--onlyvisible", "--name", "MuJoCo").stdout.split()
        if found:
            return found[0]
        time.sleep(0.2)
    raise AssertionError(f"no viewer window within {timeout:g} s: {process.stderr.read() if process.stderr else ''}")


@pytest.mark.skipif(shutil.which("Xvfb") is None or shutil.which("xdotool") is None, reason="needs xvfb and xdotool")
def test_the_robot_walks_where_the_keys_say(tmp_path):
    """Up four times: 0.2 m/s forward; 7 s later Left four times: 0.2 rad/s to the left; then a push and the levels
    round. The base went forward, not sideways, then turned left; Talos did not fall; the screenshot is a picture."""
    pytest.importorskip("mujoco")
    pytest.importorskip("pinocchio")
    pytest.importorskip("matplotlib")
    shot, summary = tmp_path / "last.png", tmp_path / "play.json"
    with xvfb() as display:
        process = subprocess.Popen(
            # On the truth: this tests the keys; a walk paced by a loaded machine's wall clock that cycles the levels
            # on the estimate fell once in a full-suite run (docs/estimation.md measures the estimate's walks).
            [*RTGAIT, "play", "--robot", "talos", "--state", "truth", "--exit-after", "12", "--screenshot", str(shot),
             "--summary", str(summary)],
            env={**os.environ, "DISPLAY": display, "PYTHONPATH": str(ROOT)}, cwd=ROOT, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        try:
            wid = window(display, process)
            xdotool(display, "windowfocus", wid)  # no window manager: give it the keyboard
            xdotool(display, "key", "--window", wid, "--delay", "50", "Up", "Up", "Up", "Up")
            time.sleep(7.0)  # some 5 s of walk at real time; the checks below hold down to half of that
            xdotool(display, "key", "--delay", "50", "Left", "Left", "Left", "Left")
            time.sleep(1.5)
            xdotool(display, "key", "Return")
            time.sleep(0.5)
            xdotool(display, "key", "--delay", "100", "Insert", "Insert", "Insert")
            out, err = process.communicate(timeout=60)
        finally:
            if process.poll() is None:
                process.kill()
    assert process.returncode == 0, err
    assert out.strip().splitlines()[-1].startswith("rtgait: play: walked"), out
    result = json.loads(summary.read_text())
    actions = [key["action"] for key in result["keys"]]
    assert actions[:4] == ["forward"] * 4 and actions.count("turn-left") == 4, actions
    assert not result["fell"] and result["end"] == "exit-after"
    assert result["state"] == "truth"
    assert result["command"] == pytest.approx([0.2, 0.0, 0.2])
    turned_at = next(key["t"] for key in result["keys"] if key["action"] == "turn-left")
    # Until the turn: forward at 0.2 m/s (from the walk's start), not sideways, heading kept.
    straight = [p for p in result["path"] if p[0] <= turned_at]
    t, x, y, yaw = straight[-1]
    assert t > 1.5 and x > 0.2 and x > 0.5 * 0.2 * t, straight
    assert abs(y) < 0.25 * x and abs(yaw) < 0.1
    # Then it turned left: 0.2 rad/s for the rest of the walk, at least half of it in yaw.
    assert result["yaw_turned"] > 0.5 * 0.2 * (result["walk_time"] - turned_at - 1.0) > 0.1
    assert result["steps_completed"] >= 8
    assert len(result["pushes"]) == 1 and result["pushes"][0]["duration"] == 0.1
    assert result["levels"] == ["adaptive", "open-loop", "stabilized", "adaptive"]
    # The last frame: a PNG of the window's picture, not a blank one.
    import matplotlib.image

    image = matplotlib.image.imread(shot)
    assert image.shape[:2] == (720, 960)
    assert image[..., :3].std() > 0.05 and len({tuple(p) for p in image[::20, ::20, :3].reshape(-1, 3)}) > 20
    assert math.isfinite(result["real_time_factor"])


def test_the_scene_shows_the_plan_s_footprints_and_the_tick_s_points(talos):
    """draw_walk's geoms: a sole rectangle on each footprint around the step under way (centred where the sole's
    front/back and inner/outer extents put it), the planned ZMP and the DCMs where the loop says, an arrow during a
    push. No window needed: an mjvScene is plain memory."""
    mujoco = pytest.importorskip("mujoco")
    pytest.importorskip("pinocchio")
    import numpy as np

    from rtgait.control.controller import make_controller
    from rtgait.robot.motion import robot_scenario
    from rtgait.scenario.loading import load_scenario
    from rtgait.sim.live import LiveWalk
    from rtgait.sim.loop import ClosedLoop, LoopOptions
    from rtgait.sim.model import SimConfig, build_sim_model
    from rtgait.viz.live_view import draw_walk

    sim = build_sim_model(talos, SimConfig(meshes=False))
    walk = robot_scenario(load_scenario("fig8"), talos)
    level = make_controller("stabilized", walk.planner_config(), walk.strides(), walk.sole, robot_info(talos))
    live = LiveWalk(ClosedLoop(sim, level, LoopOptions(start_ramp=0.2, start_hold=0.1), keep=0.0), False, 50.0)
    while live.loop.t < 1.0:  # into step 1's single support
        live.step()
    live.act("push")
    live.step()
    scene = mujoco.MjvScene(sim.model, 100)
    draw_walk(scene, live, walk.sole)
    geoms = [scene.geoms[i] for i in range(scene.ngeom)]
    boxes = [g for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_BOX]
    spheres = [g for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_SPHERE]
    arrows = [g for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_ARROW]
    values, sole = live.loop.last, walk.sole
    step = (values.phase + 1) // 2
    shown = [f for i, f in enumerate(live.loop.footprints()) if step - 2 <= i <= step + 4]
    assert len(boxes) == len(shown) >= 4
    for box, foot in zip(boxes, shown, strict=True):
        side = 1.0 if foot.side == "left" else -1.0
        local = np.array([(sole.front - sole.back) / 2, side * (sole.outer - sole.inner) / 2])
        c, s = np.cos(foot.yaw), np.sin(foot.yaw)
        centre = np.array([foot.x, foot.y]) + np.array([[c, -s], [s, c]]) @ local
        assert np.allclose(box.pos[:2], centre, atol=1e-6)
        assert np.allclose(box.size[:2], [(sole.front + sole.back) / 2, (sole.inner + sole.outer) / 2], atol=1e-6)
    assert np.allclose(spheres[0].pos[:2], values.zmp_planned, atol=1e-6)
    assert np.allclose(spheres[-2].pos[:2], values.dcm, atol=1e-6)
    assert np.allclose(spheres[-1].pos[:2], values.dcm_planned, atol=1e-6)
    assert len(arrows) == 1 and live.loop.push_acting is not None
