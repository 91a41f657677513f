"""``rtgait simulate``: walk a scenario in closed loop, on a robot in MuJoCo physics or on the point-mass pendulum."""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtgait.commands.common import (
    PROG,
    RunError,
    add_format_option,
    check_run_length,
    load_robot,
    numbers,
    out_folder,
    progress_printer,
    require_extras,
    robot_walk,
)
from rtgait.outputs import check_destination, staged_outputs
from rtgait.report import pendulum_report, simulation_report
from rtgait.scenario import Scenario, ScenarioError, load_scenario

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel
    from rtgait.sim.loop import Push, SimResult

MODELS = ("mujoco", "lipm")
"""What ``--model`` can simulate: the robot in MuJoCo, or the linear inverted pendulum's point mass."""
CONTROLLERS = ("open-loop", "stabilized", "adaptive")
"""The controller levels (``docs/closed_loop.md``)."""


def add_parser(commands: Any) -> None:
    simulate = commands.add_parser(
        "simulate",
        help="walk a scenario on a robot in MuJoCo physics (planner + whole-body IK + position servos at 1 kHz)",
        description="Walk the scenario in closed loop in MuJoCo at 1 kHz: each tick the online planner samples, "
        "the whole-body IK solves and the joint servos track; the measured ZMP (centre of pressure of the contact "
        "forces), base pose, COG and contacts are logged, and falls end the run. Writes sim.csv, summary.json "
        "and zmp_sim.png (and with --html, replay.html: the simulated motion in 3D). A scenario with a [guide] path "
        "(e.g. guided) is walked led by the hand: a person pulls the robot's hand along it. A walk the robot "
        "cannot reach kinematically is refused before simulating, as by plan --robot.",
    )
    simulate.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or scenario .toml file")
    simulate.add_argument(
        "--model",
        choices=MODELS,
        default="mujoco",
        help="mujoco (default): the robot in MuJoCo physics; lipm: a point mass on the linear inverted pendulum, "
        "its ZMP the commanded one clipped to the feet on the ground (numpy only, no robot model needed)",
    )
    simulate.add_argument(
        "--controller",
        choices=CONTROLLERS,
        help="open-loop (the plan alone, the paper's assumption), stabilized (+ DCM feedback) or adaptive (+ "
        "replanning from the measured state, step adjustment, re-anchoring on landings); default: adaptive with "
        "--model lipm; MuJoCo runs open-loop for now (--stabilizer adds its COG-shift stabiliser)",
    )
    simulate.add_argument(
        "--robot",
        metavar="NAME_OR_FILE",
        help="robot (default talos with --model mujoco); with --model lipm, its COG height, sole, step width and "
        "mass replace the scenario's",
    )
    simulate.add_argument(
        "--mass", metavar="KG", type=float, help="--model lipm: the point mass (default the scenario's, else 57 kg)"
    )
    simulate.add_argument(
        "--control-dt", metavar="S", type=float, help="--model lipm: control period (default 0.001 s)"
    )
    simulate.add_argument("--out", metavar="DIR", type=out_folder, help="output folder (default: out/<scenario>-sim)")
    simulate.add_argument(
        "--velocity",
        metavar="VX,VY,WZ",
        help="walk the scenario's number of steps by a velocity command instead of its footsteps (m/s, m/s, rad/s)",
    )
    simulate.add_argument(
        "--push",
        metavar="T,DURATION,FX,FY",
        action="append",
        default=[],
        help="push the base with a horizontal force (N) from time T (s, from the start of the run) for DURATION "
        "(s); may be repeated, for pushes that do not overlap",
    )
    simulate.add_argument("--stabilizer", action="store_true", help="turn the ZMP/COG feedback stabiliser on")
    simulate.add_argument("--no-figures", action="store_true", help="skip zmp_sim.png")
    add_format_option(
        simulate,
        default=None,  # None: not given, which the MuJoCo run must tell from an explicit png
        description="--model lipm: file format of pendulum.png, png (default), pdf or svg (the MuJoCo run writes PNG)",
    )
    simulate.add_argument(
        "--html", action="store_true", help="write replay.html, a 3D replay of the simulated motion (needs meshcat)"
    )
    simulate.add_argument("--quiet", action="store_true", help="print nothing on success")


def _push_values(texts: Sequence[str], run_time: float) -> list[tuple[float, float, float, float]]:
    """The ``--push`` options as ``(start, duration, fx, fy)`` (s, s, N, N), refusing what would silently not
    happen: a push that starts after the run (``run_time``, s) has ended, and overlapping pushes (the MuJoCo loop
    applies one at a time, so the later one would cut the earlier one short)."""
    pushes = []
    for text in texts:
        start, duration, fx, fy = numbers(text, 4, "--push")
        if not start >= 0.0:
            raise ScenarioError(f"--push start must be a time >= 0 s, got {start:g} in {text!r}")
        if not duration > 0.0:
            raise ScenarioError(f"--push duration must be > 0 s, got {duration:g} in {text!r}")
        if start >= run_time:
            raise ScenarioError(f"--push {text} starts after the run has ended (at {run_time:.2f} s)")
        pushes.append((start, duration, fx, fy))
    ordered = sorted(zip(pushes, texts, strict=True), key=lambda pair: pair[0][0])
    for (first, first_text), (second, second_text) in itertools.pairwise(ordered):
        if second[0] < first[0] + first[1]:
            raise ScenarioError(f"--push {first_text} and --push {second_text} overlap: pushes act one at a time")
    return pushes


def _pushes(texts: Sequence[str], run_time: float) -> list[Push]:
    """The ``--push`` options as the MuJoCo loop's pushes (:func:`_push_values`)."""
    from rtgait.sim.loop import Push

    pushes = []
    for start, duration, fx, fy in _push_values(texts, run_time):
        try:
            pushes.append(Push(start=start, duration=duration, force=(fx, fy, 0.0)))
        except ValueError as error:  # "push start must be ..."
            raise ScenarioError(f"--{error}") from None
    return pushes


def run(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.scenario)
    out: Path = args.out if args.out is not None else Path("out") / f"{scenario.name}-sim"
    if args.model == "lipm":
        return _simulate_pendulum(args, scenario, out)
    for option in ("mass", "control_dt"):
        if getattr(args, option) is not None:
            raise ScenarioError(f"--{option.replace('_', '-')} is for --model lipm")
    if args.figure_format not in (None, "png"):  # zmp_sim.png is drawn by rtgait.sim.run, in PNG only for now
        raise ScenarioError(f"--format {args.figure_format} is for --model lipm: the MuJoCo run writes zmp_sim.png")
    if args.controller not in (None, "open-loop"):
        raise ScenarioError(
            f"--controller {args.controller} is not wired into the MuJoCo loop yet: use --model lipm, or open-loop "
            "(with --stabilizer for the loop's COG-shift stabiliser)"
        )
    args.robot = args.robot or "talos"
    velocity = None if args.velocity is None else numbers(args.velocity, 3, "--velocity")
    try:
        from rtgait.robot.motion import whole_body_motion
        from rtgait.sim.run import mujoco_messages, planned_walk
    except ImportError:
        raise RunError("simulate needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'") from None
    pushes = _check_simulation(args, scenario, velocity, out)
    robot = load_robot(args.robot)
    walk = robot_walk(scenario, robot)
    # The check of `plan --robot`, on the walk the simulation will ask for: a robot that cannot reach it is refused.
    whole_body_motion(robot, planned_walk(scenario, robot, velocity))
    show = not args.quiet and sys.stderr.isatty()
    progress = progress_printer(sys.stderr, f"{PROG}: simulating {scenario.name}") if show else None
    extra: dict[str, Any] = {"scenario": scenario.name, "connection": scenario.connection}
    extra["stabilizer"] = args.stabilizer
    with mujoco_messages() as messages:  # else MuJoCo appends them to MUJOCO_LOG.TXT in the working folder
        result = _physics(scenario, walk, robot, velocity, pushes, args.stabilizer, progress, extra)
    extra["mujoco_warnings"] = messages
    if show:
        sys.stderr.write("\r\033[K")
    summary = _write_simulation(result, scenario, walk, robot, out, not args.no_figures, args.html, extra)
    if not args.quiet:
        sys.stdout.write(simulation_report(summary, out))
    return 0


def _simulate_pendulum(args: argparse.Namespace, scenario: Scenario, out: Path) -> int:
    """``simulate --model lipm``: the walk on the point-mass pendulum at the controller level asked for."""
    from rtgait.pendulum_sim import PENDULUM_FILES, simulate_pendulum, write_pendulum_outputs
    from rtgait.viz.run_data import PENDULUM_FIGURE, figure_file

    for option, why in (("velocity", "walks by command"), ("html", "the 3D replay"), ("stabilizer", "its stabiliser")):
        if getattr(args, option):
            raise ScenarioError(f"--{option} ({why}) is for --model mujoco")
    if scenario.guide is not None:
        raise ScenarioError(f"{scenario.name} is led by the hand ([guide]): that needs --model mujoco")
    mass = args.mass
    if args.robot is not None:
        robot = load_robot(args.robot)
        scenario = robot_walk(scenario, robot)
        mass = robot.mass if mass is None else mass
    if mass is not None and not (math.isfinite(mass) and 1.0 <= mass <= 500.0):
        raise ScenarioError(f"--mass must be within [1, 500] kg, got {mass}")
    dt = 0.001 if args.control_dt is None else args.control_dt
    if not (math.isfinite(dt) and 1e-5 <= dt <= min(scenario.timing.single_support, scenario.timing.double_support)):
        raise ScenarioError(f"--control-dt must be within [1e-05 s, the shortest phase], got {dt}")
    run_time = scenario.duration + 0.5
    check_run_length(run_time, dt)
    pushes = _push_values(args.push, run_time)
    figures = not args.no_figures
    require_extras(figures, html=False)
    figure_name = figure_file(PENDULUM_FIGURE, args.figure_format or "png")
    check_destination(out, [*PENDULUM_FILES, *([figure_name] if figures else [])])
    controller = args.controller or "adaptive"
    show = not args.quiet and sys.stderr.isatty()
    progress = progress_printer(sys.stderr, f"{PROG}: simulating {scenario.name}") if show else None
    try:
        result = simulate_pendulum(scenario, controller, pushes, mass=mass, dt=dt, progress=progress)
    except ValueError as error:  # a push beyond physical sense, caught by the plant
        raise ScenarioError(f"--push: {error}") from None
    if show:
        sys.stderr.write("\r\033[K")
    extra = {"scenario": scenario.name, "connection": scenario.connection}
    with staged_outputs(out) as staging:
        summary = write_pendulum_outputs(result, staging.folder, extra)
        for name in summary["files"]:
            staging.add(name)
        if figures:
            from rtgait.viz.pendulum import plot_pendulum

            plot_pendulum(result, staging.add(figure_name), title=f"{scenario.name} ({scenario.connection})")
            summary["files"].append(figure_name)
            text = json.dumps(summary, indent=2, allow_nan=False) + "\n"  # again, now listing the figure
            (staging.folder / "summary.json").write_text(text, encoding="utf-8")
    if not args.quiet:
        sys.stdout.write(pendulum_report(summary, out))
    return 0


def _check_simulation(
    args: argparse.Namespace, scenario: Scenario, velocity: tuple[float, ...] | None, out: Path
) -> list[Push]:
    """Everything about a simulation that can be checked before loading the robot; returns the pushes."""
    from rtgait.sim.model import SimConfig
    from rtgait.sim.run import SIM_FILES, simulated_time

    run_time = simulated_time(scenario, velocity=velocity)
    check_run_length(run_time, SimConfig().timestep)
    pushes = _pushes(args.push, run_time)
    figures = not args.no_figures
    require_extras(figures, args.html)
    names = [name for name in SIM_FILES if figures or name != "zmp_sim.png"] + (["replay.html"] if args.html else [])
    check_destination(out, names)
    return pushes


def _physics(
    scenario: Scenario,
    walk: Scenario,
    robot: RobotModel,
    velocity: tuple[float, ...] | None,
    pushes: list[Push],
    stabilizer: bool,
    progress: Callable[[float], None] | None,
    extra: dict[str, Any],
) -> SimResult:
    """Walk ``scenario`` (as ``robot`` walks it: ``walk``) in MuJoCo; a guided walk's outcome goes into ``extra``."""
    from rtgait.sim.run import loop_options, simulate

    if scenario.guide is None or velocity is not None:
        return simulate(scenario, robot, velocity=velocity, push=pushes or None, stabilizer=stabilizer,
                        progress=progress)  # fmt: skip
    # Led by the hand: the outcome (where the person led the robot) goes into the summary too.
    from rtgait.sim.guided import simulate_guided
    from rtgait.sim.model import build_sim_model

    options = loop_options(pushes or None, stabilizer)
    result, led = simulate_guided(build_sim_model(robot), walk, options, progress=progress)
    extra["guide"] = {**asdict(led), "base_error": led.base_error}
    return result


def _write_simulation(
    result: SimResult,
    scenario: Scenario,
    walk: Scenario,
    robot: RobotModel,
    out: Path,
    figures: bool,
    html: bool,
    extra: dict[str, Any],
) -> dict[str, Any]:
    """Write the simulation's outputs into a staging folder, then replace the previous ones in ``out`` together."""
    from rtgait.sim.run import write_sim_outputs

    with staged_outputs(out) as staging:
        summary = write_sim_outputs(
            result, staging.folder, figure=figures, title=f"{scenario.name} ({scenario.connection})", extra=extra,
            replay=robot if html else None, sole=walk.sole,  # the sole the walk was planned with
        )  # fmt: skip
        for name in summary["files"]:
            staging.add(name)
    return summary

