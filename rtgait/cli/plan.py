"""``rtgait plan``: roll a scenario out and write its trajectory, summary and figures (on a robot, its joints)."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from rtgait.cli.common import (
    PROG,
    add_format_option,
    add_replay_background_option,
    asked_walking,
    load_robot,
    out_folder,
    progress_printer,
    require_extras,
    robot_walk,
)
from rtgait.core.analysis.rollout import Rollout, rollout
from rtgait.core.obstacle.walk import ObstacleRun, avoiding_rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.io.obstacle_outputs import obstacle_runs
from rtgait.io.plan_files import plan_files, write_plan_outputs
from rtgait.io.plan_report import plan_report
from rtgait.outputs import OutputError, check_destination, write_text_atomic
from rtgait.scenario.footholds import footstep_plan_text
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import Scenario, ScenarioError

PROGRESS_MIN_TICKS = 50_000
"""Below this many ticks a rollout takes well under a second: a progress bar would only flicker."""


def add_parser(commands: Any) -> None:
    plan = commands.add_parser(
        "plan",
        help="plan a scenario and write trajectory.csv, summary.json and figures",
        description="Roll out a scenario at its control period, handing each footstep change to the planner at "
        "its connection mode's deadline, and write trajectory.csv, summary.json and four figures (PNG by default).",
    )
    plan.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or path to a scenario .toml file")
    plan.add_argument("--out", metavar="DIR", type=out_folder, help="output folder (default: out/<scenario name>)")
    plan.add_argument("--dt", metavar="S", type=float, help="control period in seconds (default: the scenario's)")
    plan.add_argument("--no-figures", action="store_true", help="skip the figures (no matplotlib needed)")
    add_format_option(plan)
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
    add_replay_background_option(plan)
    plan.add_argument(
        "--export-footsteps",
        metavar="FILE",
        type=Path,
        dest="export_footsteps",
        help="also write the walk's footholds, as walked (after its changes), as a footstep plan .toml that "
        "'rtgait plan FILE' walks again",
    )
    plan.add_argument("--quiet", action="store_true", help="print nothing on success")


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
    shortest = min(scenario.timing.shortest_phase, scenario.timing.settle)
    samples = math.floor(shortest / scenario.dt + 1e-9) + 1
    if 2 * order + 1 > samples:
        raise ScenarioError(
            f"{option} {order} needs {2 * order + 1} samples per phase; the shortest phase ({shortest:g} s at dt "
            f"{scenario.dt:g} s) has at most {samples}"
        )


def _run(scenario: Scenario, quiet: bool) -> tuple[Rollout, float, ObstacleRun | None]:
    """Roll the scenario out, reacting to its obstacles if any; returns the rollout, its wall time (s) and, with
    obstacles, the run of the scenario's own connection mode."""
    ticks = scenario.duration / scenario.dt
    show = not quiet and ticks >= PROGRESS_MIN_TICKS and sys.stderr.isatty()
    label = f"{PROG}: planning {scenario.name}"
    progress = progress_printer(sys.stderr, label, total=math.floor(ticks + 1e-9) + 1, unit="ticks") if show else None
    began = time.perf_counter()
    if scenario.obstacles:
        result, seen = avoiding_rollout(scenario.planner_config(), scenario.strides(), scenario.dt, scenario.sole,
                                        scenario.obstacles, scenario.changes, progress=progress)  # fmt: skip
        return result, time.perf_counter() - began, ObstacleRun(scenario.connection, result, seen)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    result = rollout(planner, scenario.dt, scenario.sole, scenario.changes, progress=progress)
    elapsed = time.perf_counter() - began
    return result, elapsed, None


def run(args: argparse.Namespace) -> int:
    scenario = _with_dt(load_scenario(args.scenario), args.dt)
    out: Path = args.out if args.out is not None else Path("out") / scenario.name
    _check_order(args.compensate, scenario)
    figures = not args.no_figures
    robot_name = args.robot or ("talos" if args.html or args.compensate is not None else None)
    require_extras(figures, args.html)
    fmt = args.figure_format
    check_destination(out, plan_files(figures, robot_name is not None, args.html, fmt, bool(scenario.obstacles)))
    _check_export(args.export_footsteps)
    robot = None
    if robot_name is not None:
        robot = load_robot(robot_name, scenario)
        scenario = robot_walk(scenario, robot)
    result, wall_time, own = _run(scenario, args.quiet)
    # With obstacles, the walk under each of the paper's connection modes, for the figure like its Fig. 1.
    walks = obstacle_runs(scenario, own) if scenario.obstacles else None
    robot_run = None
    if robot is not None:
        from rtgait.robot.pipeline import run_on_robot

        # The robot's check: an IK error beyond its limit anywhere (UnreachableError) refuses the walk.
        with asked_walking(scenario, robot):
            robot_run = run_on_robot(robot, result, scenario.cog_height, scenario.gravity, args.compensate)
    summary = write_plan_outputs(
        result, scenario, out, figures=figures, robot_run=robot_run, html=args.html, fmt=fmt,
        background=args.replay_background, obstacle_runs=walks,
    )  # fmt: skip
    if args.export_footsteps is not None:
        try:
            write_text_atomic(args.export_footsteps, footstep_plan_text(scenario, result.footprints))
        except OSError as error:  # a full disk, or a folder changed during the run
            reason = error.strerror or error
            raise OutputError(f"--export-footsteps: cannot write {args.export_footsteps}: {reason}") from None
    if not args.quiet:
        sys.stdout.write(plan_report(summary, out, wall_time))
        if args.export_footsteps is not None:
            sys.stdout.write(f"footsteps   {args.export_footsteps}\n")
    return 0


def _check_export(path: Path | None) -> None:
    """``--export-footsteps FILE`` can be written: not a folder, not read-only, in an existing folder."""
    if path is None:
        return
    option = "--export-footsteps"
    if str(path) in ("", "."):
        raise ScenarioError(f"{option} needs a file name")
    try:
        _check_export_path(path, option)
    except OSError as error:  # a name the file system refuses (too long), an unreadable folder
        raise OutputError(f"{option}: cannot write {path}: {error.strerror or error}") from None


def _check_export_path(path: Path, option: str) -> None:
    if path.is_dir():
        raise ScenarioError(f"{option} {path} is a folder")
    folder = path.parent
    if not folder.is_dir():
        raise OutputError(f"{option}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise OutputError(f"{option}: {path} is not writable")
