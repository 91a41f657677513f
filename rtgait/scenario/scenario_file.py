"""A scenario's TOML tables read into a :class:`~rtgait.scenario.scenario.Scenario`: each field checked with its unit
(m, s, rad, kg) and range as it is read, so that an error names the field (``docs/cli_and_scenarios.md``, "Scenario
files"); the parts a footstep plan shares (:mod:`rtgait.scenario.footholds`) too.
"""

from __future__ import annotations

from typing import Any

from rtgait.core.geometry.footsteps import (
    SoleRect,
    Timing,
)
from rtgait.core.limits import (
    MAX_HORIZON_STEPS,
    MAX_PHASE_DURATION,
    MIN_DT,
)
from rtgait.core.planner.config import ALL_CONNECTION_MODES, MAX_AUTO_MARGIN
from rtgait.scenario.checks import (
    ScenarioError,
)
from rtgait.scenario.fields import LENGTH_BOUNDS as _LENGTH_BOUNDS
from rtgait.scenario.fields import WIDTH_BOUNDS as _WIDTH_BOUNDS
from rtgait.scenario.fields import YAW_RULE as _YAW_RULE
from rtgait.scenario.fields import choice as _choice
from rtgait.scenario.fields import number as _number
from rtgait.scenario.fields import parse_changes as _parse_changes
from rtgait.scenario.fields import parse_guide as _parse_guide
from rtgait.scenario.obstacles import parse_obstacles, parse_robot_velocity
from rtgait.scenario.scenario import (
    _COG_HEIGHT_BOUNDS,
    _FILES,
    _GRAVITY_BOUNDS,
    _HORIZON_WHY,
    _MASS_BOUNDS,
    _NAME_PATTERN,
    _PHASE_BOUNDS,
    _STEPS_WHY,
    DEFAULT_STEP_HEIGHT,
    DEFAULT_STEP_WIDTH,
    MAX_WALK_STEPS,
    Scenario,
)
from rtgait.scenario.terrain_table import parse_terrain
from rtgait.scenario.walking_table import parse_walking

__all__ = ["build_scenario", "number", "parse_common", "parse_scenario", "walk_stance"]


def parse_common(data: dict[str, Any]) -> dict[str, Any]:
    """The parts a scenario and a footstep plan (:mod:`rtgait.scenario.footholds`) share: ``name``, ``description``,
    ``connection``, ``auto_margin``, ``[robot]``, ``[timing]``, ``[control]``, ``[[obstacle]]`` and
    ``[walking.<robot>]``, checked (``[control]``'s keys by :mod:`rtgait.control.control_table` when applied), as
    :class:`Scenario` keywords."""
    name = _FILES.string(data, "name")
    if not _NAME_PATTERN.fullmatch(name):
        raise ScenarioError(f"name must be letters, digits, '.', '_' or '-' (a folder name), got {name!r}")
    description = _FILES.string(data, "description") if "description" in data else ""
    if "\n" in description:
        raise ScenarioError("description must be a single line")
    connection = _choice(data, "connection", "", ALL_CONNECTION_MODES)
    auto_margin = 0.01
    if "auto_margin" in data:
        if connection != "auto":
            raise ScenarioError(f'auto_margin is for connection = "auto", got connection = "{connection}"')
        auto_margin = _number(data, "auto_margin", "", unit="m", bounds=(-MAX_AUTO_MARGIN, MAX_AUTO_MARGIN))

    robot = _FILES.table(data["robot"], "robot")
    _FILES.check_keys(robot, "robot", ("cog_height", "sole"), ("gravity", "mass", "velocity"))
    cog_height = _number(robot, "cog_height", "robot", rule="> 0", unit="m", bounds=_COG_HEIGHT_BOUNDS)
    gravity = 9.81
    if "gravity" in robot:
        gravity = _number(robot, "gravity", "robot", rule="> 0", unit="m/s^2", bounds=_GRAVITY_BOUNDS)
    mass = _number(robot, "mass", "robot", rule="> 0", unit="kg", bounds=_MASS_BOUNDS) if "mass" in robot else None
    sole_table = _FILES.table(robot["sole"], "robot.sole")
    sides = ("front", "back", "inner", "outer")
    _FILES.check_keys(sole_table, "robot.sole", sides, ())
    sole_values = {key: _number(sole_table, key, "robot.sole", rule=">= 0", unit="m") for key in sides}
    if sole_values["front"] + sole_values["back"] <= 0.0 or sole_values["inner"] + sole_values["outer"] <= 0.0:
        raise ScenarioError("robot.sole must have a positive length (front + back) and width (inner + outer)")
    sole = SoleRect(**sole_values)

    timing_table = _FILES.table(data["timing"], "timing")
    durations = ("single_support", "double_support")
    extra_durations = ("start", "end", "settle")
    _FILES.check_keys(timing_table, "timing", (*durations, "dt", "horizon_steps"), extra_durations)
    timing_values = {
        key: _number(timing_table, key, "timing", rule="> 0", unit="s", bounds=_PHASE_BOUNDS)
        for key in (*durations, *extra_durations)
        if key in timing_table
    }
    timing = Timing(**timing_values)
    dt = _number(timing_table, "dt", "timing", rule="> 0", unit="s", bounds=(MIN_DT, MAX_PHASE_DURATION))
    horizon_steps = _FILES.count(
        timing_table["horizon_steps"], "timing.horizon_steps", high=MAX_HORIZON_STEPS, why=_HORIZON_WHY
    )
    control = _FILES.settings(data["control"], "control") if "control" in data else ()
    velocity = parse_robot_velocity(robot["velocity"]) if "velocity" in robot else None
    obstacles = parse_obstacles(data["obstacle"]) if "obstacle" in data else ()
    walking = parse_walking(data["walking"]) if "walking" in data else ()
    return {
        "name": name, "description": description, "connection": connection, "auto_margin": auto_margin,
        "cog_height": cog_height, "gravity": gravity, "mass": mass, "sole": sole, "timing": timing, "dt": dt,
        "horizon_steps": horizon_steps, "control": control, "velocity": velocity, "obstacles": obstacles,
        "walking": walking,
    }  # fmt: skip


def walk_stance(walk: dict[str, Any]) -> tuple[float, float]:
    """``step_width`` and ``step_height`` (m) of a ``[walk]`` table, checked; each :data:`DEFAULT_STEP_WIDTH` or
    :data:`DEFAULT_STEP_HEIGHT` when not given (a scenario's table has both: its keys are checked first)."""
    step_width = DEFAULT_STEP_WIDTH
    if "step_width" in walk:
        step_width = _number(walk, "step_width", "walk", rule="> 0", unit="m", bounds=_WIDTH_BOUNDS)
    step_height = DEFAULT_STEP_HEIGHT
    if "step_height" in walk:
        step_height = _number(walk, "step_height", "walk", rule=">= 0", unit="m")
    return step_width, step_height


number = _number
"""A finite number of a scenario-like file, checked and worded as the scenario's own fields (for
:mod:`rtgait.scenario.footholds`)."""


def build_scenario(**fields: Any) -> Scenario:
    """:class:`Scenario` from parsed fields, its cross-field messages pointed at the TOML table they live in."""
    try:
        return Scenario(**fields)
    except ScenarioError as error:
        message = str(error)
        if message.startswith("dt "):
            message = "timing." + message
        raise ScenarioError(message) from None


def parse_scenario(data: dict[str, Any], source: str = "") -> Scenario:
    """Build a :class:`Scenario` from the parsed TOML document ``data`` (see the module docstring)."""
    _FILES.check_keys(
        data,
        "",
        ("name", "connection", "robot", "timing", "walk"),
        ("description", "guide", "auto_margin", "control", "obstacle", "terrain", "walking"),
    )
    common = parse_common(data)
    connection = common["connection"]

    walk = _FILES.table(data["walk"], "walk")
    walk_required = ("steps", "step_length", "step_width", "step_height")
    _FILES.check_keys(walk, "walk", walk_required, ("yaw", "first_foot", "change"))
    steps = _FILES.count(walk["steps"], "walk.steps", high=MAX_WALK_STEPS, why=_STEPS_WHY)
    step_length = _number(walk, "step_length", "walk", unit="m", bounds=_LENGTH_BOUNDS)
    step_width, step_height = walk_stance(walk)
    yaw = _number(walk, "yaw", "walk", rule=_YAW_RULE, unit="rad") if "yaw" in walk else 0.0
    first_foot = _choice(walk, "first_foot", "walk", ("right", "left")) if "first_foot" in walk else "right"
    changes = _parse_changes(walk["change"], steps) if "change" in walk else ()
    guide = _parse_guide(data["guide"]) if "guide" in data else None
    if guide is not None and connection != "quasi-real-time":
        raise ScenarioError("a [guide] walk uses the quasi-real-time connection (the paper's Section 6)")

    return build_scenario(
        **common,
        steps=steps,
        step_length=step_length,
        step_width=step_width,
        step_height=step_height,
        changes=changes,
        yaw=yaw,
        first_foot=first_foot,
        source=source,
        guide=guide,
        terrain=parse_terrain(data["terrain"], step_width) if "terrain" in data else None,
    )
