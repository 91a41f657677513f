"""The options of ``rtgait simulate`` read and checked before anything runs: pushes, velocity commands and their
times, control and physics periods (s), the robot's gains; each refusal a one-line :class:`ScenarioError` naming the
option, so that nothing asked for silently fails to happen."""

from __future__ import annotations

import argparse
import itertools
import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rtgait.cli.common import check_run_length, numbers, require_extras
from rtgait.core.geometry.footsteps import Timeline
from rtgait.outputs import check_destination
from rtgait.scenario.scenario import Scenario, ScenarioError

if TYPE_CHECKING:
    from rtgait.core.push import Push
    from rtgait.robot.model import RobotModel
    from rtgait.sim.model import SimConfig

__all__ = ["last_command_time"]  # the rest are the command's own helpers


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
            raise ScenarioError(
                f"--push {text} starts after the run has ended (at {run_time:.2f} s on the walk's clock)"
            )
        pushes.append((start, duration, fx, fy))
    ordered = sorted(zip(pushes, texts, strict=True), key=lambda pair: pair[0][0])
    for (first, first_text), (second, second_text) in itertools.pairwise(ordered):
        if second[0] < first[0] + first[1]:
            raise ScenarioError(f"--push {first_text} and --push {second_text} overlap: pushes act one at a time")
    return pushes


def _pushes(texts: Sequence[str], run_time: float) -> list[Push]:
    """The ``--push`` options as the MuJoCo loop's pushes (:func:`_push_values`)."""
    from rtgait.core.push import Push

    pushes = []
    for start, duration, fx, fy in _push_values(texts, run_time):
        try:
            pushes.append(Push(start=start, duration=duration, force=(fx, fy, 0.0)))
        except ValueError as error:  # "push start must be ..."
            raise ScenarioError(f"--{error}") from None
    return pushes


def _velocities(texts: Sequence[str] | None) -> tuple[tuple[float, ...] | None, list[tuple[float, ...]]]:
    """``--velocity`` options: the one command ``(vx, vy, wz)`` (m/s, m/s, rad/s), or the schedule ``(t, vx, vy,
    wz)`` of several (the first from the walk's start unless it says ``@T``), in time order."""
    if not texts:
        return None, []
    schedule = []
    for i, text in enumerate(texts):
        command, _, at = text.partition("@")
        values = numbers(command, 3, "--velocity")
        t = 0.0 if not at and i == 0 else numbers(at, 1, f"--velocity ...@T (in {text!r})")[0]
        if not at and i > 0:
            raise ScenarioError(f"--velocity {text}: a command after the first needs its time, VX,VY,WZ@T")
        schedule.append((t, *values))
    times = [item[0] for item in schedule]
    if times != sorted(times) or len(set(times)) != len(times) or times[0] < 0.0:
        raise ScenarioError(f"--velocity times must be >= 0 s and increasing, got {times}")
    if len(schedule) == 1 and schedule[0][0] == 0.0:
        return schedule[0][1:], []
    return schedule[0][1:], schedule


def last_command_time(scenario: Scenario) -> float:
    """The last time (s, on the walk's clock) a velocity command changes a walk of ``scenario`` by command: the
    start of phase ``2n - 1`` (the swing of its last forward step ``n = walk.steps``) with the real-time and auto
    connections, of ``2n - 2`` (the double support before it) with the quasi-real-time one. From then on step ``n``
    can no longer change (:meth:`rtgait.core.walk.walk.Walk.first_open_step`) and the walk is stopped
    (:mod:`rtgait.sim.loop_inputs`); a command due at that very tick still reaches step ``n``. A walk by command
    has one timing for every step."""
    steps = scenario.steps
    phase = 2 * steps - 2 if scenario.connection == "quasi-real-time" else 2 * steps - 1
    return Timeline(scenario.timing).start_time(phase)


def _check_command_times(texts: Sequence[str] | None, schedule: list[tuple[float, ...]], scenario: Scenario) -> None:
    """Refuse a ``--velocity ...@T`` that would silently change nothing, as a ``--push`` after the run is."""
    if not schedule:
        return
    last = last_command_time(scenario)
    for text, (t, *_) in zip(texts or (), schedule, strict=True):
        if t > last + 1e-9:  # the loop's own tolerance on a command's time (rtgait.sim.loop_inputs)
            raise ScenarioError(
                f"--velocity {text} comes after the walk's last step is decided (at {last:.2f} s on the walk's clock):"
                " it would change nothing; more walk.steps make the walk longer"
            )


def _check_periods(control_dt: float | None, physics_dt: float | None) -> None:
    """The periods asked for, when both are known before the robot is (s); each must be a duration > 0."""
    for name, value in (("--control-dt", control_dt), ("--physics-dt", physics_dt)):
        if value is not None and not (math.isfinite(value) and 1e-5 <= value <= 0.1):
            raise ScenarioError(f"{name} must be within [1e-05, 0.1] s, got {value}")
    if control_dt is not None and physics_dt is not None:
        from rtgait.sim.actuation import substeps

        try:
            substeps(control_dt, physics_dt)
        except ValueError as error:
            raise ScenarioError(f"--physics-dt: {error}") from None


def _check_gains(robot: RobotModel, gains: str, drive: str) -> None:
    """The robot's own gains, which ``--gains robot`` and ``--drive torque`` need, are in its description."""
    if gains != "robot" and drive != "torque":
        return
    missing = [
        name for name in robot.joint_names
        if robot.description.joint_actuation(name).robot_kp is None
        or robot.description.joint_actuation(name).robot_kd is None
    ]  # fmt: skip
    if missing:
        flag = "--gains robot" if gains == "robot" else "--drive torque"
        raise ScenarioError(
            f"{flag}: the description of {robot.name} gives no robot_kp and robot_kd for joint {missing[0]} "
            "([[actuation.joints]])"
        )


def _physics_config(robot: RobotModel, control_dt: float | None, physics_dt: float | None) -> SimConfig:
    """The physics parameters with the periods asked for, checked against the robot's own control period."""
    from rtgait.io.sim_run import sim_config
    from rtgait.sim.actuation import substeps

    config = sim_config(None, control_dt, physics_dt)
    actuation = robot.description.actuation
    control = actuation.control_dt if control_dt is None else control_dt
    try:
        substeps(control, actuation.physics_dt if config.physics_dt is None else config.physics_dt)
    except ValueError as error:
        raise ScenarioError(f"--physics-dt: {error} (the control period of {robot.name})") from None
    return config


def _check_simulation(
    args: argparse.Namespace, scenario: Scenario, velocity: tuple[float, ...] | None, out: Path
) -> list[Push]:  # velocity: the first command, enough to tell a walk by command
    """Everything about a simulation that can be checked before loading the robot; returns the pushes."""
    from rtgait.io.sim_files import sim_figure_file
    from rtgait.io.sim_run import simulated_time
    from rtgait.sim.log_file import LOG_FILE, parquet_available

    run_time = simulated_time(scenario, velocity=velocity)
    check_run_length(run_time, args.physics_dt or 0.001)
    lead = 1.5  # the start transition (LoopOptions' start_ramp + start_hold): the walk's clock starts after it
    pushes = _pushes(args.push, run_time - lead)
    figures = not args.no_figures
    require_extras(figures, args.html)
    names = ["sim.csv", "summary.json"] + ([sim_figure_file(args.figure_format)] if figures else [])
    if parquet_available():
        names.append(LOG_FILE)
    else:
        warnings.warn(f"pyarrow is not installed: {LOG_FILE} (the complete log) is not written; pip install "
                      "'rtgait[sim]'", stacklevel=1)  # fmt: skip
    check_destination(out, names + (["replay.html"] if args.html else []))
    return pushes
