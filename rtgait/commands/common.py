"""What the ``rtgait`` subcommands share: the program's name, the error that is not the input's fault, one-line
messages, progress lines, loading a robot, checks made before a long run."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from rtgait.core.limits import MAX_ROLLOUT_TICKS
from rtgait.scenario import Scenario, ScenarioError

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

PROG = "rtgait"


class RunError(Exception):
    """The run could not complete for a reason other than the input (a missing extra package)."""


def out_folder(text: str) -> Path:
    # Path("") is Path("."): an empty --out (an unset shell variable) would write into the working folder.
    if not text:
        raise argparse.ArgumentTypeError("must name a folder, got an empty string")
    return Path(text)


def require_extras(figures: bool, html: bool) -> None:
    """Fail fast, before a long run, when an output asked for needs a package that is not installed."""
    if figures:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise RunError("figures need matplotlib: pip install 'rtgait[viz]', or pass --no-figures") from None
    if html:
        try:
            import meshcat  # noqa: F401
        except ImportError:
            raise RunError("--html needs meshcat: pip install 'rtgait[viz]'") from None


def load_robot(name: str) -> RobotModel:
    try:
        from rtgait.robot.model import RobotModel
    except ImportError:
        raise RunError("--robot needs Pinocchio and example-robot-data: pip install 'rtgait[robot]'") from None
    return RobotModel.load(name)


def robot_walk(scenario: Scenario, robot: RobotModel) -> Scenario:
    """``scenario`` as ``robot`` walks it (its COG height, step width and sole), checked like the scenario."""
    from rtgait.robot.motion import robot_scenario

    try:
        return robot_scenario(scenario, robot)
    except ScenarioError as error:  # e.g. a description's COG height outside the limits
        raise ScenarioError(f"with robot {robot.name}: {error}") from None


def progress_printer(stream: TextIO, label: str) -> Callable[[float], None]:
    def report(fraction: float) -> None:
        stream.write(f"\r{label} {fraction * 100:3.0f}%")
        stream.flush()

    return report


def numbers(text: str, count: int, option: str) -> tuple[float, ...]:
    """``count`` finite comma-separated numbers from an option's value."""
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ScenarioError(f"{option} needs {count} finite comma-separated numbers, got {text!r}")
    return values


def check_run_length(seconds: float, timestep: float) -> None:
    """A simulation records every physics tick: at most MAX_ROLLOUT_TICKS of them, like a rollout."""
    ticks = math.floor(seconds / timestep + 1e-9) + 1
    if ticks > MAX_ROLLOUT_TICKS:
        raise ScenarioError(
            f"the simulation would last {seconds:g} s, which at the physics step dt {timestep:g} s is duration / dt "
            f"+ 1 = {ticks} ticks, at most {MAX_ROLLOUT_TICKS}: take fewer walk.steps (or a shorter [guide] path)"
        )


def print_error(message: str) -> None:
    # One line, whatever the message: scripts grep stderr and humans read the first line only.
    print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)

