"""What the ``rtgait`` subcommands share: the program's name, the error that is not the input's fault, one-line
messages, progress bars, loading a robot, checks made before a long run."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from rtgait.core.limits import MAX_ROLLOUT_TICKS
from rtgait.estimation.estimator import DEFAULT_STATE, STATE_SOURCES
from rtgait.scenario.scenario import Scenario, ScenarioError
from rtgait.viz.figure_files import FIGURE_FORMATS

if TYPE_CHECKING:
    from rtgait.estimation.estimator import StateSource
    from rtgait.robot.model import RobotModel
    from rtgait.sim.config import SensorSettings

PROG = "rtgait"


class RunError(Exception):
    """The run could not complete for a reason other than the input (a missing extra package)."""


def out_folder(text: str) -> Path:
    # Path("") is Path("."): an empty --out (an unset shell variable) would write into the working folder.
    if not text:
        raise argparse.ArgumentTypeError("must name a folder, got an empty string")
    return Path(text)


def add_format_option(
    parser: argparse.ArgumentParser,
    default: str | None = "png",
    description: str = "file format of the figures: png (default), pdf or svg (vector, for papers)",
) -> None:
    """``--format png|pdf|svg``, the figures' file format, as ``args.figure_format`` (every command that draws
    figures; ``default=None`` lets a command tell whether it was given)."""
    parser.add_argument("--format", choices=FIGURE_FORMATS, default=default, dest="figure_format", help=description)


def add_replay_background_option(parser: argparse.ArgumentParser) -> None:
    """``--replay-background sky|white``: the 3D replay's background, as ``args.replay_background``."""
    parser.add_argument(
        "--replay-background",
        choices=("sky", "white"),
        default="sky",
        help="with --html: the replay's background, sky (meshcat's blue gradient, default) or white (for print)",
    )


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


def load_robot(name: str, scenario: Scenario | None = None) -> RobotModel:
    """The robot ``name`` (built-in, or a description file), as it walks ``scenario`` when one is given: with the
    COG height and toe release the scenario's ``[walking.<robot>]`` asks of it
    (:func:`~rtgait.robot.motion.walking_robot`)."""
    try:
        from rtgait.robot.model import RobotModel
        from rtgait.robot.motion import walking_robot
    except ImportError:
        raise RunError("--robot needs Pinocchio and example-robot-data: pip install 'rtgait[robot]'") from None
    robot = RobotModel.load(name)
    return robot if scenario is None else walking_robot(robot, scenario)


@contextlib.contextmanager
def asked_walking(scenario: Scenario, robot: RobotModel) -> Iterator[None]:
    """Run the reach check of ``robot`` on ``scenario``: a refusal of a walk at the COG height the scenario asks of
    the robot names that setting, the likely cause."""
    from rtgait.robot.motion import UnreachableError
    from rtgait.scenario.walking_table import walking_for

    try:
        yield
    except UnreachableError as error:
        entry = walking_for(scenario.walking, robot.name)
        if entry is None or entry.cog_height is None:
            raise
        raise UnreachableError(
            f"{error}, with the COG at the scenario's walking.{robot.name}.cog_height = {entry.cog_height:g} m"
        ) from None


def robot_walk(scenario: Scenario, robot: RobotModel) -> Scenario:
    """``scenario`` as ``robot`` walks it (its COG height, step width and sole), checked like the scenario."""
    from rtgait.robot.motion import robot_scenario

    try:
        return robot_scenario(scenario, robot)
    except ScenarioError as error:  # e.g. a description's COG height outside the limits
        raise ScenarioError(f"with robot {robot.name}: {error}") from None


class _Progress:
    """A tqdm bar driven by the fraction of the work done (the callback the long runs take)."""

    def __init__(self, stream: TextIO, label: str, total: int | None, unit: str) -> None:
        from tqdm import tqdm

        # With a count the bar shows its rate (ticks per second); with a fraction only, the share done and the
        # time left. leave=False: the bar is erased when done, so the summary printed after it starts clean.
        self._total = total
        self._bar = tqdm(
            total=total if total is not None else 100,
            desc=label,
            file=stream,
            leave=False,
            disable=None,  # None: nothing on a stream that is not a terminal (a log file, a pipe)
            unit=f" {unit}" if total is not None else "%",  # "2.5k ticks/s"
            unit_scale=total is not None,
            dynamic_ncols=True,
            bar_format=None if total is not None else "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]",
        )

    def __call__(self, fraction: float) -> None:
        done = round(min(max(fraction, 0.0), 1.0) * self._bar.total)
        if done > self._bar.n:
            self._bar.update(done - self._bar.n)  # tqdm throttles the redraws itself
        if fraction >= 1.0:
            self.close()

    def close(self) -> None:
        """Erase the bar (again harmless)."""
        self._bar.close()


def progress_printer(
    stream: TextIO, label: str, total: int | None = None, unit: str = "ticks"
) -> Callable[[float], None]:
    """A progress bar on ``stream`` (tqdm), as a callback taking the fraction of the work done, 0 to 1.

    ``total``: how many ``unit`` the whole work is, for a rate in ``unit`` per second; without it the bar shows the
    share done and the time left. The bar closes (and erases itself) when the fraction reaches 1; callers decide
    whether to show one at all (a terminal, no ``--quiet``), and tqdm shows nothing on a stream that is no terminal.
    """
    return _Progress(stream, label, total, unit)


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


MAX_LATENCY = 1000
"""Largest ``--latency`` (control periods): the robot descriptions' own limit for ``sensors.latency``."""


def add_state_options(parser: argparse.ArgumentParser) -> None:
    """``--state``, ``--sensor-noise``, ``--sensor-seed``, ``--latency`` and ``--model-error``: what the controller
    acts on, how the simulated sensors report and how the simulated robot differs from its model (read back by
    :func:`state_settings`)."""
    parser.add_argument(
        "--state",
        choices=STATE_SOURCES,
        default=DEFAULT_STATE,
        help="what the controller acts on: estimated (default), the state estimated from the simulated robot's "
        "sensors (IMU, encoders, foot force sensors or joint torques), as on a robot; truth, the simulator's own "
        "state (COM, velocities, contact forces), to tell the controller's doing from the estimator's",
    )
    parser.add_argument(
        "--sensor-noise",
        metavar="SCALE",
        type=float,
        default=1.0,
        help="factor on every noise, bias and offset of the robot description's [sensors] (default 1; 0: the "
        "readings are the simulator's truth)",
    )
    parser.add_argument(
        "--sensor-seed", metavar="N", type=int, default=0, help="seed of the sensors' noise (integer >= 0, default 0)"
    )
    parser.add_argument(
        "--latency",
        metavar="TICKS",
        type=int,
        help=f"control periods between the sensors' sampling and the controller's reading (0 to {MAX_LATENCY}; "
        "default the robot description's sensors.latency)",
    )
    parser.add_argument(
        "--model-error",
        metavar="SEED",
        type=int,
        help="simulate a robot that differs from the controller's model: masses +-5 %%, centres of mass +-10 mm, "
        "joint zeros +-0.5 deg, drawn from SEED (integer >= 0; default none: the robot is its model)",
    )


def check_state_options(args: argparse.Namespace) -> None:
    """Refuse a bad value of :func:`add_state_options`' options, one line each (nothing is imported)."""
    noise, seed, latency, model_error = args.sensor_noise, args.sensor_seed, args.latency, args.model_error
    if not (math.isfinite(noise) and noise >= 0.0):
        raise ScenarioError(f"--sensor-noise must be a finite factor >= 0, got {noise:g}")
    if seed < 0:
        raise ScenarioError(f"--sensor-seed must be an integer >= 0, got {seed}")
    if latency is not None and not 0 <= latency <= MAX_LATENCY:
        raise ScenarioError(f"--latency must be a whole number of control periods in [0, {MAX_LATENCY}], got {latency}")
    if model_error is not None and model_error < 0:
        raise ScenarioError(f"--model-error must be an integer seed >= 0, got {model_error}")


def state_settings(args: argparse.Namespace) -> tuple[StateSource, SensorSettings, int | None]:
    """The state, sensor settings and model error seed of :func:`add_state_options`, checked
    (:func:`check_state_options`; needs MuJoCo)."""
    check_state_options(args)
    from rtgait.sim.config import SensorSettings

    sensors = SensorSettings(noise=args.sensor_noise, latency=args.latency, seed=args.sensor_seed)
    return args.state, sensors, args.model_error


def print_error(message: str) -> None:
    # One line, whatever the message: scripts grep stderr and humans read the first line only.
    print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)
