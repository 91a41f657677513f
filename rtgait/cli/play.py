"""``rtgait play``: the robot walking in MuJoCo physics in real time in MuJoCo's viewer, driven from the keyboard."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtgait.cli.common import (
    PROG,
    RunError,
    add_state_options,
    asked_walking,
    check_state_options,
    load_robot,
    robot_walk,
    state_settings,
)
from rtgait.cli.control_file import controller_settings
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.interface.command import GAIN_SETS
from rtgait.io.summary_json import summary_text
from rtgait.outputs import OutputError, check_destination
from rtgait.robot.controller_info import robot_info
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import Scenario, ScenarioError

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel
    from rtgait.sim.live import LiveWalk

COMMAND_SCENARIO = "fig8"
"""The built-in scenario whose timing a walk by command takes (T_s 0.7 s, T_dbl 0.1 s, quasi-real-time)."""
KEEP = 10.0
"""Seconds of the per-tick record kept (a ring): the memory of a live run stays bounded however long it lasts."""
PUSH_SPEED = 0.15
"""Default push: the change of the robot's COM speed (m/s) it would give the free robot over 0.1 s, so the force
scales with the robot: 135 N for Talos (90 kg), 53 N for G1; a third of what the adaptive level recovers forward on
Talos (README, pushes)."""


def add_parser(commands: Any) -> None:
    play = commands.add_parser(
        "play",
        help="walk the robot in MuJoCo physics in real time in MuJoCo's viewer, driven from the keyboard",
        description="Walk the robot in MuJoCo physics at real-time pace in MuJoCo's interactive viewer. Without a "
        "scenario the walk follows a velocity command set from the keyboard (Up/Down forward and backward, "
        "Left/Right turning, Delete/Page Down sideways, Space stops); a scenario or footstep-plan file is walked "
        "as planned, and the keys only push (Enter), switch the controller level (Insert) and stop (Space). "
        "The scene shows the footprints, the planned (blue) and measured (red) ZMP and the DCM (green). Needs a "
        "display (e.g. xvfb-run for scripts).",
        epilog="keys: Up/Down forward speed +-0.05 m/s, Left/Right yaw rate +-0.05 rad/s, Delete/Page Down "
        "sideways speed +-0.02 m/s, Space stop, Enter push, Insert next controller level. MuJoCo's viewer binds "
        "every letter key to its own visual toggles (and Backspace resets it): they are not used here.",
    )
    play.add_argument(
        "scenario", metavar="SCENARIO", nargs="?", help="built-in scenario or scenario/footstep-plan .toml file to "
        f"walk as planned (default: walk by velocity command with {COMMAND_SCENARIO}'s timing)",
    )  # fmt: skip
    play.add_argument("--robot", metavar="NAME_OR_FILE", default="talos", help="robot (default talos)")
    play.add_argument(
        "--controller", choices=CONTROLLER_LEVELS, default="adaptive", help="controller level to start with (default "
        "adaptive; Insert switches it while walking)",
    )  # fmt: skip
    play.add_argument(
        "--gains", choices=GAIN_SETS, default="stiff", help="the drives' own gains: stiff (default) or "
        "robot, the real robot's, with feed-forward torques (as rtgait simulate)",
    )  # fmt: skip
    play.add_argument(
        "--drive", choices=("position", "torque"), default="position", help="position (default) or torque: the "
        "motion carried by feed-forward torques under a tenth of the robot's gains (as rtgait simulate)",
    )  # fmt: skip
    play.add_argument(
        "--exit-after", metavar="SECONDS", type=float, help="end when the walk's clock reaches SECONDS (simulated "
        "time since the walk started, after the 1.5 s start transition), or earlier if a planned walk ends or the "
        "robot falls; without it, play runs until the window is closed",
    )  # fmt: skip
    play.add_argument("--screenshot", metavar="PATH", type=Path, help="write a PNG of the last frame at the end")
    play.add_argument("--summary", metavar="PATH", type=Path, help="write the outcome as JSON at the end")
    play.add_argument(
        "--push-force", metavar="N", type=float, help="force of the push key's 0.1 s push on the base (N; default "
        f"the robot's mass times {PUSH_SPEED / 0.1:g} m/s^2)",
    )  # fmt: skip
    add_state_options(play)
    play.add_argument("--quiet", action="store_true", help="print nothing but errors")


def _check_options(args: argparse.Namespace) -> None:
    """The options that can be refused before anything loads: one line each."""
    check_state_options(args)
    if args.exit_after is not None and not (math.isfinite(args.exit_after) and 0.0 < args.exit_after <= 3600.0):
        raise ScenarioError(f"--exit-after must be a time in (0, 3600] s, got {args.exit_after:g}")
    if args.push_force is not None and not (math.isfinite(args.push_force) and 0.0 < args.push_force <= 5000.0):
        raise ScenarioError(f"--push-force must be a force in (0, 5000] N, got {args.push_force:g}")
    for option, path, suffix in (("--screenshot", args.screenshot, ".png"), ("--summary", args.summary, ".json")):
        if path is None:
            continue
        if path.suffix.lower() != suffix:
            raise ScenarioError(f"{option} must name a {suffix} file, got {str(path)!r}")
        try:
            if path.is_dir() or not path.parent.is_dir():
                raise ScenarioError(f"{option} {str(path)!r}: its folder does not exist")
            check_destination(path.parent, [path.name])  # written at the end: refused now, not after the walk
        except OutputError as error:
            raise OutputError(f"{option}: {error}") from None
        except OSError as error:  # a name the file system refuses (too long)
            raise OutputError(f"{option}: cannot write {path}: {error.strerror or error}") from None


def _requirements(screenshot: bool) -> None:
    """The extras play needs, checked before the window opens."""
    try:
        import mujoco  # noqa: F401
        import pinocchio  # noqa: F401
    except ImportError:
        raise RunError("play needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'") from None
    if screenshot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise RunError("--screenshot writes its PNG with matplotlib: pip install 'rtgait[viz]'") from None


def _scenario(name: str | None) -> tuple[Scenario, bool]:
    """The walk: a scenario walked as planned, or ``COMMAND_SCENARIO``'s timing walked by command."""
    if name is None:
        return load_scenario(COMMAND_SCENARIO), True
    scenario = load_scenario(name)
    if scenario.guide is not None:
        raise ScenarioError(f"{scenario.name} is led by the hand ([guide]): walk it with 'rtgait simulate'")
    return scenario, False


def _live_walk(
    scenario: Scenario,
    by_command: bool,
    robot: RobotModel,
    level: str,
    push_force: float | None,
    args: argparse.Namespace,
    gains: str = "stiff",
    drive: str = "position",
) -> tuple[LiveWalk, Scenario]:
    """The controller, the closed loop and the live walk of ``scenario`` on ``robot``, with the state, sensors and
    model error of ``args`` (:func:`~rtgait.cli.common.state_settings`)."""
    from rtgait.control.controller import make_controller
    from rtgait.io.sim_run import obstacle_reactions, planned_walk
    from rtgait.robot.motion import whole_body_motion
    from rtgait.sim.live import LiveWalk
    from rtgait.sim.loop import ClosedLoop, LoopOptions
    from rtgait.sim.model import SimConfig, build_sim_model

    state, sensors, model_error = state_settings(args)
    walk = robot_walk(scenario, robot)
    settings, _ = controller_settings(robot.description, scenario, None, (), gains)  # the [control] tables, as simulate
    if not by_command:  # as simulate does: a walk the robot cannot reach is refused before it starts
        with asked_walking(scenario, robot):
            whole_body_motion(robot, planned_walk(scenario, robot))
    obstacles = () if by_command else walk.obstacles  # drawn, and stepped around when seen
    terrain = None if by_command or walk.terrain is None else walk.terrain.terrain
    config = SimConfig(gains=gains, sensors=sensors, model_error=model_error)
    sim = build_sim_model(robot, config, obstacles, terrain)
    strides = None if by_command else walk.strides()
    controller = make_controller(
        level,
        walk.planner_config(),
        strides,
        walk.sole,
        robot_info(robot, gains=gains),  # the lean bounded by the hips' servos at the robot's gains, as simulate
        dt=sim.control_dt,
        options=settings,
        terrain=None if by_command else walk.placed_on,
    )
    options = LoopOptions(
        changes=() if by_command else walk.changes, reactions=obstacle_reactions(walk) if obstacles else (),
        drive=drive, state=state,  # type: ignore[arg-type]
    )  # fmt: skip
    loop = ClosedLoop(sim, controller, options, keep=KEEP)
    force = push_force if push_force is not None else robot.mass * PUSH_SPEED / 0.1
    return LiveWalk(loop, by_command, force), walk


def run(args: argparse.Namespace) -> int:
    _check_options(args)
    scenario, by_command = _scenario(args.scenario)
    _requirements(args.screenshot is not None)
    # Every argument and file is checked before the display is: a bad --robot file is bad input (exit 2) with or
    # without a display. Loading a robot takes well under a second.
    robot = load_robot(args.robot, scenario)
    from rtgait.viz.live_view import DisplayError, check_display, play

    try:
        check_display()
    except DisplayError as error:
        raise RunError(str(error)) from None
    from rtgait.io.sim_run import mujoco_messages

    live, walk = _live_walk(
        scenario, by_command, robot, args.controller, args.push_force, args, args.gains, args.drive
    )  # fmt: skip
    if not args.quiet:
        what = "by velocity command" if by_command else f"{scenario.name} as planned"
        print(f"{PROG}: play: {robot.name}, {args.controller}, walking {what}; close the window to end", flush=True)
    with mujoco_messages() as messages:
        try:
            outcome = play(live, walk.sole, exit_after=args.exit_after, screenshot=args.screenshot)
        except DisplayError as error:
            raise RunError(str(error)) from None
    summary = live.summary(outcome.wall_time, outcome.pacer)
    sensors = live.loop.sim.config.sensors
    summary.update(
        scenario=None if by_command else scenario.name, end=outcome.reason, mujoco_warnings=messages,
        state=live.loop.options.state,
        sensors={**dataclasses.asdict(sensors), "latency": live.loop.robot.sensors.latency},
        model_error=None if live.loop.sim.model_error is None else live.loop.sim.model_error.summary(),
        screenshot=None if outcome.screenshot is None else str(outcome.screenshot),
    )  # fmt: skip
    if args.summary is not None:
        from rtgait.outputs import write_text_atomic

        try:
            write_text_atomic(args.summary, summary_text(summary))
        except OSError as error:  # a full disk, or the folder changed during the walk
            raise OutputError(f"--summary: cannot write {args.summary}: {error.strerror or error}") from None
    if not args.quiet:
        print(_summary_line(summary))
    return 0


def _summary_line(summary: dict[str, Any]) -> str:
    """One line: distance, steps, fall, pace."""
    dx, dy = summary["displacement"]
    fell = f"fell at {summary['fall_time']:.2f} s ({summary['fall_cause']})" if summary["fell"] else "did not fall"
    rate = summary["real_time_factor"]
    return (
        f"{PROG}: play: walked {summary['distance_walked']:.2f} m (x {dx:+.2f}, y {dy:+.2f} m, turned "
        f"{math.degrees(summary['yaw_turned']):+.0f} deg) in {summary['steps_completed']} steps over "
        f"{summary['walk_time']:.1f} s of walk, {fell}; real-time factor {rate:.2f} ({summary['end']})"
        if rate is not None
        else f"{PROG}: play: nothing simulated ({summary['end']})"
    )
