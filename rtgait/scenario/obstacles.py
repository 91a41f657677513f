"""The ``[[obstacle]]`` entries of a scenario file: boxes on the ground that the walk sees while walking, and the
scenario's own stride limits, ``[robot.velocity]``, that bound the footsteps' changes around them.

::

    [[obstacle]]              # one per box, any number
    x = 1.71                  # m, the box's centre in the world frame (the walk starts at the origin heading +x)
    y = -0.10                 # m
    length = 0.30             # m, along the box's own x axis (> 0)
    width = 0.20              # m, across it (> 0)
    height = 0.30             # m (>= 0): a box lower than the swing height less a clearance is stepped over
    yaw = 0.0                 # rad, optional (default 0), within [-pi, pi]
    seen_at = 2.55            # s from the walk's start (>= 0, within the walk): when the robot sees it

    [robot.velocity]          # optional: the robot's stride limits, a robot description's [velocity] keys
    max_step_length = 0.29    # m
    max_step_lateral = 0.25   # m per pair of steps
    max_step_turn = 0.6       # rad per pair of steps
    min_step_width = 0.15     # m

When it is seen the walk changes its remaining footsteps to keep off the box (:mod:`rtgait.core.obstacle.avoid`).
Every problem raises :class:`~rtgait.scenario.checks.ScenarioError` with one line naming the field.
"""

from __future__ import annotations

import math
from typing import Any

from rtgait.core.obstacle.box import MAX_OBSTACLE_SIZE, Obstacle
from rtgait.core.planner.config import VelocityLimits
from rtgait.scenario.checks import ScenarioError
from rtgait.scenario.tomlfile import TomlFiles

__all__ = ["OBSTACLE_KEYS", "check_seen_within", "parse_obstacles", "parse_robot_velocity"]

_FILES = TomlFiles(kind="scenario", folder="scenarios", error=ScenarioError)
OBSTACLE_KEYS = ("x", "y", "length", "width", "height", "seen_at")
"""The keys every ``[[obstacle]]`` entry must have (``yaw`` is optional)."""
_SIZE_WHY = f"within (0, {MAX_OBSTACLE_SIZE:g}] m"


def parse_obstacles(raw: Any) -> tuple[Obstacle, ...]:
    """The ``[[obstacle]]`` array of a scenario document, each entry checked (module docstring)."""
    if not isinstance(raw, list):
        raise ScenarioError("obstacle must be an array of tables, written [[obstacle]]")
    obstacles = []
    for index, entry in enumerate(raw):
        where = f"obstacle[{index}]"
        entry = _FILES.table(entry, where)
        _FILES.check_keys(entry, where, OBSTACLE_KEYS, ("yaw",))
        values = {key: _FILES.number(entry[key], f"{where}.{key}", unit="m") for key in ("x", "y")}
        for key in ("length", "width"):
            value = _FILES.number(entry[key], f"{where}.{key}", rule="> 0", unit="m")
            if value > MAX_OBSTACLE_SIZE:
                raise ScenarioError(f"{where}.{key} must be {_SIZE_WHY}, got {value!r}")
            values[key] = value
        values["height"] = _FILES.number(entry["height"], f"{where}.height", rule=">= 0", unit="m")
        if values["height"] > MAX_OBSTACLE_SIZE:
            raise ScenarioError(f"{where}.height must be within [0, {MAX_OBSTACLE_SIZE:g}] m, got {values['height']!r}")
        values["seen_at"] = _FILES.number(entry["seen_at"], f"{where}.seen_at", rule=">= 0", unit="s")
        if "yaw" in entry:
            yaw = _FILES.number(entry["yaw"], f"{where}.yaw", unit="rad")
            if abs(yaw) > math.pi:
                raise ScenarioError(f"{where}.yaw must be within [-pi, pi] rad, got {yaw!r}")
            values["yaw"] = yaw
        try:
            obstacles.append(Obstacle(**values))
        except ValueError as error:  # the core's own bounds (positions within the planner's range)
            raise ScenarioError(f"{where}: {error}") from None
    return tuple(obstacles)


def check_seen_within(obstacles: tuple[Obstacle, ...], duration: float) -> None:
    """Every obstacle is seen while the walk goes on (before its ``duration``, s)."""
    for index, obstacle in enumerate(obstacles):
        if not isinstance(obstacle, Obstacle):
            raise ScenarioError(f"obstacles[{index}] must be an Obstacle, got {type(obstacle).__name__}")
        if obstacle.seen_at >= duration:
            raise ScenarioError(
                f"obstacle[{index}].seen_at must be within the walk (before {duration:g} s), got {obstacle.seen_at!r}"
            )


def parse_robot_velocity(raw: Any) -> VelocityLimits:
    """The ``[robot.velocity]`` table: the robot's stride limits, as a robot description's ``[velocity]``."""
    table = _FILES.table(raw, "robot.velocity")
    try:
        return VelocityLimits.from_table(table, "robot.velocity")
    except ValueError as error:
        raise ScenarioError(str(error)) from None
