"""The ``rtgait`` command: list the built-in scenarios, plan a scenario and write its trajectory and figures, or
walk it in physics.

Exit codes: 0 success, 1 the run could not complete (outputs not writable, an extra package missing), 2 bad input
(unknown scenario, invalid file, bad option, a size beyond :mod:`rtgait.core.limits`); every error, argparse's
included, is one ``rtgait: error: ...`` line on stderr. Everything is checked before the run starts, and a run
replaces its whole set of outputs or changes nothing (:mod:`rtgait.outputs`).
"""

from __future__ import annotations

import argparse
import itertools
import math
import re
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TextIO

from rtgait import __version__
from rtgait.core.limits import MAX_ROLLOUT_TICKS
from rtgait.core.online import OnlinePlanner
from rtgait.core.rollout import Rollout, rollout
from rtgait.outputs import OutputError, check_destination, staged_outputs
from rtgait.report import plan_files, plan_report, simulation_report, write_plan_outputs
from rtgait.scenario import PHASES, Scenario, ScenarioError, builtin_scenarios, load_scenario

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel
    from rtgait.sim.loop import Push, SimResult

PROG = "rtgait"
# Below this many ticks a rollout takes well under a second: a progress bar would only flicker.
PROGRESS_MIN_TICKS = 50_000
# A value that starts like a negative number ("-0.1,0,0", "-1e-3", "-inf"); argparse would take it for an option.
_NEGATIVE_VALUE = re.compile(r"-(\d|\.\d|inf|nan)", re.IGNORECASE)


class _RunError(Exception):
    """The run could not complete for a reason other than the input (a missing extra package)."""


class _Parser(argparse.ArgumentParser):
    """argparse with rtgait's one-line errors, and option values that start with a minus sign."""

    def error(self, message: str) -> NoReturn:
        # argparse prints its usage and the message on several lines; scripts grep one line, humans read one.
        _error(f"{message} (see '{self.prog} --help')")
        raise SystemExit(2)

    def parse_known_args(  # type: ignore[override]  # typeshed's overloads; the behaviour is argparse's
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        # Each subcommand's parser runs this on its own arguments, so it knows the options that take a value.
        tokens = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(self._glue_negative_values(tokens), namespace)

    def _glue_negative_values(self, tokens: list[str]) -> list[str]:
        """``--velocity -0.1,0,0`` as ``--velocity=-0.1,0,0``: argparse reads a value starting with '-' as an
        option unless it is a bare negative number, so comma lists and exponents would be refused."""
        glued: list[str] = []
        index = 0
        while index < len(tokens):
            token = tokens[index]
            if token == "--":  # the rest are positional, whatever they look like
                return glued + tokens[index:]
            following = tokens[index + 1] if index + 1 < len(tokens) else ""
            if self._takes_value(token) and _NEGATIVE_VALUE.match(following):
                glued.append(f"{token}={following}")
                index += 2
            else:
                glued.append(token)
                index += 1
        return glued

    def _takes_value(self, token: str) -> bool:
        """Whether ``token`` names (in full, or by a unique prefix as argparse allows) an option with a value."""
        if not token.startswith("--") or "=" in token:
            return False
        options = {name: action.nargs != 0 for action in self._actions for name in action.option_strings}
        if token in options:
            return options[token]
        matches = [name for name in options if name.startswith(token)]
        return self.allow_abbrev and len(matches) == 1 and options[matches[0]]


def _out_folder(text: str) -> Path:
    # Path("") is Path("."): an empty --out (an unset shell variable) would write into the working folder.
    if not text:
        raise argparse.ArgumentTypeError("must name a folder, got an empty string")
    return Path(text)


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description="Real-time humanoid gait planning (Harada et al.'s analytical method):\nplan walks whose "
        "footsteps change while walking, and check that the ZMP stays inside\nthe support polygon.",
        epilog="examples:\n  rtgait scenarios\n  rtgait plan fig4\n"
        "  rtgait plan my_walk.toml --out results/my_walk --dt 0.001\n  rtgait simulate fig8 --velocity -0.1,0,0",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    commands.add_parser("scenarios", help="list the built-in scenarios", description="List the built-in scenarios.")
    _add_plan_parser(commands)
    _add_simulate_parser(commands)
    return parser


def _add_plan_parser(commands: Any) -> None:
    plan = commands.add_parser(
        "plan",
        help="plan a scenario and write trajectory.csv, summary.json and figures",
        description="Roll out a scenario at its control period, handing each footstep change to the planner at "
        "its connection mode's deadline, and write trajectory.csv, summary.json and four PNG figures.",
    )
    plan.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or path to a scenario .toml file")
    plan.add_argument("--out", metavar="DIR", type=_out_folder, help="output folder (default: out/<scenario name>)")
    plan.add_argument("--dt", metavar="S", type=float, help="control period in seconds (default: the scenario's)")
    plan.add_argument("--no-figures", action="store_true", help="skip the PNG figures (no matplotlib needed)")
    plan.add_argument(
        "--robot",
        metavar="NAME_OR_FILE",
        help="walk it on a humanoid model: a built-in robot (talos, g1) or a robot description .toml; adds "
        "joints.csv, the multibody check and its figure (the robot's COG height, step width and sole replace the "
        "scenario's)",
    )
    plan.add_argument(
        "--compensate-angular-momentum",
        metavar="ORDER",
        nargs="?",
        const=3,
        type=int,
        dest="compensate",
        help="correct the COG for the motion's angular momentum (the paper's Appendix A) with a Fourier series of "
        "ORDER per phase (default 3); implies --robot talos unless --robot is given",
    )
    plan.add_argument(
        "--html", action="store_true", help="write replay.html, a 3D replay of the robot (implies --robot talos)"
    )
    plan.add_argument("--quiet", action="store_true", help="print nothing on success")


def _add_simulate_parser(commands: Any) -> None:
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
    simulate.add_argument("--robot", metavar="NAME_OR_FILE", default="talos", help="robot (default talos)")
    simulate.add_argument("--out", metavar="DIR", type=_out_folder, help="output folder (default: out/<scenario>-sim)")
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
    simulate.add_argument(
        "--html", action="store_true", help="write replay.html, a 3D replay of the simulated motion (needs meshcat)"
    )
    simulate.add_argument("--quiet", action="store_true", help="print nothing on success")


# ----- checks made before any run -------------------------------------------------------------------------------


def _with_dt(scenario: Scenario, dt: float | None) -> Scenario:
    if dt is None:
        return scenario
    if not (math.isfinite(dt) and dt > 0.0):
        raise ScenarioError(f"--dt must be a number > 0 s, got {dt}")
    try:
        return replace(scenario, dt=dt)
    except ScenarioError as error:  # the period's checks (limits, tick count) word it "dt ..."
        raise ScenarioError(f"--{error}") from None


def _check_order(order: int | None, scenario: Scenario) -> None:
    """The Fourier order of the angular-momentum compensation: >= 0, and few enough coefficients that every phase
    has the samples to fit them (this also bounds the fit's memory by the rollout's)."""
    if order is None:
        return
    option = "--compensate-angular-momentum ORDER"
    if order < 0:
        raise ScenarioError(f"{option} must be an integer >= 0, got {order}")
    shortest = min(getattr(scenario.timing, name) for name in PHASES)
    samples = math.floor(shortest / scenario.dt + 1e-9) + 1
    if 2 * order + 1 > samples:
        raise ScenarioError(
            f"{option} {order} needs {2 * order + 1} samples per phase; the shortest phase ({shortest:g} s at dt "
            f"{scenario.dt:g} s) has at most {samples}"
        )


def _require_extras(figures: bool, html: bool) -> None:
    """Fail fast, before a long run, when an output asked for needs a package that is not installed."""
    if figures:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise _RunError("figures need matplotlib: pip install 'rtgait[viz]', or pass --no-figures") from None
    if html:
        try:
            import meshcat  # noqa: F401
        except ImportError:
            raise _RunError("--html needs meshcat: pip install 'rtgait[viz]'") from None


def _load_robot(name: str) -> RobotModel:
    try:
        from rtgait.robot.model import RobotModel
    except ImportError:
        raise _RunError("--robot needs Pinocchio and example-robot-data: pip install 'rtgait[robot]'") from None
    return RobotModel.load(name)


def _robot_walk(scenario: Scenario, robot: RobotModel) -> Scenario:
    """``scenario`` as ``robot`` walks it (its COG height, step width and sole), checked like the scenario."""
    from rtgait.robot.motion import robot_scenario

    try:
        return robot_scenario(scenario, robot)
    except ScenarioError as error:  # e.g. a description's COG height outside the limits
        raise ScenarioError(f"with robot {robot.name}: {error}") from None


# ----- plan -----------------------------------------------------------------------------------------------------


def _progress_printer(stream: TextIO, label: str) -> Callable[[float], None]:
    def report(fraction: float) -> None:
        stream.write(f"\r{label} {fraction * 100:3.0f}%")
        stream.flush()

    return report


def _run(scenario: Scenario, quiet: bool) -> tuple[Rollout, float]:
    """Roll the scenario out; returns the rollout and its wall time (s)."""
    ticks = scenario.duration / scenario.dt
    show = not quiet and ticks >= PROGRESS_MIN_TICKS and sys.stderr.isatty()
    progress = _progress_printer(sys.stderr, f"{PROG}: planning {scenario.name}") if show else None
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    began = time.perf_counter()
    result = rollout(planner, scenario.dt, scenario.sole, scenario.changes, progress=progress)
    elapsed = time.perf_counter() - began
    if show:
        sys.stderr.write("\r\033[K")  # erase the progress line so the summary starts clean
        sys.stderr.flush()
    return result, elapsed


def _plan(args: argparse.Namespace) -> int:
    scenario = _with_dt(load_scenario(args.scenario), args.dt)
    out: Path = args.out if args.out is not None else Path("out") / scenario.name
    _check_order(args.compensate, scenario)
    figures = not args.no_figures
    robot_name = args.robot or ("talos" if args.html or args.compensate is not None else None)
    _require_extras(figures, args.html)
    check_destination(out, plan_files(figures, robot_name is not None, args.html))
    robot = None
    if robot_name is not None:
        robot = _load_robot(robot_name)
        scenario = _robot_walk(scenario, robot)
    result, wall_time = _run(scenario, args.quiet)
    robot_run = None
    if robot is not None:
        from rtgait.robot.pipeline import run_on_robot

        # The robot's check: an IK error beyond its limit anywhere (UnreachableError) refuses the walk.
        robot_run = run_on_robot(robot, result, scenario.cog_height, scenario.gravity, args.compensate)
    summary = write_plan_outputs(result, scenario, out, figures=figures, robot_run=robot_run, html=args.html)
    if not args.quiet:
        sys.stdout.write(plan_report(summary, out, wall_time))
    return 0


# ----- simulate -------------------------------------------------------------------------------------------------


def _numbers(text: str, count: int, option: str) -> tuple[float, ...]:
    """``count`` finite comma-separated numbers from an option's value."""
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ScenarioError(f"{option} needs {count} finite comma-separated numbers, got {text!r}")
    return values


def _pushes(texts: Sequence[str], run_time: float) -> list[Push]:
    """The ``--push`` options as pushes, refusing what would silently not happen: a push that starts after the
    run (``run_time``, s) has ended, and overlapping pushes (the loop applies one at a time, so the later one
    would cut the earlier one short)."""
    from rtgait.sim.loop import Push

    pushes = []
    for text in texts:
        start, duration, fx, fy = _numbers(text, 4, "--push")
        try:
            push = Push(start=start, duration=duration, force=(fx, fy, 0.0))
        except ValueError as error:  # "push start must be ..."
            raise ScenarioError(f"--{error}") from None
        if start >= run_time:
            raise ScenarioError(f"--push {text} starts after the run has ended (at {run_time:.2f} s)")
        pushes.append(push)
    ordered = sorted(zip(pushes, texts, strict=True), key=lambda pair: pair[0].start)
    for (first, first_text), (second, second_text) in itertools.pairwise(ordered):
        if second.start < first.start + first.duration:
            raise ScenarioError(f"--push {first_text} and --push {second_text} overlap: pushes act one at a time")
    return pushes


def _check_run_length(seconds: float, timestep: float) -> None:
    """A simulation records every physics tick: at most MAX_ROLLOUT_TICKS of them, like a rollout."""
    ticks = math.floor(seconds / timestep + 1e-9) + 1
    if ticks > MAX_ROLLOUT_TICKS:
        raise ScenarioError(
            f"the simulation would last {seconds:g} s, which at the physics step dt {timestep:g} s is duration / dt "
            f"+ 1 = {ticks} ticks, at most {MAX_ROLLOUT_TICKS}: take fewer walk.steps (or a shorter [guide] path)"
        )


def _simulate(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.scenario)
    out: Path = args.out if args.out is not None else Path("out") / f"{scenario.name}-sim"
    velocity = None if args.velocity is None else _numbers(args.velocity, 3, "--velocity")
    try:
        from rtgait.robot.motion import whole_body_motion
        from rtgait.sim.run import mujoco_messages, planned_walk
    except ImportError:
        raise _RunError("simulate needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'") from None
    pushes = _check_simulation(args, scenario, velocity, out)
    robot = _load_robot(args.robot)
    walk = _robot_walk(scenario, robot)
    # The check of `plan --robot`, on the walk the simulation will ask for: a robot that cannot reach it is refused.
    whole_body_motion(robot, planned_walk(scenario, robot, velocity))
    show = not args.quiet and sys.stderr.isatty()
    progress = _progress_printer(sys.stderr, f"{PROG}: simulating {scenario.name}") if show else None
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


def _check_simulation(
    args: argparse.Namespace, scenario: Scenario, velocity: tuple[float, ...] | None, out: Path
) -> list[Push]:
    """Everything about a simulation that can be checked before loading the robot; returns the pushes."""
    from rtgait.sim.model import SimConfig
    from rtgait.sim.run import SIM_FILES, simulated_time

    run_time = simulated_time(scenario, velocity=velocity)
    _check_run_length(run_time, SimConfig().timestep)
    pushes = _pushes(args.push, run_time)
    figures = not args.no_figures
    _require_extras(figures, args.html)
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


# ----- entry point ----------------------------------------------------------------------------------------------


def _scenarios(args: argparse.Namespace) -> int:
    listing = builtin_scenarios()
    width = max(len(name) for name in listing)
    for name, description in listing.items():
        print(f"{name:<{width}}  {description}")
    return 0


_COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "scenarios": _scenarios,
    "plan": _plan,
    "simulate": _simulate,
}


def _error(message: str) -> None:
    # One line, whatever the message: scripts grep stderr and humans read the first line only.
    print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)


def _show_warning(message: Warning | str, category: type[Warning], *args: Any, **kwargs: Any) -> None:
    # Python's format (file, line, source) is for programmers; a user gets one line, like an error.
    print(f"{PROG}: warning: {' '.join(str(message).split())}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse's usage errors (code 2, one line) and --help/--version (0)
        return stop.code if isinstance(stop.code, int) else 2
    if args.command is None:
        _error(f"choose a command: {', '.join(_COMMANDS)} (see '{PROG} --help')")
        return 2
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        try:
            return _COMMANDS[args.command](args)
        except ValueError as error:  # ScenarioError, the robot's and the core's own input checks
            _error(str(error))
            return 2
        except (_RunError, OutputError) as error:
            _error(str(error))
            return 1
        except KeyboardInterrupt:
            _error("interrupted")
            return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
