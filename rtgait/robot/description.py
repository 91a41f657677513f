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

Every problem with a description raises :class:`RobotError` with one line naming the field. The URDF is read
with the standard library's XML parser (not Pinocchio) to check frame and joint names, so a description can be
validated without building the model.
"""

from __future__ import annotations

import math
import re
import sys
import xml.etree.ElementTree as ElementTree
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rtgait.core.footsteps import SoleRect
from rtgait.robot.data import RobotDataError, robots_dir, share_dir

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised only on Python 3.10
    import tomli as tomllib

__all__ = ["ERD_PREFIX", "RobotDescription", "RobotError", "builtin_robots", "load_robot", "parse_robot"]

ERD_PREFIX = "example-robot-data:"
"""Prefix of ``model.urdf`` values that name a file below example-robot-data's ``robots/`` folder."""

DEFAULT_ROBOT = "talos"

_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
# URDF joint types with one coordinate and position limits: the whole-body IK moves these only.
_LIMITED_TYPES = ("revolute", "prismatic")
_MOVABLE_TYPES = (*_LIMITED_TYPES, "continuous")


class RobotError(ValueError):
    """A robot description is unknown, unreadable or invalid. The message is one line naming the field."""


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
        kp, kd: optional joint gains for the physics layer, one number for all joints or joint name -> value.
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


def _table(data: Any, where: str) -> dict[str, Any]:
    if not isinstance(data, dict):
        raise RobotError(f"{where} must be a table, got {type(data).__name__} {data!r}")
    return data


def _check_keys(data: dict[str, Any], where: str, required: tuple[str, ...], optional: tuple[str, ...]) -> None:
    prefix = f"{where}." if where else ""
    allowed = required + optional
    for key in data:
        if key not in allowed:
            # A typo ("cog_heigth") silently ignored would walk a different robot from the one described.
            kind = "key" if where else "top-level key"
            raise RobotError(f"unknown {kind} {prefix}{key} (allowed here: {', '.join(allowed)})")
    for key in required:
        if key not in data:
            raise RobotError(f"missing required key {prefix}{key}")


def _is_number(value: Any) -> bool:
    # bool is an int subclass in Python: `cog_height = true` must not pass as 1.0.
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _number(value: Any, path: str, *, positive: bool = False, non_negative: bool = False, unit: str = "") -> float:
    ok = _is_number(value) and (not positive or value > 0) and (not non_negative or value >= 0)
    if not ok:
        rule = "a number > 0" if positive else "a number >= 0" if non_negative else "a finite number"
        raise RobotError(f"{path} must be {rule}{' ' + unit if unit else ''}, got {value!r}")
    return float(value)


def _string(data: dict[str, Any], key: str, where: str = "") -> str:
    value = data[key]
    path = f"{where}.{key}" if where else key
    if not isinstance(value, str) or not value:
        raise RobotError(f"{path} must be a non-empty string, got {value!r}")
    return value


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
    table = _table(raw, where)
    values = {}
    for joint, value in table.items():
        if joint not in names.joints or names.joints[joint] not in _MOVABLE_TYPES:
            raise RobotError(f"{where}.{joint}: the URDF has no movable joint named {joint!r}")
        values[joint] = _number(value, f"{where}.{joint}", unit=unit)
    return values


def _gain(raw: Any, where: str, names: _UrdfNames) -> float | Mapping[str, float]:
    if isinstance(raw, dict):
        values = _joint_values(raw, where, names, unit="")
        for joint, value in values.items():
            if value < 0.0:
                raise RobotError(f"{where}.{joint} must be a number >= 0, got {value!r}")
        return MappingProxyType(values)
    return _number(raw, where, non_negative=True)


def parse_robot(data: dict[str, Any], source: str = "", base: Path | None = None) -> RobotDescription:
    """Build a :class:`RobotDescription` from a parsed TOML document (see the module docstring).

    Args:
        data: the TOML document.
        source: where it came from, for messages.
        base: folder that relative paths are resolved against (the TOML file's folder); ``None`` for built-ins.
    """
    _check_keys(data, "", ("name", "model", "feet", "walking", "posture"), ("description", "gains"))
    name = _string(data, "name")
    if not _NAME_PATTERN.fullmatch(name):
        raise RobotError(f"name must be letters, digits, '.', '_' or '-', got {name!r}")
    description = _string(data, "description") if "description" in data else ""
    if "\n" in description:
        raise RobotError("description must be a single line")

    model = _table(data["model"], "model")
    _check_keys(model, "model", ("urdf",), ("package_dirs",))
    urdf = _resolve_urdf(_string(model, "urdf", "model"), base)
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

    feet = _table(data["feet"], "feet")
    _check_keys(feet, "feet", ("left_sole_frame", "right_sole_frame", "sole"), ("sole_offset",))
    frames = {key: _string(feet, key, "feet") for key in ("left_sole_frame", "right_sole_frame")}
    for key, frame in frames.items():
        if frame not in names.frames:
            raise RobotError(f"feet.{key}: the URDF {urdf.name} has no link or joint named {frame!r}")
    if frames["left_sole_frame"] == frames["right_sole_frame"]:
        raise RobotError("feet.left_sole_frame and feet.right_sole_frame must be different frames")
    sole_offset = (0.0, 0.0, 0.0)
    if "sole_offset" in feet:
        raw = feet["sole_offset"]
        if not (isinstance(raw, list) and len(raw) == 3 and all(_is_number(v) for v in raw)):
            raise RobotError(f"feet.sole_offset must be three finite numbers [x, y, z] in m, got {raw!r}")
        sole_offset = (float(raw[0]), float(raw[1]), float(raw[2]))
    sole_table = _table(feet["sole"], "feet.sole")
    sides = ("front", "back", "inner", "outer")
    _check_keys(sole_table, "feet.sole", sides, ())
    sole_values = {key: _number(sole_table[key], f"feet.sole.{key}", non_negative=True, unit="m") for key in sides}
    if sole_values["front"] + sole_values["back"] <= 0.0 or sole_values["inner"] + sole_values["outer"] <= 0.0:
        raise RobotError("feet.sole must have a positive length (front + back) and width (inner + outer)")
    sole = SoleRect(**sole_values)

    walking = _table(data["walking"], "walking")
    _check_keys(walking, "walking", ("cog_height", "moving_joints", "torso_frame"), ())
    cog_height = _number(walking["cog_height"], "walking.cog_height", positive=True, unit="m")
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
    torso_frame = _string(walking, "torso_frame", "walking")
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
        gains = _table(data["gains"], "gains")
        _check_keys(gains, "gains", ("kp", "kd"), ())
        kp = _gain(gains["kp"], "gains.kp", names)
        kd = _gain(gains["kd"], "gains.kd", names)

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
        source=source,
    )


# ----- finding descriptions -------------------------------------------------------------------------------------


def _builtin_dir() -> Any:
    return resources.files("rtgait").joinpath("robots")


def _builtin_names() -> list[str]:
    return sorted(entry.name[: -len(".toml")] for entry in _builtin_dir().iterdir() if entry.name.endswith(".toml"))


def _parse_text(text: str, source: str, base: Path | None) -> RobotDescription:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise RobotError(f"invalid TOML in {source}: {error}") from None
    return parse_robot(data, source, base)


def builtin_robots() -> dict[str, str]:
    """Built-in robot names mapped to their one-line descriptions (without loading their URDFs)."""
    result = {}
    for name in _builtin_names():
        text = _builtin_dir().joinpath(f"{name}.toml").read_text(encoding="utf-8")
        result[name] = str(tomllib.loads(text).get("description", ""))
    return result


def load_robot(name_or_path: str | Path = DEFAULT_ROBOT) -> RobotDescription:
    """Load a built-in robot description by name (default ``"talos"``), or any description TOML file by path.

    A string that is a built-in name wins over a file of the same name in the current folder; anything that
    looks like a path (a ``.toml`` suffix, a folder separator, or an existing file) is read as a file.

    Raises:
        RobotError: unknown robot, unreadable file, invalid TOML or any invalid field (one line naming it).
    """
    text_arg = str(name_or_path)
    if not isinstance(name_or_path, Path) and text_arg in _builtin_names():
        text = _builtin_dir().joinpath(f"{text_arg}.toml").read_text(encoding="utf-8")
        return _parse_text(text, "builtin", None)
    path = Path(name_or_path)
    looks_like_path = isinstance(name_or_path, Path) or path.suffix == ".toml" or "/" in text_arg or path.exists()
    if not looks_like_path:
        known = ", ".join(_builtin_names())
        raise RobotError(f"unknown robot {text_arg!r}: built-in robots are {known} (or give a .toml path)")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise RobotError(f"cannot read robot file {text_arg}: {reason}") from None
    return _parse_text(text, str(path), path.resolve().parent)
