"""Robot descriptions: which URDF, which frames are the feet and the torso, how to stand and how to walk.

A robot is described by a small TOML file. The built-in ones ship as package data in ``rtgait/robots/`` and are
loaded by name (``load_robot("talos")``); any other file is loaded by path. Every key::

    name = "talos"                       # letters, digits, '.', '_' or '-'
    description = "one line for listings"

    [model]
    urdf = "example-robot-data:talos_data/robots/talos_reduced.urdf"
    #   either "example-robot-data:<path below example-robot-data's robots/ folder>" or a filesystem path;
    #   a relative path is resolved against the folder of the TOML file
    # package_dirs = ["meshes/share"]    # optional: folders that package:// URIs resolve against (relative
    #                                    # paths as for urdf); default: example-robot-data's share folder

    [feet]
    left_sole_frame = "left_sole_link"   # URDF link or joint whose origin is on the sole, under the ankle,
    right_sole_frame = "right_sole_link" # x forward and z up when the robot stands
    # sole_offset = [0.0, 0.0, -0.035]   # optional, m: from those frames to the sole point, in the frame of the
    #                                    # left foot; the right foot uses the mirror image (y negated)

    [feet.sole]                          # sole rectangle around the sole point, m
    front = 0.105
    back = 0.105
    inner = 0.065                        # toward the other foot
    outer = 0.065

    [walking]
    cog_height = 0.84                    # m above the ground, a little below the half-sitting COG (bent knees)
    moving_joints = ["leg_left_1_joint", ...]   # joints the walking motion may move; all others stay locked
    torso_frame = "torso_2_link"         # kept upright, heading along the mean yaw of the feet

    [posture]                            # half-sitting start posture, joint name -> angle (rad or m);
    leg_left_3_joint = -0.411354         # joints not listed are at 0
    ...

    [gains]                              # optional, for the physics layer: a number for every joint, or a table
    kp = 500.0                           # joint name -> value (N m/rad and N m s/rad for revolute joints)
    kd = 5.0

    [actuation]                          # optional, for the physics layer (docs/robots.md has every key)
    control_dt = 0.001                   # s: the period at which the controller sends joint references
    natural_frequency = 10.0             # Hz: target of the derived kp on the inertia the joint carries
    damping_ratio = 1.0                  # of the derived kd, on the joint's drive and the limb beyond it
    armature_per_torque = 5e-4           # s^2: default armature per N m of effort limit

    [[actuation.joints]]                 # joints matched by fnmatch patterns; a later group wins
    match = ["leg_*_joint"]
    rotor_inertia = 1e-5                 # kg m^2; armature = rotor_inertia * gear_ratio^2 (or give armature)
    gear_ratio = 100.0                   # also: kp, kd, effort_limit, natural_frequency, damping_ratio

    [stepping]                           # optional: step adjustment's limits (rtgait.core.stepping.SteppingLimits);
    max_length = 0.30                    # m, forward and back from the stance foot; every key optional
    min_width = 0.15                     # m between the foot frames, at least 2 x feet.sole.inner (no crossing)
    max_width = 0.40                     # m
    max_swing_speed = 1.0                # m/s, average over the swing
    min_time_to_touchdown = 0.2          # s: no change closer to touch-down
    min_single_support = 0.5             # s: the shortest step timing adaptation may make
    max_single_support = 1.2             # s: the longest (omit it: steps are only shortened)

    [velocity]                           # optional: bounds of walks by velocity command (PlannerConfig's fields of
    max_step_length = 0.29               # the same names, rtgait.core.config.VelocityLimits); every key optional
    max_step_lateral = 0.16              # m of sideways displacement per pair of steps: |vy| <= it / 2T
    max_step_turn = 0.6                  # rad of heading change per pair of steps: |wz| <= it / 2T
    min_step_width = 0.15                # m: the narrowest stance a sideways walk closes to, at most the stance

A joint's actuation is resolved key by key: the last matching ``[[actuation.joints]]`` group that sets the key,
else ``[gains]`` (kp, kd), else a default derived from the URDF by :mod:`rtgait.sim.actuation`.

Every problem with a description raises :class:`RobotError` with one line naming the field. The URDF is read
with the standard library's XML parser (not Pinocchio) to check frame and joint names, so a description can be
validated without building the model.
"""

from __future__ import annotations

import fnmatch
import re
import xml.etree.ElementTree as ElementTree
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rtgait.core.config import VELOCITY_KEYS, VelocityLimits
from rtgait.core.footsteps import SoleRect
from rtgait.core.stepping import STEPPING_KEYS, SteppingLimits
from rtgait.robot.actuation_table import (
    DEFAULT_NATURAL_FREQUENCY,
    ActuationSpec,
    ActuatorGroup,
    JointActuationSpec,
)
from rtgait.robot.data import RobotDataError, robots_dir, share_dir
from rtgait.tomlfile import TomlFiles, is_finite_number

__all__ = [
    "DEFAULT_NATURAL_FREQUENCY",
    "ERD_PREFIX",
    "ActuationSpec",
    "ActuatorGroup",
    "JointActuationSpec",
    "RobotDescription",
    "RobotError",
    "builtin_robots",
    "load_robot",
    "parse_robot",
]

ERD_PREFIX = "example-robot-data:"
"""Prefix of ``model.urdf`` values that name a file below example-robot-data's ``robots/`` folder."""

DEFAULT_ROBOT = "talos"

_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
# URDF joint types with one coordinate and position limits: the whole-body IK moves these only.
_LIMITED_TYPES = ("revolute", "prismatic")
_MOVABLE_TYPES = (*_LIMITED_TYPES, "continuous")


class RobotError(ValueError):
    """A robot description is unknown, unreadable or invalid. The message is one line naming the field."""


_FILES = TomlFiles(kind="robot", folder="robots", error=RobotError)


@dataclass(frozen=True)
class RobotDescription:
    """Everything rtgait needs to know about a humanoid besides its URDF.

    Attributes:
        name: short identifier.
        description: one line for listings.
        urdf: the URDF file (absolute path).
        package_dirs: folders ``package://`` URIs of the URDF's meshes resolve against.
        left_sole_frame, right_sole_frame: URDF frames (links or joints) at or above the soles.
        sole_offset: from the sole frames to the sole point, in the left foot's frame (m); the right foot's
            offset is its mirror image. ``(0, 0, 0)`` when the frames are on the soles already.
        sole: sole rectangle around the sole point (m).
        cog_height: nominal COG height above the ground while walking (m).
        moving_joints: joints the walking motion may move, in the order given.
        torso_frame: frame kept upright while walking.
        posture: half-sitting posture, joint name -> angle (rad; m for prismatic joints); other joints at 0.
        kp, kd: optional joint gains for the physics layer (``[gains]``), one number for all joints or joint name ->
            value.
        actuation: the ``[actuation]`` table (defaults when absent); :meth:`joint_actuation` resolves one joint.
        stepping: the ``[stepping]`` table, step adjustment's limits (keys missing from it take
            :class:`~rtgait.core.stepping.SteppingLimits`'s defaults); ``None`` when the description has none (then
            each user picks its defaults: the pendulum loop the core's, the MuJoCo loop limits scaled by leg length).
        velocity: the ``[velocity]`` table, the bounds of walks by velocity command
            (:class:`~rtgait.core.config.VelocityLimits`, applied to the planner's config of every walk of this
            robot by :func:`rtgait.robot.motion.robot_scenario`); ``None`` when the description has none (then the
            :class:`~rtgait.core.config.PlannerConfig` defaults apply).
        source: where the description came from (``"builtin"`` or a file path); informative only.
    """

    name: str
    description: str
    urdf: Path
    package_dirs: tuple[Path, ...]
    left_sole_frame: str
    right_sole_frame: str
    sole_offset: tuple[float, float, float]
    sole: SoleRect
    cog_height: float
    moving_joints: tuple[str, ...]
    torso_frame: str
    posture: Mapping[str, float]
    kp: float | Mapping[str, float] | None = None
    kd: float | Mapping[str, float] | None = None
    actuation: ActuationSpec = field(default_factory=ActuationSpec)
    stepping: SteppingLimits | None = None
    velocity: VelocityLimits | None = None
    source: str = field(default="", compare=False)

    def posture_angle(self, joint: str) -> float:
        """Half-sitting angle of ``joint`` (rad or m): 0 unless the ``[posture]`` table lists it."""
        return self.posture.get(joint, 0.0)

    def gains(self, joint: str) -> tuple[float, float] | None:
        """``(kp, kd)`` of ``joint`` (N m/rad, N m s/rad), or ``None`` when the description gives none for it."""
        if self.kp is None or self.kd is None:
            return None
        kp = self.kp if isinstance(self.kp, float) else self.kp.get(joint)
        kd = self.kd if isinstance(self.kd, float) else self.kd.get(joint)
        if kp is None or kd is None:
            return None
        return kp, kd

    def joint_actuation(self, joint: str) -> JointActuationSpec:
        """What the description gives for ``joint``'s actuator, key by key (see the module docstring): the last
        matching ``[[actuation.joints]]`` group that sets a key wins, then ``[gains]`` for kp and kd."""
        spec, gains = self.actuation, self.gains(joint)
        values: dict[str, float | None] = {"kp": None, "kd": None, "armature": None, "effort_limit": None}
        if gains is not None:
            values["kp"], values["kd"] = gains
        values.update(natural_frequency=spec.natural_frequency, damping_ratio=spec.damping_ratio)
        for group in (g for g in spec.groups if g.matches(joint)):
            values.update({key: getattr(group, key) for key in values if getattr(group, key) is not None})
        return JointActuationSpec(armature_per_torque=spec.armature_per_torque, **values)  # type: ignore[arg-type]


# ----- the URDF's names -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _UrdfNames:
    links: frozenset[str]
    joints: dict[str, str]  # every joint name -> its URDF type
    limits: dict[str, tuple[float, float]]  # limited joints -> (lower, upper)

    @property
    def frames(self) -> frozenset[str]:
        # Pinocchio makes a frame of every link and every joint, so either name can serve as a frame.
        return self.links | frozenset(self.joints)


def _read_urdf_names(path: Path) -> _UrdfNames:
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError) as error:
        raise RobotError(f"model.urdf {path} is not a readable URDF: {error}") from None
    if root.tag != "robot":
        raise RobotError(f"model.urdf {path} is not a URDF: its root element is <{root.tag}>, not <robot>")
    links = frozenset(link.get("name", "") for link in root.findall("link"))
    joints: dict[str, str] = {}
    limits: dict[str, tuple[float, float]] = {}
    # <joint> elements also occur inside <transmission>; only direct children of <robot> are joints.
    for joint in root.findall("joint"):
        name, kind = joint.get("name", ""), joint.get("type", "")
        joints[name] = kind
        limit = joint.find("limit")
        if kind in _LIMITED_TYPES and limit is not None:
            try:
                limits[name] = (float(limit.get("lower", "0")), float(limit.get("upper", "0")))
            except ValueError:
                raise RobotError(f"model.urdf {path}: joint {name} has a non-numeric limit") from None
    return _UrdfNames(links, joints, limits)


# ----- TOML parsing ---------------------------------------------------------------------------------------------


def _resolve_path(value: str, base: Path | None, path: str) -> Path:
    candidate = Path(value).expanduser()
    if not candidate.is_absolute():
        if base is None:
            # Built-in descriptions have no folder of their own; they must name example-robot-data files.
            raise RobotError(f"{path} {value!r} is relative, but the description has no folder to resolve it in")
        candidate = base / candidate
    return candidate


def _resolve_urdf(value: str, base: Path | None) -> Path:
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
    path = _resolve_path(value, base, "model.urdf")
    if not path.is_file():
        raise RobotError(f"model.urdf {value!r}: no such file {path}")
    return path.resolve()


def _default_package_dirs() -> tuple[Path, ...]:
    try:
        return (share_dir(),)
    except RobotDataError:
        return ()  # a URDF of one's own needs no example-robot-data; meshes are then only looked up by path


def _joint_values(raw: Any, where: str, names: _UrdfNames, *, unit: str) -> dict[str, float]:
    table = _FILES.table(raw, where)
    values = {}
    for joint, value in table.items():
        if joint not in names.joints or names.joints[joint] not in _MOVABLE_TYPES:
            raise RobotError(f"{where}.{joint}: the URDF has no movable joint named {joint!r}")
        values[joint] = _FILES.number(value, f"{where}.{joint}", unit=unit)
    return values


def _gain(raw: Any, where: str, names: _UrdfNames) -> float | Mapping[str, float]:
    if isinstance(raw, dict):
        values = _joint_values(raw, where, names, unit="")
        for joint, value in values.items():
            if value < 0.0:
                raise RobotError(f"{where}.{joint} must be a number >= 0, got {value!r}")
        return MappingProxyType(values)
    return _FILES.number(raw, where, rule=">= 0")


_GROUP_KEYS = ("kp", "kd", "armature", "rotor_inertia", "gear_ratio", "effort_limit", "natural_frequency",
               "damping_ratio")  # fmt: skip
_TABLE_KEYS = ("control_dt", "physics_dt", "natural_frequency", "damping_ratio", "armature_per_torque")
_UNITS = {"kp": "N m/rad", "kd": "N m s/rad", "armature": "kg m^2", "rotor_inertia": "kg m^2", "effort_limit": "N m",
          "natural_frequency": "Hz", "control_dt": "s", "physics_dt": "s", "armature_per_torque": "s^2"}  # fmt: skip
_MAY_BE_ZERO = ("kd", "armature", "rotor_inertia", "armature_per_torque")


def _numbers(table: dict[str, Any], where: str, keys: tuple[str, ...]) -> dict[str, float]:
    return {
        key: _FILES.number(
            table[key], f"{where}.{key}", rule=">= 0" if key in _MAY_BE_ZERO else "> 0", unit=_UNITS.get(key, "")
        )
        for key in keys
        if key in table
    }


def _actuator_group(raw: Any, where: str, names: _UrdfNames) -> ActuatorGroup:
    table = _FILES.table(raw, where)
    _FILES.check_keys(table, where, ("match",), _GROUP_KEYS)
    patterns = [table["match"]] if isinstance(table["match"], str) else table["match"]
    if not (isinstance(patterns, list) and patterns and all(isinstance(p, str) and p for p in patterns)):
        raise RobotError(f"{where}.match must be a joint name pattern or a non-empty list of them, got {patterns!r}")
    movable = [j for j, kind in names.joints.items() if kind in _MOVABLE_TYPES]
    for pattern in patterns:
        # A pattern that matches nothing is a typo: the group would silently not apply.
        if not any(fnmatch.fnmatchcase(joint, pattern) for joint in movable):
            raise RobotError(f"{where}.match: {pattern!r} matches no movable joint of the URDF")
    values = _numbers(table, where, _GROUP_KEYS)
    rotor = "rotor_inertia" in values, "gear_ratio" in values
    if any(rotor) and not all(rotor):
        raise RobotError(f"{where}: rotor_inertia and gear_ratio go together (armature = rotor_inertia * gear_ratio^2)")
    if all(rotor):
        if "armature" in values:
            raise RobotError(f"{where}: give armature or rotor_inertia and gear_ratio, not both")
        values["armature"] = values.pop("rotor_inertia") * values.pop("gear_ratio") ** 2
    return ActuatorGroup(match=tuple(patterns), **values)


def _actuation(raw: Any, names: _UrdfNames) -> ActuationSpec:
    table = _FILES.table(raw, "actuation")
    _FILES.check_keys(table, "actuation", (), (*_TABLE_KEYS, "joints"))
    raw_groups = table.get("joints", [])
    if not isinstance(raw_groups, list):
        raise RobotError("actuation.joints must be an array of tables ([[actuation.joints]])")
    groups = tuple(_actuator_group(g, f"actuation.joints[{i}]", names) for i, g in enumerate(raw_groups))
    spec = ActuationSpec(groups=groups, **_numbers(table, "actuation", _TABLE_KEYS))
    ratio = spec.control_dt / spec.physics_dt
    if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6 * ratio:
        raise RobotError(
            f"actuation.physics_dt = {spec.physics_dt:g} s must divide actuation.control_dt = {spec.control_dt:g} s"
        )
    return spec


def parse_robot(data: dict[str, Any], source: str = "", base: Path | None = None) -> RobotDescription:
    """Build a :class:`RobotDescription` from a parsed TOML document (see the module docstring).

    Args:
        data: the TOML document.
        source: where it came from, for messages.
        base: folder that relative paths are resolved against (the TOML file's folder); ``None`` for built-ins.
    """
    _FILES.check_keys(
        data,
        "",
        ("name", "model", "feet", "walking", "posture"),
        ("description", "gains", "actuation", "stepping", "velocity"),
    )
    name = _FILES.string(data, "name", non_empty=True)
    if not _NAME_PATTERN.fullmatch(name):
        raise RobotError(f"name must be letters, digits, '.', '_' or '-', got {name!r}")
    description = _FILES.string(data, "description", non_empty=True) if "description" in data else ""
    if "\n" in description:
        raise RobotError("description must be a single line")

    model = _FILES.table(data["model"], "model")
    _FILES.check_keys(model, "model", ("urdf",), ("package_dirs",))
    urdf = _resolve_urdf(_FILES.string(model, "urdf", "model", non_empty=True), base)
    if "package_dirs" in model:
        raw_dirs = model["package_dirs"]
        if not isinstance(raw_dirs, list) or not all(isinstance(d, str) and d for d in raw_dirs):
            raise RobotError(f"model.package_dirs must be a list of folder names, got {raw_dirs!r}")
        package_dirs = tuple(_resolve_path(d, base, "model.package_dirs") for d in raw_dirs)
        for folder in package_dirs:
            if not folder.is_dir():
                raise RobotError(f"model.package_dirs: no such folder {folder}")
    else:
        package_dirs = _default_package_dirs()
    names = _read_urdf_names(urdf)

    feet = _FILES.table(data["feet"], "feet")
    _FILES.check_keys(feet, "feet", ("left_sole_frame", "right_sole_frame", "sole"), ("sole_offset",))
    frames = {key: _FILES.string(feet, key, "feet", non_empty=True) for key in ("left_sole_frame", "right_sole_frame")}
    for key, frame in frames.items():
        if frame not in names.frames:
            raise RobotError(f"feet.{key}: the URDF {urdf.name} has no link or joint named {frame!r}")
    if frames["left_sole_frame"] == frames["right_sole_frame"]:
        raise RobotError("feet.left_sole_frame and feet.right_sole_frame must be different frames")
    sole_offset = (0.0, 0.0, 0.0)
    if "sole_offset" in feet:
        raw = feet["sole_offset"]
        if not (isinstance(raw, list) and len(raw) == 3 and all(is_finite_number(v) for v in raw)):
            raise RobotError(f"feet.sole_offset must be three finite numbers [x, y, z] in m, got {raw!r}")
        sole_offset = (float(raw[0]), float(raw[1]), float(raw[2]))
    sole_table = _FILES.table(feet["sole"], "feet.sole")
    sides = ("front", "back", "inner", "outer")
    _FILES.check_keys(sole_table, "feet.sole", sides, ())
    sole_values = {key: _FILES.number(sole_table[key], f"feet.sole.{key}", rule=">= 0", unit="m") for key in sides}
    if sole_values["front"] + sole_values["back"] <= 0.0 or sole_values["inner"] + sole_values["outer"] <= 0.0:
        raise RobotError("feet.sole must have a positive length (front + back) and width (inner + outer)")
    sole = SoleRect(**sole_values)

    walking = _FILES.table(data["walking"], "walking")
    _FILES.check_keys(walking, "walking", ("cog_height", "moving_joints", "torso_frame"), ())
    cog_height = _FILES.number(walking["cog_height"], "walking.cog_height", rule="> 0", unit="m")
    raw_joints = walking["moving_joints"]
    if not isinstance(raw_joints, list) or not raw_joints or not all(isinstance(j, str) for j in raw_joints):
        raise RobotError(f"walking.moving_joints must be a non-empty list of joint names, got {raw_joints!r}")
    missing = [j for j in raw_joints if j not in names.joints]
    if missing:
        raise RobotError(f"walking.moving_joints: the URDF {urdf.name} has no joint named {', '.join(missing)}")
    duplicates = sorted({j for j in raw_joints if raw_joints.count(j) > 1})
    if duplicates:
        raise RobotError(f"walking.moving_joints lists {', '.join(duplicates)} more than once")
    for joint in raw_joints:
        if names.joints[joint] not in _LIMITED_TYPES:
            # The IK clamps every moving joint to its limits and treats its coordinate as one number.
            raise RobotError(
                f"walking.moving_joints: {joint} is a {names.joints[joint]} joint; "
                f"only {' and '.join(_LIMITED_TYPES)} joints (one coordinate, with limits) can move"
            )
    torso_frame = _FILES.string(walking, "torso_frame", "walking", non_empty=True)
    if torso_frame not in names.frames:
        raise RobotError(f"walking.torso_frame: the URDF {urdf.name} has no link or joint named {torso_frame!r}")

    posture = _joint_values(data["posture"], "posture", names, unit="rad")
    for joint, angle in posture.items():
        if joint in names.limits:
            lower, upper = names.limits[joint]
            if not lower <= angle <= upper:
                raise RobotError(f"posture.{joint} = {angle} is outside the URDF limits [{lower}, {upper}]")

    kp = kd = None
    if "gains" in data:
        gains = _FILES.table(data["gains"], "gains")
        _FILES.check_keys(gains, "gains", ("kp", "kd"), ())
        kp = _gain(gains["kp"], "gains.kp", names)
        kd = _gain(gains["kd"], "gains.kd", names)
    actuation = _actuation(data["actuation"], names) if "actuation" in data else ActuationSpec()
    stepping = _stepping(data["stepping"], sole) if "stepping" in data else None
    velocity = _velocity(data["velocity"], sole) if "velocity" in data else None

    return RobotDescription(
        name=name,
        description=description,
        urdf=urdf,
        package_dirs=package_dirs,
        left_sole_frame=frames["left_sole_frame"],
        right_sole_frame=frames["right_sole_frame"],
        sole_offset=sole_offset,
        sole=sole,
        cog_height=cog_height,
        moving_joints=tuple(raw_joints),
        torso_frame=torso_frame,
        posture=MappingProxyType(posture),
        kp=kp,
        kd=kd,
        actuation=actuation,
        stepping=stepping,
        velocity=velocity,
        source=source,
    )


def _stepping(raw: Any, sole: SoleRect) -> SteppingLimits:
    """The ``[stepping]`` table (:class:`~rtgait.core.stepping.SteppingLimits` checks the values)."""
    limits = _limits_table(raw, "stepping", STEPPING_KEYS, SteppingLimits.from_table)
    _soles_apart("stepping.min_width", limits.min_width, sole)
    return limits


def _velocity(raw: Any, sole: SoleRect) -> VelocityLimits:
    """The ``[velocity]`` table (:class:`~rtgait.core.config.VelocityLimits` checks the values the way
    :class:`~rtgait.core.config.PlannerConfig` does; ``min_step_width`` against the robot's stance is checked when
    it is applied, :func:`rtgait.robot.motion.robot_scenario`)."""
    limits = _limits_table(raw, "velocity", VELOCITY_KEYS, VelocityLimits.from_table)
    _soles_apart("velocity.min_step_width", limits.min_step_width, sole)
    return limits


def _limits_table(raw: Any, name: str, keys: tuple[str, ...], parse: Any) -> Any:
    """The table ``name`` of limits, its keys among ``keys``, parsed by ``parse`` (whose errors name the key)."""
    table = _FILES.table(raw, name)
    _FILES.check_keys(table, name, (), keys)
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


# ----- finding descriptions -------------------------------------------------------------------------------------


def builtin_robots() -> dict[str, str]:
    """Built-in robot names mapped to their one-line descriptions (without loading their URDFs)."""
    # Only the raw document is read: parse_robot would resolve and parse every URDF just for a listing.
    return {name: str(_FILES.load(name).data.get("description", "")) for name in _FILES.builtin_names()}


def load_robot(name_or_path: str | Path = DEFAULT_ROBOT) -> RobotDescription:
    """Load a built-in robot description by name (default ``"talos"``), or any description TOML file by path.

    A string that is a built-in name wins over a file of the same name in the current folder; anything that
    looks like a path (a ``.toml`` suffix, a folder separator, or an existing file) is read as a file.

    Raises:
        RobotError: unknown robot, unreadable file, invalid TOML or any invalid field (one line naming it).
    """
    document = _FILES.load(name_or_path)
    # Relative paths in a description (model.urdf, model.package_dirs) are relative to its own folder.
    return parse_robot(document.data, document.source, document.folder)
