"""The ``rtgait`` command: list the built-in scenarios, plan a scenario and write its trajectory and figures.

Exit codes: 0 success, 1 the run could not complete (outputs not writable, matplotlib missing), 2 bad input
(unknown scenario, invalid file, bad option); every error is one ``rtgait: error: ...`` line on stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from rtgait import __version__
from rtgait.core.online import OnlinePlanner
from rtgait.core.rollout import Rollout, rollout
from rtgait.report import summarize, write_joints_csv, write_trajectory_csv
from rtgait.scenario import Scenario, ScenarioError, builtin_scenarios, load_scenario

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel
    from rtgait.robot.pipeline import RobotRun

PROG = "rtgait"
# Below this many ticks a rollout takes well under a second: a progress bar would only flicker.
PROGRESS_MIN_TICKS = 50_000


class _RunError(Exception):
    """The run could not complete for a reason other than the input (missing extra, unwritable folder)."""


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Real-time humanoid gait planning (Harada et al.'s analytical method):\nplan walks whose "
        "footsteps change while walking, and check that the ZMP stays inside\nthe support polygon.",
        epilog="examples:\n  rtgait scenarios\n  rtgait plan fig4\n"
        "  rtgait plan my_walk.toml --out results/my_walk --dt 0.001",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    commands.add_parser("scenarios", help="list the built-in scenarios", description="List the built-in scenarios.")
    plan = commands.add_parser(
        "plan",
        help="plan a scenario and write trajectory.csv, summary.json and figures",
        description="Roll out a scenario at its control period, handing each footstep change to the planner at "
        "its connection mode's deadline, and write trajectory.csv, summary.json and four PNG figures.",
    )
    plan.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or path to a scenario .toml file")
    plan.add_argument("--out", metavar="DIR", type=Path, help="output folder (default: out/<scenario name>)")
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
    simulate = commands.add_parser(
        "simulate",
        help="walk a scenario on a robot in MuJoCo physics (planner + whole-body IK + position servos at 1 kHz)",
        description="Walk the scenario in closed loop in MuJoCo at 1 kHz: each tick the online planner samples, "
        "the whole-body IK solves and the joint servos track; the measured ZMP (centre of pressure of the contact "
        "forces), base pose, COG and contacts are logged, and falls end the run. Writes sim.csv, summary.json "
        "and zmp_sim.png (and with --html, replay.html: the simulated motion in 3D). A scenario with a [guide] path "
        "(e.g. guided) is walked led by the hand: a person pulls the robot's hand along it.",
    )
    simulate.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or scenario .toml file")
    simulate.add_argument("--robot", metavar="NAME_OR_FILE", default="talos", help="robot (default talos)")
    simulate.add_argument("--out", metavar="DIR", type=Path, help="output folder (default: out/<scenario>-sim)")
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
        "(s); may be repeated",
    )
    simulate.add_argument("--stabilizer", action="store_true", help="turn the ZMP/COG feedback stabiliser on")
    simulate.add_argument("--no-figures", action="store_true", help="skip zmp_sim.png")
    simulate.add_argument(
        "--html", action="store_true", help="write replay.html, a 3D replay of the simulated motion (needs meshcat)"
    )
    simulate.add_argument("--quiet", action="store_true", help="print nothing on success")
    return parser


# ----- plan -----------------------------------------------------------------------------------------------------


def _with_dt(scenario: Scenario, dt: float | None) -> Scenario:
    if dt is None:
        return scenario
    if not (math.isfinite(dt) and dt > 0.0):
        raise ScenarioError(f"--dt must be a number > 0 s, got {dt}")
    try:
        return replace(scenario, dt=dt)
    except ScenarioError as error:
        raise ScenarioError(f"--{error}") from None


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


def _write_outputs(
    result: Rollout, scenario: Scenario, out: Path, figures: bool, robot_run: RobotRun | None, html: bool
) -> dict[str, Any]:
    """Write everything into a temporary folder beside ``out``, then move it into ``out`` in one go.

    A failure at any point leaves ``out`` as it was (no half-written trajectory next to an old summary).
    """
    with _staged_outputs(out) as (staging, files):
        rows = write_trajectory_csv(result, staging / "trajectory.csv")
        files.append("trajectory.csv")
        summary = summarize(result, scenario)
        if robot_run is not None:
            files.append("joints.csv")
            write_joints_csv(*robot_run.motion.table(), staging / "joints.csv")
            summary.update(robot_run.summary())
        if figures:
            from rtgait.viz.figures import FigureInfo, plot_multibody_zmp, render_all

            info = FigureInfo(
                title=f"{scenario.name} ({scenario.connection})",
                sole=scenario.sole,
                nominal_footprints=scenario.nominal_footprints(),
            )
            files += [path.name for path in render_all(result, info, staging)]
            if robot_run is not None:
                before = robot_run.uncompensated[1] if robot_run.uncompensated else robot_run.check
                after = robot_run.check if robot_run.uncompensated else None
                plot_multibody_zmp(
                    result, info, staging / "multibody_zmp.png", before.zmp, None if after is None else after.zmp,
                    robot=robot_run.robot.name,
                )
                files.append("multibody_zmp.png")
        if html and robot_run is not None:
            _write_replay(result, scenario, robot_run, staging / "replay.html")
            files.append("replay.html")
        summary["rows"] = rows
        files.insert(1, "summary.json")
        summary["files"] = files
        (staging / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    return summary


def _write_replay(result: Rollout, scenario: Scenario, robot_run: RobotRun, path: Path) -> None:
    from rtgait.robot.pipeline import visual_model
    from rtgait.viz.replay import write_replay_html

    robot = robot_run.robot
    motion = robot_run.motion
    write_replay_html(
        path,
        robot.full_model,
        visual_model(robot),
        motion.times,
        motion.q_full,
        footprints=result.footprints,
        sole=scenario.sole,
        cog=robot_run.check.cog,
        zmp=np.column_stack([result.column("zmp_x"), result.column("zmp_y")]),
        title=f"rtgait: {scenario.name} on {robot.name}",
    )


def _describe_change(change: dict[str, Any]) -> str:
    parts = []
    if change["length"] is not None:
        parts.append(f"length {change['length']:g} m")
    if change["width"] is not None:
        parts.append(f"width {change['width']:g} m")
    if change["yaw"] is not None:
        parts.append(f"yaw {change['yaw']:g} rad")
    span = "that step only" if change["through"] == change["step"] else f"steps {change['step']}..{change['through']}"
    return f"step {change['step']} decided at {change['decided_at']:.3f} s: {', '.join(parts)} ({span})"


def _print_summary(summary: dict[str, Any], out: Path, wall_time: float, stream: TextIO) -> None:
    timing = summary["timing"]
    outside = summary["zmp_outside"]
    x, y = summary["zmp_margin_min_position"]
    times = summary["planning_time_us"]
    lines = [
        f"scenario    {summary['scenario']}: {summary['description']}",
        f"mode        {summary['connection']} connection, T_s {timing['single_support']:g} s, "
        f"T_dbl {timing['double_support']:g} s, {summary['steps']} steps + 1 closing, dt {summary['dt']:g} s, "
        f"{summary['duration']:.2f} s walked",
    ]
    lines += [f"change      {_describe_change(change)}" for change in summary["changes"]] or ["change      none"]
    lines += [
        f"ZMP margin  min {summary['zmp_margin_min']:+.4f} m at t = {summary['zmp_margin_min_time']:.3f} s, "
        f"ZMP at ({x:.3f}, {y:.3f}) m, {summary['zmp_margin_min_support']} support",
        f"verdict     {'OUTSIDE the support polygon' if outside else 'inside the support polygon'}"
        + (f" for {summary['zmp_outside_duration']:.3f} s" if outside else ""),
    ]
    if times["replan_median"] is not None:
        lines.append(
            f"replans     {summary['replans']} connected replans, planning time per replan "
            f"median {times['replan_median']:.0f} µs, max {times['replan_max']:.0f} µs "
            f"(first plan {times['first_plan']:.0f} µs; whole rollout {wall_time:.2f} s)"
        )
    else:
        lines.append(f"replans     none (first plan {times['first_plan']:.0f} µs)")
    if "robot" in summary:
        lines.append(_robot_line(summary))
        compensation = summary.get("angular_momentum_compensation")
        if compensation is not None:
            before, after = compensation["before"], compensation["after"]
            lines.append(
                f"compensate  angular momentum, Fourier order {compensation['order']}: multibody ZMP error max "
                + ", ".join(
                    f"{axis} {before['multibody_zmp_error_max'][axis] * 1e3:.1f} -> "
                    f"{after['multibody_zmp_error_max'][axis] * 1e3:.1f} mm"
                    for axis in "xy"
                )
                + "; rms "
                + ", ".join(
                    f"{axis} {before['multibody_zmp_error_rms'][axis] * 1e3:.1f} -> "
                    f"{after['multibody_zmp_error_rms'][axis] * 1e3:.1f} mm"
                    for axis in "xy"
                )
            )
    lines.append(f"outputs     {out}{os.sep}: {', '.join(summary['files'])} ({summary['rows']} rows)")
    stream.write("\n".join(lines) + "\n")


def _robot_line(summary: dict[str, Any]) -> str:
    error = summary["multibody_zmp_error_max"]
    return (
        f"robot       {summary['robot']} ({summary['robot_mass']:.1f} kg): IK error max COG "
        f"{summary['ik_cog_error_max'] * 1e6:.2f} µm, feet {summary['ik_foot_error_max'] * 1e6:.2f} µm, "
        f"{summary['ik_time_per_tick_us']:.0f} µs per tick; multibody ZMP error max x {error['x'] * 1e3:.1f} mm, "
        f"y {error['y'] * 1e3:.1f} mm"
    )


def _load_robot(name: str) -> RobotModel:
    try:
        from rtgait.robot.model import RobotModel
    except ImportError:
        raise _RunError("--robot needs Pinocchio and example-robot-data: pip install 'rtgait[robot]'") from None
    return RobotModel.load(name)


def _plan(args: argparse.Namespace) -> int:
    scenario = _with_dt(load_scenario(args.scenario), args.dt)
    out: Path = args.out if args.out is not None else Path("out") / scenario.name
    if args.compensate is not None and args.compensate < 0:
        raise ScenarioError(f"--compensate-angular-momentum ORDER must be an integer >= 0, got {args.compensate}")
    if not args.no_figures:
        try:
            import matplotlib  # noqa: F401  # checked before the run so a missing extra fails fast
        except ImportError:
            raise _RunError("figures need matplotlib: pip install 'rtgait[viz]', or pass --no-figures") from None
    robot_name = args.robot or ("talos" if args.html or args.compensate is not None else None)
    robot = None
    if robot_name is not None:
        from rtgait.robot.motion import robot_scenario

        robot = _load_robot(robot_name)
        scenario = robot_scenario(scenario, robot)
    result, wall_time = _run(scenario, args.quiet)
    robot_run = None
    if robot is not None:
        from rtgait.robot.pipeline import run_on_robot

        robot_run = run_on_robot(robot, result, scenario.cog_height, scenario.gravity, args.compensate)
    summary = _write_outputs(result, scenario, out, not args.no_figures, robot_run, args.html)
    if not args.quiet:
        _print_summary(summary, out, wall_time, sys.stdout)
    return 0


def _numbers(text: str, count: int, option: str) -> tuple[float, ...]:
    """``count`` finite comma-separated numbers from an option's value."""
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ScenarioError(f"{option} needs {count} finite comma-separated numbers, got {text!r}")
    return values


def _simulate(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.scenario)
    out: Path = args.out if args.out is not None else Path("out") / f"{scenario.name}-sim"
    velocity = None if args.velocity is None else _numbers(args.velocity, 3, "--velocity")
    try:
        from rtgait.sim.loop import Push
        from rtgait.sim.run import simulate, write_sim_outputs
    except ImportError:
        raise _RunError("simulate needs MuJoCo and Pinocchio: pip install 'rtgait[robot,sim]'") from None
    pushes = []
    for text in args.push:
        start, duration, fx, fy = _numbers(text, 4, "--push")
        pushes.append(Push(start=start, duration=duration, force=(fx, fy, 0.0)))
    robot = _load_robot(args.robot)
    show = not args.quiet and sys.stderr.isatty()
    progress = _progress_printer(sys.stderr, f"{PROG}: simulating {scenario.name}") if show else None
    extra: dict[str, Any] = {"scenario": scenario.name, "connection": scenario.connection}
    extra["stabilizer"] = args.stabilizer
    if scenario.guide is not None and velocity is None:
        # Led by the hand: the outcome (where the person led the robot) goes into the summary too.
        from rtgait.robot.motion import robot_scenario
        from rtgait.sim.guided import simulate_guided
        from rtgait.sim.model import build_sim_model
        from rtgait.sim.run import loop_options

        result, led = simulate_guided(
            build_sim_model(robot),
            robot_scenario(scenario, robot),
            loop_options(pushes or None, args.stabilizer),
            progress=progress,
        )
        extra["guide"] = {**asdict(led), "base_error": led.base_error}
    else:
        result = simulate(
            scenario, robot, velocity=velocity, push=pushes or None, stabilizer=args.stabilizer, progress=progress
        )
    if show:
        sys.stderr.write("\r\033[K")
    with _staged_outputs(out) as (staging, files):
        summary = write_sim_outputs(
            result, staging, figure=not args.no_figures, title=f"{scenario.name} ({scenario.connection})", extra=extra
        )
        files.extend(summary["files"])
        if args.html:
            from rtgait.robot.motion import robot_scenario
            from rtgait.sim.run import write_sim_replay

            # The footprints are drawn with the sole the walk was planned with: the robot's, not the scenario's.
            write_sim_replay(
                result,
                robot,
                staging / "replay.html",
                sole=robot_scenario(scenario, robot).sole,
                title=f"rtgait: {scenario.name} on {robot.name} in MuJoCo",
            )
            files.append("replay.html")
            summary["files"].append("replay.html")
            # summary.json was written before the replay existed: written again, it lists the replay too.
            text = json.dumps(summary, indent=2, allow_nan=False) + "\n"
            (staging / "summary.json").write_text(text, encoding="utf-8")
    if not args.quiet:
        if summary["fell"]:
            outcome = f"FELL at {summary['fall_time']:.2f} s ({summary['fall_cause']})"
        else:
            outcome = f"walked {summary['steps_completed']} of {summary['steps_planned']} steps without falling"
        if summary["tipped"]:
            outcome += f"; a loaded foot tipped over at {summary['tip_time']:.2f} s"
        if "guide" in summary:
            outcome += f"; led by the hand, the base ended {summary['guide']['base_error']:.3f} m from its goal"
        rms = summary["zmp_tracking_error_rms"]
        print(
            "\n".join(
                [
                    f"scenario    {scenario.name} ({scenario.connection}) on {summary['robot']} in MuJoCo, 1 kHz",
                    f"outcome     {outcome}",
                    f"walked      {summary['distance_walked']:.3f} m; measured vs planned ZMP in single support: "
                    f"RMS {'n/a' if rms is None else f'{rms * 1e3:.1f} mm'}",
                    f"speed       real-time factor {summary['real_time_factor']:.1f} "
                    f"({summary['simulated_time']:.1f} s simulated in {summary['wall_time']:.1f} s)",
                    f"outputs     {out}{os.sep}: {', '.join(summary['files'])} ({summary['rows']} rows)",
                ]
            )
        )
    return 0


@contextlib.contextmanager
def _staged_outputs(out: Path) -> Iterator[tuple[Path, list[str]]]:
    """Yield a staging folder beside ``out`` and a list to name the files written there; on success they move
    into ``out``, on any failure the staging folder is removed and ``out`` is left as it was."""
    staging = _staging_folder(out)
    files: list[str] = []
    try:
        yield staging, files
        _move_into(staging, out, files)
    except OSError as error:
        shutil.rmtree(staging, ignore_errors=True)
        raise _RunError(f"cannot write outputs to {out}: {error.strerror or error}") from None
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def _staging_folder(out: Path) -> Path:
    """A fresh folder beside ``out`` to write into before moving the results into place."""
    if out.exists() and not out.is_dir():
        raise _RunError(f"--out {out} exists and is not a folder")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        # Not tempfile.mkdtemp: its 0700 mode would survive the rename and surprise anyone sharing the results.
        staging = out.parent / f".{out.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
        staging.mkdir()
    except OSError as error:
        raise _RunError(f"cannot create output folder {out}: {error.strerror or error}") from None
    return staging


def _move_into(staging: Path, out: Path, files: Sequence[str]) -> None:
    """Move finished outputs from ``staging`` into ``out`` (renaming the folder when ``out`` is new)."""
    if out.exists():
        # Replace file by file: the folder may hold other things the user keeps there.
        for name in files:
            os.replace(staging / name, out / name)
        staging.rmdir()
    else:
        staging.rename(out)


def _scenarios() -> int:
    listing = builtin_scenarios()
    width = max(len(name) for name in listing)
    for name, description in listing.items():
        print(f"{name:<{width}}  {description}")
    return 0


def _error(message: str) -> None:
    # One line, whatever the message: scripts grep stderr and humans read the first line only.
    print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse reports usage errors (code 2) and --help/--version (0) this way
        return stop.code if isinstance(stop.code, int) else 2
    try:
        if args.command == "scenarios":
            return _scenarios()
        if args.command == "plan":
            return _plan(args)
        if args.command == "simulate":
            return _simulate(args)
        parser.print_usage(sys.stderr)
        _error("choose a command: scenarios, plan or simulate")
        return 2
    except ValueError as error:  # ScenarioError and the core's own input checks
        _error(str(error))
        return 2
    except _RunError as error:
        _error(str(error))
        return 1
    except KeyboardInterrupt:
        _error("interrupted")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
