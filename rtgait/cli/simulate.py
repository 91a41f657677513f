"""``rtgait simulate``: walk a scenario in closed loop, on a robot in MuJoCo physics or on the point-mass pendulum."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtgait.cli.common import (
    PROG,
    RunError,
    add_format_option,
    add_replay_background_option,
    add_state_options,
    asked_walking,
    check_state_options,
    load_robot,
    out_folder,
    progress_printer,
    robot_walk,
    state_settings,
)
from rtgait.cli.control_file import controller_settings, read_control_file
from rtgait.cli.simulate_options import (
    _check_command_times,
    _check_gains,
    _check_periods,
    _check_simulation,
    _physics_config,
    _velocities,
)
from rtgait.cli.simulate_pendulum import _simulate_pendulum
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.estimation.estimator import DEFAULT_STATE
from rtgait.interface.command import GAIN_SETS
from rtgait.outputs import staged_outputs
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import Scenario, ScenarioError
from rtgait.scenario.walking_table import walking_for
from rtgait.viz.walk_title import velocity_commands, velocity_facts, walk_title

if TYPE_CHECKING:
    from rtgait.control.settings import ControllerOptions
    from rtgait.core.push import Push
    from rtgait.estimation.estimator import StateSource
    from rtgait.robot.model import RobotModel
    from rtgait.sim.loop import SimResult
    from rtgait.sim.model import SimConfig

MODELS = ("mujoco", "lipm")
"""What ``--model`` can simulate: the robot in MuJoCo, or the linear inverted pendulum's point mass."""


def add_parser(commands: Any) -> None:
    simulate = commands.add_parser(
        "simulate",
        help="walk a scenario on a robot in MuJoCo physics (planner + whole-body IK + position servos at 1 kHz)",
        description="Walk the scenario in closed loop in MuJoCo at 1 kHz: each tick the online planner samples, "
        "the whole-body IK solves and the joint servos track; the measured ZMP (centre of pressure of the contact "
        "forces), base pose, COG and contacts are logged, and falls end the run. Writes sim.csv, sim.parquet (the "
        "complete log, docs/logs.md; needs pyarrow), summary.json and zmp_sim.png (and with --html, replay.html: "
        "the simulated motion in 3D). A scenario with a [guide] path "
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
        choices=CONTROLLER_LEVELS,
        help="adaptive (default): + replanning from the measured state, re-anchoring on landings, step adjustment "
        "and landing detection; stabilized: the plan + DCM feedback on the measured COM state and foot force control "
        "from the measured wrench of each foot; open-loop: the plan alone (the paper's assumption)",
    )
    simulate.add_argument(
        "--gains",
        choices=GAIN_SETS,
        default="stiff",
        help="the drives' own gains: stiff (default), derived from the URDF for an open-loop pattern; robot, the "
        "gains the real robot's low-level controller runs, with feed-forward torques (docs/robots.md)",
    )
    simulate.add_argument(
        "--drive",
        choices=("position", "torque"),
        default="position",
        help="position (default): the drives' own gains around the IK's references; torque: the motion carried by "
        "the feed-forward torques of inverse dynamics under a tenth of the robot's gains",
    )
    simulate.add_argument(
        "--motor-model",
        action="store_true",
        help="--model mujoco: the drives as the robot's motors run (its description's motor types: torque-speed "
        "envelope, Coulomb and viscous joint friction) with its command delay (a command applied a control period "
        "late); without it the drives are ideal within their torque limits, with no delay (docs/robots.md)",
    )
    simulate.add_argument(
        "--control",
        metavar="FILE",
        help="the controller's settings from the [control] table of a TOML file (gains, filters, landing handling: "
        "docs/cli_and_scenarios.md), over the robot description's and the scenario's own [control] tables",
    )
    simulate.add_argument(
        "--robot",
        metavar="NAME_OR_FILE",
        help="robot (default talos with --model mujoco); its COG height, sole and step width replace the scenario's "
        "(and with --model lipm its mass)",
    )
    simulate.add_argument(
        "--mass", metavar="KG", type=float, help="--model lipm: the point mass (default the scenario's, else 57 kg)"
    )
    simulate.add_argument(
        "--control-dt",
        metavar="S",
        type=float,
        help="control period (s): a new joint reference every period (default: the robot description's, 1 ms for "
        "Talos, 2 ms for G1; 1 ms with --model lipm)",
    )
    simulate.add_argument(
        "--physics-dt",
        metavar="S",
        type=float,
        help="--model mujoco: physics step (s, default 0.001); at most the control period and dividing it",
    )
    add_state_options(simulate)
    simulate.add_argument("--out", metavar="DIR", type=out_folder, help="output folder (default: out/<scenario>-sim)")
    simulate.add_argument(
        "--velocity",
        metavar="VX,VY,WZ[@T]",
        action="append",
        help="walk the scenario's number of steps by a velocity command instead of its footsteps (m/s, m/s, rad/s); "
        "repeat it with @T for a new command from time T on (s, walk clock), e.g. --velocity 0.2,0,0 --velocity "
        "0,0,0.3@5 (MuJoCo)",
    )
    simulate.add_argument(
        "--push",
        metavar="T,DURATION,FX,FY",
        action="append",
        default=[],
        help="push the base with a horizontal force (N) from time T (s, on the walk's clock: 0 when the walk starts, "
        "after MuJoCo's 1.5 s start transition from half-sitting) for DURATION (s); may be repeated, for pushes "
        "that do not overlap",
    )
    simulate.add_argument("--stabilizer", action="store_true", help=argparse.SUPPRESS)  # removed: a clear error
    simulate.add_argument("--no-figures", action="store_true", help="skip the figure (zmp_sim or pendulum)")
    add_format_option(
        simulate,
        default="png",
        description="file format of the figure (zmp_sim, or pendulum with --model lipm): png (default), pdf or svg",
    )
    simulate.add_argument(
        "--html", action="store_true", help="write replay.html, a 3D replay of the simulated motion (needs meshcat)"
    )
    add_replay_background_option(simulate)
    simulate.add_argument("--quiet", action="store_true", help="print nothing on success")


STABILIZER_REMOVED = (
    "--stabilizer was removed: its COG-shift stabiliser is replaced by the controller levels, use --controller "
    "stabilized (DCM feedback and foot force control) or adaptive (the default)"
)


def run(args: argparse.Namespace) -> int:
    if args.stabilizer:
        raise ScenarioError(STABILIZER_REMOVED)
    scenario = load_scenario(args.scenario)
    out: Path = args.out if args.out is not None else Path("out") / f"{scenario.name}-sim"
    control_pairs = read_control_file(args.control)
    if args.model == "lipm":
        return _simulate_pendulum(args, scenario, out, control_pairs)
    if args.mass is not None:
        raise ScenarioError("--mass is for --model lipm (the robot's mass is its model's)")
    _check_periods(args.control_dt, args.physics_dt)
    check_state_options(args)
    args.robot = args.robot or "talos"
    controller = args.controller or "adaptive"
    velocity, schedule = _velocities(args.velocity)
    _check_command_times(args.velocity, schedule, scenario)
    try:
        from rtgait.io.sim_run import mujoco_messages, planned_walk
        from rtgait.robot.motion import whole_body_motion
    except ImportError:
        raise RunError("simulate needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'") from None
    state, sensors, model_error = state_settings(args)
    pushes = _check_simulation(args, scenario, velocity, out)
    robot = load_robot(args.robot, scenario)
    walk = robot_walk(scenario, robot)
    options, chosen = controller_settings(robot.description, scenario, args.control, control_pairs, args.gains)
    config = dataclasses.replace(
        _physics_config(robot, args.control_dt, args.physics_dt), gains=args.gains, sensors=sensors,
        model_error=model_error, motor_model=args.motor_model, command_delay=None if args.motor_model else 0,
    )  # fmt: skip
    _check_gains(robot, args.gains, args.drive)
    for push in pushes:
        try:
            push.check(robot.mass, walk.cog_height, walk.gravity)
        except ValueError as error:
            raise ScenarioError(f"--push at {push.start:g} s: {error}") from None
    # The check of `plan --robot`, on the walk the simulation will ask for: a robot that cannot reach it is refused.
    for command in [velocity] if not schedule else [v for _, *v in schedule]:  # each command's walk must be reachable
        with asked_walking(scenario, robot):
            whole_body_motion(robot, planned_walk(scenario, robot, command))
    show = not args.quiet and sys.stderr.isatty()
    progress = progress_printer(sys.stderr, f"{PROG}: simulating {scenario.name}") if show else None
    extra: dict[str, Any] = {
        "scenario": scenario.name, "connection": scenario.connection, "walk": _walk_facts(walk, robot)
    }  # fmt: skip
    if chosen:
        extra["control"] = chosen
    if walk.terrain is not None:  # for the summary and the log, so that `rtgait plot` draws the terrain again
        from rtgait.core.geometry.terrain import terrain_fields

        extra["terrain"] = terrain_fields(walk.terrain.terrain)
    commands = schedule or ([(0.0, *velocity)] if velocity is not None else [])
    if commands:  # a walk by velocity command: its commands, for the summary's and the figures' titles
        extra["velocity"] = velocity_facts(commands)
    with mujoco_messages() as messages:  # else MuJoCo appends them to MUJOCO_LOG.TXT in the working folder
        result = _physics(
            scenario,
            walk,
            robot,
            config,
            controller,
            options,
            schedule or velocity,
            pushes,
            progress,
            extra,
            args.drive,
            state,
        )
    extra["mujoco_warnings"] = messages
    if show:
        sys.stderr.write("\r\033[K")
    summary = _write_simulation(result, scenario, walk, robot, out, args, extra)
    if not args.quiet:
        from rtgait.io.sim_files import sim_report

        sys.stdout.write(sim_report(summary, out))
    return 0


def _walk_facts(walk: Scenario, robot: RobotModel) -> dict[str, Any]:
    """The walk's COG height, step width and sole as the robot gives them, for the summary; the values the
    scenario's ``[walking.<robot>]`` asks instead, named as such."""
    sole = walk.sole
    facts: dict[str, Any] = {
        "cog_height": walk.cog_height,
        "step_width": walk.step_width,
        "sole": {"front": sole.front, "back": sole.back, "inner": sole.inner, "outer": sole.outer},
        "source": "from the robot description (the scenario's own are not used)",
    }
    asked = walking_for(walk.walking, robot.name)
    if asked is not None:
        facts["toe_release"] = robot.description.toe_release
        keys = " and ".join(key for key in ("cog_height", "toe_release") if getattr(asked, key) is not None)
        facts["source"] = f"from the robot description, {keys} from the scenario's [walking.{robot.name}]"
    return facts


def _physics(
    scenario: Scenario,
    walk: Scenario,
    robot: RobotModel,
    config: SimConfig,
    controller: str,
    options: ControllerOptions,
    velocity: tuple[float, ...] | list[tuple[float, ...]] | None,
    pushes: list[Push],
    progress: Callable[[float], None] | None,
    extra: dict[str, Any],
    drive: str = "position",
    state: StateSource = DEFAULT_STATE,
) -> SimResult:
    """Walk ``scenario`` (as ``robot`` walks it: ``walk``) in MuJoCo, the controller on ``state``; a guided walk's
    outcome goes into ``extra``."""
    from rtgait.io.obstacle_outputs import sim_obstacle_facts
    from rtgait.io.sim_run import loop_options, obstacle_reactions, simulate
    from rtgait.sim.loop_options import LoopOptions
    from rtgait.sim.model import build_sim_model

    terrain = None if walk.terrain is None else walk.terrain.terrain
    sim = build_sim_model(robot, config, walk.obstacles, terrain)
    driven = LoopOptions(drive=drive, state=state)  # type: ignore[arg-type]
    if scenario.guide is None or velocity is not None:
        reactions = obstacle_reactions(walk) if velocity is None else ()
        result = simulate(scenario, robot, controller=controller, controller_options=options, velocity=velocity,
                          push=pushes or None, sim=sim, progress=progress,
                          options=dataclasses.replace(driven, reactions=reactions))  # type: ignore[arg-type]  # fmt: skip
        if reactions:
            extra["obstacles"] = sim_obstacle_facts(reactions, result.sole_pose, walk.sole)
        return result
    # Led by the hand: the outcome (where the person led the robot) goes into the summary too.
    from rtgait.sim.guided import simulate_guided

    loop = loop_options(pushes or None, driven)
    result, led = simulate_guided(
        sim, walk, loop, controller=controller, controller_options=options, progress=progress  # type: ignore[arg-type]
    )  # fmt: skip
    extra["guide"] = {**asdict(led), "base_error": led.base_error}
    return result


def _write_simulation(
    result: SimResult,
    scenario: Scenario,
    walk: Scenario,
    robot: RobotModel,
    out: Path,
    args: argparse.Namespace,
    extra: dict[str, Any],
) -> dict[str, Any]:
    """Write the simulation's outputs into a staging folder, then replace the previous ones in ``out`` together."""
    from rtgait.io.sim_run import write_sim_outputs

    commands = velocity_commands(extra)
    with staged_outputs(out) as staging:
        summary = write_sim_outputs(
            result, staging.folder, figure=not args.no_figures, figure_format=args.figure_format,
            title=walk_title(scenario.name, scenario.connection, commands), extra=extra,
            replay=robot if args.html else None,
            sole=walk.sole,  # the sole the walk was planned with
            background=args.replay_background,
            terrain=None if walk.terrain is None else walk.terrain.terrain, obstacles=walk.obstacles,
        )  # fmt: skip
        for name in summary["files"]:
            staging.add(name)
    return summary
