"""A scenario's ``[walking.<robot>]`` tables: what one walk asks of a named robot in place of its description's
``[walking]`` values.

A robot walks every scenario at its own COG height (its description's ``walking.cog_height``), whatever the
scenario's ``[robot] cog_height`` (the pendulum's, for runs without a robot). Some walks need another one: up a
staircase whose risers are taller than the robot's nominal crouch allows, the trailing leg straightens before its
foot lifts off, and a lower COG (more knee bend on both legs) gives it the length it lacks. Such a height belongs to
one robot (a height right for Talos is out of G1's reach), so it is given per robot name::

    [walking.talos]
    cog_height = 0.80      # m, the COG's height above the support, for this walk only
    toe_release = 0.5      # share of a swing up a stair over which the sole levels after its toe-off

Keys: ``cog_height`` (m, within the scenario's COG bounds) and ``toe_release`` (a share in (0, 1], as the robot
description's ``walking.toe_release``, :mod:`rtgait.core.geometry.toe_off`); both optional, at least one. A robot
without a table walks the scenario with its own values. :func:`rtgait.robot.motion.walking_robot` applies them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from rtgait.core.limits import MAX_COG_HEIGHT, MIN_COG_HEIGHT
from rtgait.scenario.checks import ScenarioError, within
from rtgait.scenario.fields import number
from rtgait.scenario.tomlfile import TomlFiles

__all__ = ["RobotWalking", "parse_walking", "walking_for"]

_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)
_ROBOT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
_KEYS = ("cog_height", "toe_release")


@dataclass(frozen=True)
class RobotWalking:
    """The walking values one walk asks of the robot named ``robot`` (``None``: the robot's own).

    Attributes:
        robot: the robot's name (its description's ``name``).
        cog_height: the COG's height above the support for this walk (m).
        toe_release: share of a swing up a stair over which the sole levels after its toe-off.
    """

    robot: str
    cog_height: float | None = None
    toe_release: float | None = None

    def __post_init__(self) -> None:
        where = f"walking.{self.robot}"
        if not (isinstance(self.robot, str) and _ROBOT_NAME.fullmatch(self.robot)):
            raise ScenarioError(f"walking: a robot's name must be letters, digits, '.', '_' or '-', got {self.robot!r}")
        if self.cog_height is None and self.toe_release is None:
            raise ScenarioError(f"{where} must set cog_height or toe_release")
        if self.cog_height is not None:
            within(f"{where}.cog_height", self.cog_height, (MIN_COG_HEIGHT, MAX_COG_HEIGHT), "m")
        if self.toe_release is not None and not 0.0 < self.toe_release <= 1.0:
            raise ScenarioError(f"{where}.toe_release must be a share of the swing in (0, 1], got {self.toe_release:g}")


def parse_walking(raw: Any) -> tuple[RobotWalking, ...]:
    """The ``[walking.<robot>]`` tables of a scenario file, checked, in the file's order."""
    tables = _FILES.table(raw, "walking")
    out = []
    for name, entry in tables.items():
        where = f"walking.{name}"
        entry = _FILES.table(entry, where)
        _FILES.check_keys(entry, where, (), _KEYS)
        values = {key: number(entry, key, where, rule="> 0", unit="m" if key == "cog_height" else "") for key in entry}
        out.append(RobotWalking(robot=name, **values))
    return tuple(out)


def walking_for(walking: tuple[RobotWalking, ...], robot: str) -> RobotWalking | None:
    """The values ``walking`` asks of the robot named ``robot``, or ``None``: it walks with its own."""
    return next((entry for entry in walking if entry.robot == robot), None)
