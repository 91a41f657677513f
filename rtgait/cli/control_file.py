"""The controller's settings of a run from the command line: the ``[control]`` tables of the robot description and
of the scenario, then the one of ``--control FILE`` (a TOML file holding a ``[control]`` table and nothing else),
each over the one before (:mod:`rtgait.control.control_table`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rtgait.scenario.scenario import Scenario, ScenarioError
from rtgait.scenario.tomlfile import SettingsPairs, TomlFiles

if TYPE_CHECKING:
    from rtgait.control.settings import ControllerOptions
    from rtgait.robot.description import RobotDescription

__all__ = ["controller_settings", "read_control_file"]

_FILES = TomlFiles(kind="control settings", folder="", error=ScenarioError)


def read_control_file(path: str | None) -> SettingsPairs:
    """The ``[control]`` table of the file ``path`` (``--control``), as read; ``()`` without a file.

    Raises:
        ScenarioError: an unreadable file, invalid TOML, or anything but a ``[control]`` table in it (one line
            naming the file).
    """
    if path is None:
        return ()
    document = _FILES.load_file(path)
    try:
        _FILES.check_keys(document.data, "", ("control",), ())
        return _FILES.settings(document.data["control"], "control")
    except ScenarioError as error:
        raise ScenarioError(f"--control {path}: {error}") from None


def controller_settings(
    robot: RobotDescription | None,
    scenario: Scenario,
    control_file: str | None,
    file_pairs: SettingsPairs,
    gains: str = "stiff",
) -> tuple[ControllerOptions, dict[str, Any]]:
    """The controller's settings for ``scenario`` walked by ``robot`` (``None``: no robot, the pendulum alone) whose
    drives run at ``gains`` (the robot's table as it applies to them,
    :func:`~rtgait.control.control_table.at_gains`), with ``file_pairs`` from ``control_file``
    (:func:`read_control_file`) over both; and the keys the three tables set, the last value of each, for the run's
    summary (empty when none set any).

    Raises:
        rtgait.control.control_table.ControlSettingsError: a key or value the settings refuse (one line naming the
            file and the key).
    """
    from rtgait.control.control_table import at_gains, control_options, walk_defaults

    layers = [] if robot is None else at_gains(robot.control, gains, f"robot {robot.name}")
    layers.append((f"scenario {scenario.name}", scenario.control))
    if control_file is not None:
        layers.append((f"--control {control_file}", file_pairs))
    terrain = None if scenario.terrain is None else scenario.terrain.terrain.kind
    options = control_options(*layers, base=walk_defaults(terrain))
    chosen = {key: value for _, pairs in layers for key, value in pairs}
    return options, chosen
