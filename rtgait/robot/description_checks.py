"""Reading and checking the parts of a robot description (:mod:`rtgait.robot.description`), and the error they raise.

Each function reads one part of the TOML document and checks it, raising :class:`RobotError` with one line naming
the field: the paths (``model.urdf``, ``model.package_dirs``), the joint-valued tables (``[posture]``, ``[gains]``),
the ``[actuation]`` table (:mod:`rtgait.robot.actuation_table`: a group's ``rotor_inertia`` and ``gear_ratio``
become its armature, ``armature = rotor_inertia * gear_ratio^2`` in kg m^2) and the ``[stepping]`` and
``[velocity]`` limits (their values checked by the core's own parsers). Names are checked against the URDF's
(:func:`read_urdf`, :func:`read_urdf_names`: links, joints with their types and limits, read with the standard
library's XML parser, not Pinocchio, so that a description can be validated without building the model).

:func:`rtgait.robot.description.parse_robot` puts the parts together into a
:class:`~rtgait.robot.description.RobotDescription`.
"""

from __future__ import annotations

import fnmatch
import xml.etree.ElementTree as ElementTree
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.laws.stepping import STEPPING_KEYS, SteppingLimits
from rtgait.core.planner.config import MORE_SWAY_KEY, SWAY_KEY, VELOCITY_KEYS, VelocityLimits
from rtgait.robot.actuation_table import ActuationSpec, ActuatorGroup
from rtgait.robot.data import RobotDataError, robots_dir, share_dir
from rtgait.robot.motor_types import MOTOR_KEYS, MotorType
from rtgait.scenario.tomlfile import TomlFiles

__all__ = [
    "ERD_PREFIX",
    "FILES",
    "LIMITED_TYPES",
    "MOVABLE_TYPES",
    "RobotError",
    "UrdfNames",
    "default_package_dirs",
    "joint_values",
    "parse_actuation",
    "parse_gain",
    "parse_stepping",
    "parse_velocity",
    "read_urdf",
    "read_urdf_names",
    "resolve_path",
    "resolve_urdf",
]

ERD_PREFIX = "example-robot-data:"
"""Prefix of ``model.urdf`` values that name a file below example-robot-data's ``robots/`` folder."""

# URDF joint types with one coordinate and position limits: the whole-body IK moves these only.
LIMITED_TYPES = ("revolute", "prismatic")
MOVABLE_TYPES = (*LIMITED_TYPES, "continuous")


class RobotError(ValueError):
    """A robot description is unknown, unreadable or invalid. The message is one line naming the field."""


FILES = TomlFiles(kind="robot", folder="robots", error=RobotError)
"""The robot description files: the built-in ones (``rtgait/robots/*.toml``, by name) and any other (by path)."""


# ----- the URDF's names -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class UrdfNames:
    """The names a URDF declares: its links, its joints with their types, and the position limits of its limited
    joints (rad or m)."""

    links: frozenset[str]
    joints: dict[str, str]  # every joint name -> its URDF type
    limits: dict[str, tuple[float, float]]  # limited joints -> (lower, upper)

    @property
    def frames(self) -> frozenset[str]:
        # Pinocchio makes a frame of every link and every joint, so either name can serve as a frame.
        return self.links | frozenset(self.joints)


def read_urdf(path: Path) -> ElementTree.Element:
    """The ``<robot>`` element of the URDF at ``path`` (:class:`RobotError` when it is not a readable URDF)."""
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError) as error:
        raise RobotError(f"model.urdf {path} is not a readable URDF: {error}") from None
    if root.tag != "robot":
        raise RobotError(f"model.urdf {path} is not a URDF: its root element is <{root.tag}>, not <robot>")
    return root


def read_urdf_names(root: ElementTree.Element, path: Path) -> UrdfNames:
    """The names the URDF ``root`` (:func:`read_urdf`, from the file ``path``) declares."""
    links = frozenset(link.get("name", "") for link in root.findall("link"))
    joints: dict[str, str] = {}
    limits: dict[str, tuple[float, float]] = {}
    # <joint> elements also occur inside <transmission>; only direct children of <robot> are joints.
    for joint in root.findall("joint"):
        name, kind = joint.get("name", ""), joint.get("type", "")
        joints[name] = kind
        limit = joint.find("limit")
        if kind in LIMITED_TYPES and limit is not None:
            try:
                limits[name] = (float(limit.get("lower", "0")), float(limit.get("upper", "0")))
            except ValueError:
                raise RobotError(f"model.urdf {path}: joint {name} has a non-numeric limit") from None
    return UrdfNames(links, joints, limits)


# ----- the tables --------------------------------------------------------------------------------------------


def resolve_path(value: str, base: Path | None, path: str) -> Path:
    candidate = Path(value).expanduser()
    if not candidate.is_absolute():
        if base is None:
            # Built-in descriptions have no folder of their own; they must name example-robot-data files.
            raise RobotError(f"{path} {value!r} is relative, but the description has no folder to resolve it in")
        candidate = base / candidate
    return candidate


def resolve_urdf(value: str, base: Path | None) -> Path:
    if value.startswith(ERD_PREFIX):
        relative = value[len(ERD_PREFIX) :].lstrip("/")
        try:
            folder = robots_dir()
        except RobotDataError as error:
            raise RobotError(f"model.urdf {value!r}: {error}") from None
        path = folder / relative
        if not path.is_file():
            raise RobotError(f"model.urdf {value!r}: example-robot-data has no file robots/{relative}")
        return path
    path = resolve_path(value, base, "model.urdf")
    if not path.is_file():
        raise RobotError(f"model.urdf {value!r}: no such file {path}")
    return path.resolve()


def default_package_dirs() -> tuple[Path, ...]:
    try:
        return (share_dir(),)
    except RobotDataError:
        return ()  # a URDF of one's own needs no example-robot-data; meshes are then only looked up by path


def joint_values(raw: Any, where: str, names: UrdfNames, *, unit: str) -> dict[str, float]:
    table = FILES.table(raw, where)
    values = {}
    for joint, value in table.items():
        if joint not in names.joints or names.joints[joint] not in MOVABLE_TYPES:
            raise RobotError(f"{where}.{joint}: the URDF has no movable joint named {joint!r}")
        values[joint] = FILES.number(value, f"{where}.{joint}", unit=unit)
    return values


def parse_gain(raw: Any, where: str, names: UrdfNames) -> float | Mapping[str, float]:
    if isinstance(raw, dict):
        values = joint_values(raw, where, names, unit="")
        for joint, value in values.items():
            if value < 0.0:
                raise RobotError(f"{where}.{joint} must be a number >= 0, got {value!r}")
        return MappingProxyType(values)
    return FILES.number(raw, where, rule=">= 0")


_GROUP_KEYS = ("kp", "kd", "armature", "rotor_inertia", "gear_ratio", "effort_limit", "natural_frequency",
               "damping_ratio", "robot_kp", "robot_kd")  # fmt: skip
_TABLE_KEYS = ("control_dt", "physics_dt", "natural_frequency", "damping_ratio", "armature_per_torque")
_UNITS = {"kp": "N m/rad", "kd": "N m s/rad", "armature": "kg m^2", "rotor_inertia": "kg m^2", "effort_limit": "N m",
          "natural_frequency": "Hz", "control_dt": "s", "physics_dt": "s", "armature_per_torque": "s^2",
          "robot_kp": "N m/rad", "robot_kd": "N m s/rad", "peak_torque": "N m", "braking_torque": "N m",
          "no_load_speed": "rad/s", "corner_speed": "rad/s", "coulomb_friction": "N m",
          "viscous_friction": "N m s/rad"}  # fmt: skip
_MAY_BE_ZERO = ("kd", "armature", "rotor_inertia", "armature_per_torque", "robot_kd", "corner_speed",
                "coulomb_friction", "viscous_friction")  # fmt: skip


def _numbers(table: dict[str, Any], where: str, keys: tuple[str, ...]) -> dict[str, float]:
    return {
        key: FILES.number(
            table[key], f"{where}.{key}", rule=">= 0" if key in _MAY_BE_ZERO else "> 0", unit=_UNITS.get(key, "")
        )
        for key in keys
        if key in table
    }


def _motor_types(raw: Any) -> dict[str, MotorType]:
    """The ``[actuation.motors.<name>]`` tables (:mod:`rtgait.robot.motor_types`)."""
    motors = {}
    for name, table in FILES.table(raw, "actuation.motors").items():
        where = f"actuation.motors.{name}"
        table = FILES.table(table, where)
        FILES.check_keys(table, where, ("peak_torque", "no_load_speed"), MOTOR_KEYS[2:])
        values = _numbers(table, where, MOTOR_KEYS)
        if values.get("corner_speed", 0.0) >= values["no_load_speed"]:
            raise RobotError(
                f"{where}.corner_speed ({values['corner_speed']:g} rad/s) must be below {where}.no_load_speed "
                f"({values['no_load_speed']:g} rad/s)"
            )
        motors[name] = MotorType(name=name, **values)
    return motors


def _actuator_group(raw: Any, where: str, names: UrdfNames, motors: Mapping[str, MotorType]) -> ActuatorGroup:
    table = FILES.table(raw, where)
    FILES.check_keys(table, where, ("match",), (*_GROUP_KEYS, "motor"))
    patterns = [table["match"]] if isinstance(table["match"], str) else table["match"]
    if not (isinstance(patterns, list) and patterns and all(isinstance(p, str) and p for p in patterns)):
        raise RobotError(f"{where}.match must be a joint name pattern or a non-empty list of them, got {patterns!r}")
    movable = [j for j, kind in names.joints.items() if kind in MOVABLE_TYPES]
    for pattern in patterns:
        # A pattern that matches nothing is a typo: the group would silently not apply.
        if not any(fnmatch.fnmatchcase(joint, pattern) for joint in movable):
            raise RobotError(f"{where}.match: {pattern!r} matches no movable joint of the URDF")
    values: dict[str, Any] = _numbers(table, where, _GROUP_KEYS)
    if "motor" in table:
        motor = FILES.string(table, "motor", where, non_empty=True)
        if motor not in motors:
            known = ", ".join(motors) or "none"
            raise RobotError(f"{where}.motor: no motor type {motor!r} in [actuation.motors] (described: {known})")
        values["motor"] = motor
    rotor = "rotor_inertia" in values, "gear_ratio" in values
    if any(rotor) and not all(rotor):
        raise RobotError(f"{where}: rotor_inertia and gear_ratio go together (armature = rotor_inertia * gear_ratio^2)")
    if all(rotor):
        if "armature" in values:
            raise RobotError(f"{where}: give armature or rotor_inertia and gear_ratio, not both")
        values["armature"] = values.pop("rotor_inertia") * values.pop("gear_ratio") ** 2
    return ActuatorGroup(match=tuple(patterns), **values)


def parse_actuation(raw: Any, names: UrdfNames) -> ActuationSpec:
    table = FILES.table(raw, "actuation")
    FILES.check_keys(table, "actuation", (), (*_TABLE_KEYS, "command_delay", "motors", "joints"))
    motors = _motor_types(table["motors"]) if "motors" in table else {}
    raw_groups = table.get("joints", [])
    if not isinstance(raw_groups, list):
        raise RobotError("actuation.joints must be an array of tables ([[actuation.joints]])")
    groups = tuple(_actuator_group(g, f"actuation.joints[{i}]", names, motors) for i, g in enumerate(raw_groups))
    delay = table.get("command_delay", 0)
    if not (isinstance(delay, int) and not isinstance(delay, bool) and delay >= 0):
        raise RobotError(f"actuation.command_delay must be a whole number of control periods >= 0, got {delay!r}")
    spec = ActuationSpec(
        groups=groups,
        command_delay=delay,
        motors=MappingProxyType(motors),
        **_numbers(table, "actuation", _TABLE_KEYS),
    )
    ratio = spec.control_dt / spec.physics_dt
    if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6 * ratio:
        raise RobotError(
            f"actuation.physics_dt = {spec.physics_dt:g} s must divide actuation.control_dt = {spec.control_dt:g} s"
        )
    return spec


def parse_stepping(raw: Any, sole: SoleRect) -> SteppingLimits:
    """The ``[stepping]`` table (:class:`~rtgait.core.laws.stepping.SteppingLimits` checks the values)."""
    limits = _limits_table(raw, "stepping", STEPPING_KEYS, SteppingLimits.from_table)
    _soles_apart("stepping.min_width", limits.min_width, sole)
    return limits


def parse_velocity(raw: Any, sole: SoleRect) -> VelocityLimits:
    """The ``[velocity]`` table (:class:`~rtgait.core.planner.config.VelocityLimits` checks the values the way
    :class:`~rtgait.core.planner.config.PlannerConfig` does; ``min_step_width`` against the robot's stance is checked
    when it is applied, :func:`rtgait.robot.motion.robot_scenario`)."""
    limits = _limits_table(raw, "velocity", (*VELOCITY_KEYS, SWAY_KEY, MORE_SWAY_KEY), VelocityLimits.from_table)
    _soles_apart("velocity.min_step_width", limits.min_step_width, sole)
    for i, entry in enumerate(limits.more_sway):
        _soles_apart(f"velocity.{MORE_SWAY_KEY}[{i}].min_step_width", entry.min_step_width, sole)
    return limits


def _limits_table(raw: Any, name: str, keys: tuple[str, ...], parse: Any) -> Any:
    """The table ``name`` of limits, its keys among ``keys``, parsed by ``parse`` (whose errors name the key)."""
    table = FILES.table(raw, name)
    FILES.check_keys(table, name, (), keys)
    try:
        return parse(table)
    except ValueError as error:
        raise RobotError(str(error)) from None


def _soles_apart(key: str, width: float | None, sole: SoleRect) -> None:
    """A least distance ``width`` (m) between the foot frames keeps the soles from overlapping: at least twice the
    sole's inner half-width (``None``: no such limit)."""
    if width is not None and width < 2.0 * sole.inner:
        raise RobotError(
            f"{key} ({width:g} m) must be at least 2 x feet.sole.inner ({2.0 * sole.inner:g} m): the soles would "
            "overlap"
        )
