"""``rtgait simulate --model lipm``: the walk on the linear inverted pendulum's point mass (mass in kg, control
period in s) at the controller level asked for, instead of the robot in MuJoCo; its outputs and figure written
together into the output folder."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from rtgait.cli.common import (
    PROG,
    check_run_length,
    load_robot,
    progress_printer,
    require_extras,
    robot_walk,
)
from rtgait.cli.control_file import controller_settings
from rtgait.cli.simulate_options import _push_values
from rtgait.estimation.estimator import DEFAULT_STATE
from rtgait.io.plan_report import pendulum_report
from rtgait.io.summary_json import summary_text
from rtgait.outputs import check_destination, staged_outputs
from rtgait.scenario.scenario import Scenario, ScenarioError


def _simulate_pendulum(args: argparse.Namespace, scenario: Scenario, out: Path, control_pairs: Any) -> int:
    """``simulate --model lipm``: the walk on the point-mass pendulum at the controller level asked for, with the
    DCM law's gains and ``replan_dcm_error`` of the ``[control]`` tables (the rest acts on a robot only)."""
    from rtgait.io.pendulum_run import PENDULUM_FILES, simulate_pendulum, write_pendulum_outputs
    from rtgait.robot.physical_checks import TOTAL_MASS_RANGE
    from rtgait.viz.figure_files import PENDULUM_FIGURE, figure_file

    for option, why in (("velocity", "walks by command"), ("html", "the 3D replay"), ("physics_dt", "its step"),
                        ("motor_model", "the drives' motors")):  # fmt: skip
        if getattr(args, option):
            raise ScenarioError(f"--{option.replace('_', '-')} ({why}) is for --model mujoco")
    for option, default in (("state", DEFAULT_STATE), ("sensor_noise", 1.0), ("sensor_seed", 0), ("latency", None),
                            ("model_error", None)):  # fmt: skip
        if getattr(args, option) != default:
            raise ScenarioError(f"--{option.replace('_', '-')} is for --model mujoco: the point mass has no sensors, "
                                "its controller acts on its own state")  # fmt: skip
    if scenario.guide is not None:
        raise ScenarioError(f"{scenario.name} is led by the hand ([guide]): that needs --model mujoco")
    mass = args.mass
    stepping = None
    description = None
    if args.robot is not None:
        robot = load_robot(args.robot)
        scenario = robot_walk(scenario, robot)
        mass = robot.mass if mass is None else mass
        description = robot.description
        stepping = description.stepping  # the robot's step limits ([stepping]), if it has them
    options, chosen = controller_settings(description, scenario, args.control, control_pairs)
    low, high = TOTAL_MASS_RANGE  # a humanoid's, as a robot's URDF is checked
    if mass is not None and not (math.isfinite(mass) and low <= mass <= high):
        raise ScenarioError(f"--mass must be within [{low:g}, {high:g}] kg, got {mass}")
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
        adjust = None if stepping is None else stepping.adjustment(scenario.sole)
        result = simulate_pendulum(
            scenario, controller, pushes, mass=mass, dt=dt, progress=progress, step_adjustment=adjust,
            gains=options.dcm, replan_dcm_error=options.replan_dcm_error,
        )  # fmt: skip
    except ValueError as error:  # a push beyond physical sense, caught by the plant
        raise ScenarioError(f"--push: {error}") from None
    if show:
        sys.stderr.write("\r\033[K")
    extra: dict[str, Any] = {"scenario": scenario.name, "connection": scenario.connection}
    if chosen:
        extra["control"] = chosen
    with staged_outputs(out) as staging:
        summary = write_pendulum_outputs(result, staging.folder, extra)
        for name in summary["files"]:
            staging.add(name)
        if figures:
            from rtgait.viz.pendulum import plot_pendulum

            plot_pendulum(result, staging.add(figure_name), title=f"{scenario.name} ({scenario.connection})")
            summary["files"].append(figure_name)
            text = summary_text(summary)  # again, now listing the figure
            (staging.folder / "summary.json").write_text(text, encoding="utf-8")
    if not args.quiet:
        sys.stdout.write(pendulum_report(summary, out))
    return 0
