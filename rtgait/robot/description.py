"""Robot descriptions: which URDF, which frames are the feet and the torso, how to stand and how to walk.

A robot is described by a small TOML file (every key in ``docs/robots.md``, "The description file"). The built-in
ones ship as package data in ``rtgait/robots/`` and are loaded by name (``load_robot("talos")``); any other file is
loaded by path. Its tables, in SI units (m, rad, s, kg m^2, N m/rad):

* ``name``, ``description``; ``[model]``: ``urdf`` (``"example-robot-data:<path>"`` or a file path, relative to the
  TOML file) and optional ``package_dirs`` for ``package://`` mesh URIs;
* ``[feet]``: ``left_sole_frame``, ``right_sole_frame`` (URDF links or joints whose origin is on the sole, under the
  ankle, x forward and z up when standing), optional ``sole_offset`` (left foot's frame; the right foot uses its
  mirror image, y negated), and ``[feet.sole]``: the sole rectangle ``front``, ``back``, ``inner`` (toward the other
  foot), ``outer``;
* ``[walking]``: ``cog_height`` (the planner's constant COG height), ``moving_joints`` (all others stay locked at
  the posture), ``torso_frame`` (kept upright, heading along the mean yaw of the feet), optional ``toe_release``
  (the share of a swing up a stair over which the sole levels after its toe-off: :mod:`rtgait.core.geometry.toe_off`)
  and ``descent_bend`` (m: down a stair, the swing foot's path bent toward the other foot at mid-swing, so the
  folded swing leg's thigh passes clear of the stance thigh: :func:`rtgait.core.geometry.swing.swing_pose`);
* ``[posture]``: the half-sitting start posture, joint name -> angle (joints not listed are at 0);
* optional, for the physics layer: ``[gains]`` (``kp``, ``kd``: a number or a table per joint) and ``[actuation]``
  (periods, the command's delay, natural frequency, damping ratio, motor types ``[actuation.motors.<name>]`` and
  ``[[actuation.joints]]`` groups matched by fnmatch patterns giving gains, the real robot's gains, armature, torque
  limits and the motor type, a later group winning: :mod:`rtgait.robot.actuation_table`); a joint's actuation is
  resolved key by key: the last matching group that sets it, else ``[gains]``, else a default derived from the URDF
  by :mod:`rtgait.sim.actuation`;
* optional: ``[stepping]`` (step adjustment's limits, :class:`~rtgait.core.laws.stepping.SteppingLimits`) and
  ``[velocity]`` (bounds of walks by velocity command, :class:`~rtgait.core.planner.config.VelocityLimits`);
* optional: ``[sensors]`` (the IMU, the feet's force/torque sensors, encoders, joint torques, their noise and
  latency: :mod:`rtgait.robot.sensor_table`).

Every problem raises :class:`RobotError` with one line naming the field. The URDF is read with the standard
library's XML parser (not Pinocchio) to check frame and joint names and its links' masses and inertias
(:mod:`rtgait.robot.physical_checks`), so a description can be validated without building the model. This
module holds :class:`RobotDescription`, the document-level parse (:func:`parse_robot`) and the loaders; the readers
and checks of the parts are in :mod:`rtgait.robot.description_checks`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.toe_off import RELEASE
from rtgait.core.laws.stepping import SteppingLimits
from rtgait.core.planner.config import VelocityLimits
from rtgait.interface.sensor_spec import SensorSpec
from rtgait.robot.actuation_table import (
    DEFAULT_NATURAL_FREQUENCY,
    ActuationSpec,
    ActuatorGroup,
    JointActuationSpec,
    MotorType,
)
from rtgait.robot.description_checks import (
    ERD_PREFIX,
    FILES,
    LIMITED_TYPES,
    RobotError,
    default_package_dirs,
    joint_values,
    parse_actuation,
    parse_gain,
    parse_stepping,
    parse_velocity,
    read_urdf,
    read_urdf_names,
    resolve_path,
    resolve_urdf,
)
from rtgait.robot.physical_checks import check_urdf_physics
from rtgait.robot.sensor_table import parse_sensors
from rtgait.scenario.tomlfile import SettingsPairs, is_finite_number

__all__ = [
    "DEFAULT_NATURAL_FREQUENCY",
    "ERD_PREFIX",
    "ActuationSpec",
    "ActuatorGroup",
    "JointActuationSpec",
    "MotorType",
    "RobotDescription",
    "RobotError",
    "builtin_robots",
    "load_robot",
    "parse_robot",
]

DEFAULT_ROBOT = "talos"

_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


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
        toe_release: share of a swing up a stair over which the sole levels after its toe-off
            (``walking.toe_release``, default :data:`~rtgait.core.geometry.toe_off.RELEASE`;
            :mod:`rtgait.core.geometry.toe_off`).
        descent_bend: down a stair, the sideways bend of the swing foot's path toward the other foot at mid-swing
            (m, ``walking.descent_bend``, default 0: straight; :func:`rtgait.core.geometry.swing.swing_pose`).
        moving_joints: joints the walking motion may move, in the order given.
        torso_frame: frame kept upright while walking.
        posture: half-sitting posture, joint name -> angle (rad; m for prismatic joints); other joints at 0.
        kp, kd: optional joint gains for the physics layer (``[gains]``), one number for all joints or joint name ->
            value.
        actuation: the ``[actuation]`` table (defaults when absent); :meth:`joint_actuation` resolves one joint.
        stepping: the ``[stepping]`` table, step adjustment's limits (keys missing from it take
            :class:`~rtgait.core.laws.stepping.SteppingLimits`'s defaults); ``None`` when the description has none (then
            each user picks its defaults: the pendulum loop the core's, the MuJoCo loop limits scaled by leg length).
        velocity: the ``[velocity]`` table, the bounds of walks by velocity command
            (:class:`~rtgait.core.planner.config.VelocityLimits`, applied to the planner's config of every walk of this
            robot by :func:`rtgait.robot.motion.robot_scenario`); ``None`` when the description has none (then the
            :class:`~rtgait.core.planner.config.PlannerConfig` defaults apply).
        control: the ``[control]`` table, the controller's settings for this robot, as read
            (:data:`~rtgait.scenario.tomlfile.SettingsPairs`; :mod:`rtgait.control.control_table` checks and applies
            them, a scenario's own over them).
        sensors: the ``[sensors]`` table (:class:`~rtgait.interface.sensor_spec.SensorSpec`; without it, perfect
            encoders and joint torques and nothing else).
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
    control: SettingsPairs = ()
    sensors: SensorSpec = field(default_factory=SensorSpec)
    toe_release: float = RELEASE
    descent_bend: float = 0.0
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
        values: dict[str, Any] = {"kp": None, "kd": None, "armature": None, "effort_limit": None, "robot_kp": None,
                                  "robot_kd": None, "motor": None}  # fmt: skip
        if gains is not None:
            values["kp"], values["kd"] = gains
        values.update(natural_frequency=spec.natural_frequency, damping_ratio=spec.damping_ratio)
        for group in (g for g in spec.groups if g.matches(joint)):
            values.update({key: getattr(group, key) for key in values if getattr(group, key) is not None})
        if values["motor"] is not None:
            values["motor"] = spec.motors[values["motor"]]
        return JointActuationSpec(armature_per_torque=spec.armature_per_torque, **values)


def parse_robot(data: dict[str, Any], source: str = "", base: Path | None = None) -> RobotDescription:
    """Build a :class:`RobotDescription` from a parsed TOML document (see the module docstring).

    Args:
        data: the TOML document.
        source: where it came from, for messages.
        base: folder that relative paths are resolved against (the TOML file's folder); ``None`` for built-ins.
    """
    FILES.check_keys(
        data,
        "",
        ("name", "model", "feet", "walking", "posture"),
        ("description", "gains", "actuation", "stepping", "velocity", "control", "sensors"),
    )
    name = FILES.string(data, "name", non_empty=True)
    if not _NAME_PATTERN.fullmatch(name):
        raise RobotError(f"name must be letters, digits, '.', '_' or '-', got {name!r}")
    description = FILES.string(data, "description", non_empty=True) if "description" in data else ""
    if "\n" in description:
        raise RobotError("description must be a single line")

    model = FILES.table(data["model"], "model")
    FILES.check_keys(model, "model", ("urdf",), ("package_dirs",))
    urdf = resolve_urdf(FILES.string(model, "urdf", "model", non_empty=True), base)
    if "package_dirs" in model:
        raw_dirs = model["package_dirs"]
        if not isinstance(raw_dirs, list) or not all(isinstance(d, str) and d for d in raw_dirs):
            raise RobotError(f"model.package_dirs must be a list of folder names, got {raw_dirs!r}")
        package_dirs = tuple(resolve_path(d, base, "model.package_dirs") for d in raw_dirs)
        for folder in package_dirs:
            if not folder.is_dir():
                raise RobotError(f"model.package_dirs: no such folder {folder}")
    else:
        package_dirs = default_package_dirs()
    root = read_urdf(urdf)
    names = read_urdf_names(root, urdf)
    check_urdf_physics(root, urdf)  # before any URDF parser builds a model of it

    feet = FILES.table(data["feet"], "feet")
    FILES.check_keys(feet, "feet", ("left_sole_frame", "right_sole_frame", "sole"), ("sole_offset",))
    frames = {key: FILES.string(feet, key, "feet", non_empty=True) for key in ("left_sole_frame", "right_sole_frame")}
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
    sole_table = FILES.table(feet["sole"], "feet.sole")
    sides = ("front", "back", "inner", "outer")
    FILES.check_keys(sole_table, "feet.sole", sides, ())
    sole_values = {key: FILES.number(sole_table[key], f"feet.sole.{key}", rule=">= 0", unit="m") for key in sides}
    if sole_values["front"] + sole_values["back"] <= 0.0 or sole_values["inner"] + sole_values["outer"] <= 0.0:
        raise RobotError("feet.sole must have a positive length (front + back) and width (inner + outer)")
    sole = SoleRect(**sole_values)

    walking = FILES.table(data["walking"], "walking")
    required = ("cog_height", "moving_joints", "torso_frame")
    FILES.check_keys(walking, "walking", required, ("toe_release", "descent_bend"))
    cog_height = FILES.number(walking["cog_height"], "walking.cog_height", rule="> 0", unit="m")
    toe_release = RELEASE
    if "toe_release" in walking:
        toe_release = FILES.number(walking["toe_release"], "walking.toe_release", rule="> 0", unit="")
        if toe_release > 1.0:
            raise RobotError(f"walking.toe_release must be a share of the swing in (0, 1], got {toe_release:g}")
    descent_bend = 0.0
    if "descent_bend" in walking:
        descent_bend = FILES.number(walking["descent_bend"], "walking.descent_bend", rule=">= 0", unit="m")
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
        if names.joints[joint] not in LIMITED_TYPES:
            # The IK clamps every moving joint to its limits and treats its coordinate as one number.
            raise RobotError(
                f"walking.moving_joints: {joint} is a {names.joints[joint]} joint; "
                f"only {' and '.join(LIMITED_TYPES)} joints (one coordinate, with limits) can move"
            )
    torso_frame = FILES.string(walking, "torso_frame", "walking", non_empty=True)
    if torso_frame not in names.frames:
        raise RobotError(f"walking.torso_frame: the URDF {urdf.name} has no link or joint named {torso_frame!r}")

    posture = joint_values(data["posture"], "posture", names, unit="rad")
    for joint, angle in posture.items():
        if joint in names.limits:
            lower, upper = names.limits[joint]
            if not lower <= angle <= upper:
                raise RobotError(f"posture.{joint} = {angle} is outside the URDF limits [{lower}, {upper}]")

    kp = kd = None
    if "gains" in data:
        gains = FILES.table(data["gains"], "gains")
        FILES.check_keys(gains, "gains", ("kp", "kd"), ())
        kp = parse_gain(gains["kp"], "gains.kp", names)
        kd = parse_gain(gains["kd"], "gains.kd", names)
    actuation = parse_actuation(data["actuation"], names) if "actuation" in data else ActuationSpec()
    stepping = parse_stepping(data["stepping"], sole) if "stepping" in data else None
    velocity = parse_velocity(data["velocity"], sole) if "velocity" in data else None
    control = FILES.settings(data["control"], "control") if "control" in data else ()
    sensors = parse_sensors(data["sensors"], names) if "sensors" in data else SensorSpec()

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
        toe_release=toe_release,
        descent_bend=descent_bend,
        moving_joints=tuple(raw_joints),
        torso_frame=torso_frame,
        posture=MappingProxyType(posture),
        kp=kp,
        kd=kd,
        actuation=actuation,
        stepping=stepping,
        velocity=velocity,
        control=control,
        sensors=sensors,
        source=source,
    )


# ----- finding descriptions -------------------------------------------------------------------------------------


def builtin_robots() -> dict[str, str]:
    """Built-in robot names mapped to their one-line descriptions (without loading their URDFs)."""
    # Only the raw document is read: parse_robot would resolve and parse every URDF just for a listing.
    return {name: str(FILES.load(name).data.get("description", "")) for name in FILES.builtin_names()}


def load_robot(name_or_path: str | Path = DEFAULT_ROBOT) -> RobotDescription:
    """Load a built-in robot description by name (default ``"talos"``), or any description TOML file by path.

    A string that is a built-in name wins over a file of the same name in the current folder; anything that
    looks like a path (a ``.toml`` suffix, a folder separator, or an existing file) is read as a file.

    Raises:
        RobotError: unknown robot, unreadable file, invalid TOML or any invalid field (one line naming it).
    """
    document = FILES.load(name_or_path)
    # Relative paths in a description (model.urdf, model.package_dirs) are relative to its own folder.
    return parse_robot(document.data, document.source, document.folder)
