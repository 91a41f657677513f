"""``sim.parquet``: the complete log of a walk in physics, one row per control tick (``docs/logs.md``).

The columns are :func:`log_columns`: name, unit and meaning of each, also stored in the file, as the metadata
``unit`` and ``description`` of every field. Names follow ``sim.csv`` (whose columns are all here, with the same
values): ``_x``/``_y``/``_z`` for world-frame components, ``left_``/``right_`` for the feet, ``<quantity>_<joint>`` for
the joints. The file's metadata key ``rtgait`` holds one JSON object (:func:`log_metadata`): the robot, controller,
periods, rtgait version, scenario, sole, the run's outcome, and ``events``, the table of what happened (landings,
re-anchoring, step adjustments, replans, pushes, damping, tip-over, fall), each with its time, tick, kind, side,
detail and position; the per-tick ``events`` column names the events of each tick (empty on most).

Reading needs pyarrow only (:func:`read_sim_log`); writing is done from a :class:`~rtgait.sim.result.SimResult`
(:func:`write_sim_log`), through :func:`rtgait.outputs.write_atomic` by :mod:`rtgait.io.sim_files`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait import __version__
from rtgait.core.geometry.support import SUPPORT_NAMES
from rtgait.core.planner.levels import CONTROLLER_LEVELS

if TYPE_CHECKING:
    from rtgait.core.geometry.footsteps import SoleRect
    from rtgait.sim.result import SimResult

__all__ = [
    "LOG_FILE",
    "LOG_FORMAT",
    "LogColumn",
    "SimLog",
    "log_columns",
    "log_metadata",
    "parquet_available",
    "read_sim_log",
    "sim_events",
    "write_sim_log",
]

LOG_FILE = "sim.parquet"
LOG_FORMAT = "rtgait-sim-log/1"
"""``format`` in the file's metadata: the layout of this module, version 1."""

_SIDES = ("left", "right")
_XYZ = ("x", "y", "z")


@dataclass(frozen=True)
class LogColumn:
    """One column of ``sim.parquet``: its ``name``, ``unit`` (``""`` for a count, flag or label) and meaning."""

    name: str
    unit: str
    description: str


def _vector(prefix: str, unit: str, what: str, axes: Sequence[str] = _XYZ, sep: str = "_") -> list[LogColumn]:
    return [LogColumn(f"{prefix}{sep}{axis}", unit, f"{what}, {axis}") for axis in axes]


_WRENCH_TIME = "controller's measurement, one physics step before t"
_MEASURED = "controller's measurement, one physics step before t; NaN in the transition"


def _foot_columns(side: str) -> list[LogColumn]:
    s = side
    return [
        LogColumn(f"{s}_contact", "", f"the {s} sole touches the floor (vertical force > contact threshold), at t"),
        LogColumn(f"{s}_normal_force", "N", f"vertical contact force on the {s} sole, at t"),
        LogColumn(f"{s}_corners", "", f"corners of the {s} sole box touching the floor (0-4), at t"),
        LogColumn(f"{s}_tilt", "rad", f"angle between the {s} sole's normal and the vertical, at t"),
        *_vector(f"{s}_sole", "m", f"measured {s} sole frame position, at t"),
        LogColumn(f"{s}_sole_yaw", "rad", f"measured {s} sole heading (R = Rz(yaw) Ry(pitch) Rx(roll)), at t"),
        LogColumn(f"{s}_sole_pitch", "rad", f"measured {s} sole pitch, at t"),
        LogColumn(f"{s}_sole_roll", "rad", f"measured {s} sole roll, at t"),
        *_vector(f"{s}_target", "m", f"the IK's {s} sole target (planned foot with the controller's heights)"),
        LogColumn(f"{s}_target_yaw", "rad", f"the IK's {s} sole target heading"),
        *_vector(f"{s}_force", "N", f"contact force of the ground on the {s} foot, world frame ({_WRENCH_TIME})"),
        *_vector(f"{s}_torque", "N m", f"its moment about the {s} sole frame's origin, world frame ({_WRENCH_TIME})"),
        *_vector(f"{s}_cop", "m", f"{s} centre of pressure on the ground; NaN unloaded ({_WRENCH_TIME})", "xy"),
        LogColumn(f"{s}_loaded", "", f"the {s} foot is loaded, after the landing hysteresis ({_WRENCH_TIME})"),
    ]


def log_columns(joint_names: Sequence[str]) -> list[LogColumn]:
    """Every column of ``sim.parquet`` for a robot whose actuated joints are ``joint_names``, in file order."""
    columns = [
        LogColumn("t", "s", "tick time on the walk's clock (0 when the planner starts; negative: start transition)"),
        LogColumn("tick", "", "tick index from the run's first tick"),
        LogColumn("phase", "", "the planner's phase (0 standing start, odd single supports); -1 in the transition"),
        LogColumn("support_planned", "", "the plan's support: double, left or right"),
        LogColumn("support_control", "", "the support the controller acts on (after early or late landings)"),
        LogColumn("controller", "", f"controller level: {', '.join(CONTROLLER_LEVELS)}"),
        LogColumn("events", "", "what happened at this tick, 'kind:side' joined by ';' (the events table)"),
        *_vector("zmp", "m", "measured ZMP (centre of pressure of the sole contacts), at t; NaN in the air", "xy"),
        *_vector("zmp_planned", "m", "the planner's ZMP (in the transition: the COM target's projection)", "xy"),
        *_vector("zmp_command", "m", "ZMP asked of the feet (the DCM law's; the plan's in open-loop)", "xy"),
        *_vector(
            "zmp_motion",
            "m",
            "multibody ZMP of the commanded motion (Pinocchio; not differentiated across a "
            "retargeting); NaN off the ground and over re-anchored swings",
            "xy",
        ),
        *_vector("cog", "m", "measured COM, at t"),
        *_vector("cog_planned", "m", "the IK's COM target: the plan's COM plus the controller's correction"),
        *_vector("cog_offset", "m", "the controller's COM correction (added to the plan's COM)", "xy"),
        *_vector("cog_vel", "m/s", "measured COM velocity, at t"),
        *_vector("cog_vel_planned", "m/s", "the plan's COM velocity; NaN in the transition", "xy"),
        *_vector("dcm", "m", "measured DCM c + c'/w from the measured COM and its velocity, at t", "xy"),
        *_vector("dcm_planned", "m", "the plan's DCM; NaN in the transition", "xy"),
        *_vector("dcm_control", "m", f"the DCM the controller acted on ({_WRENCH_TIME}); NaN in the transition", "xy"),
        *_vector("cog_control", "m", f"the COM the controller acted on ({_MEASURED})"),
        *_vector("cog_vel_control", "m/s", f"the COM velocity the controller acted on ({_MEASURED})"),
        *_vector("cog_true", "m", f"the simulator's COM at the instant of the {_MEASURED}"),
        *_vector("cog_vel_true", "m/s", f"the simulator's COM velocity at the instant of the {_MEASURED}"),
        *_vector("dcm_true", "m", f"the simulator's DCM c + c'/w at the instant of the {_MEASURED}", "xy"),
        *_vector("base", "m", "floating-base position, at t"),
        *_vector("base_q", "", "floating-base orientation, unit quaternion", ("x", "y", "z", "w"), sep=""),
        *_vector(
            "base_q_command",
            "",
            "the IK's floating-base orientation (leaned by the hip strategy), unit quaternion",
            ("x", "y", "z", "w"),
            sep="",
        ),
        *_vector("base_v", "m/s", "floating-base velocity at its origin, world frame, at t", sep=""),
        *_vector("base_w", "rad/s", "floating-base angular velocity, world frame, at t", sep=""),
        LogColumn("legs_touch", "", "the legs' collision boxes touch each other, at t"),
    ]
    for side in _SIDES:
        columns += _foot_columns(side)
    for prefix, unit, what in (
        ("q", "rad", "measured position of joint"),
        ("q_command", "rad", "commanded position (the servo's reference, ankle offsets included) of joint"),
        ("dq", "rad/s", "measured velocity of joint"),
        ("dq_command", "rad/s", "commanded velocity (the servo's velocity reference) of joint"),
        ("tau", "N m", "torque the servo applied (mean over the tick's physics substeps) to joint"),
    ):
        columns += [LogColumn(f"{prefix}_{name}", unit, f"{what} {name}") for name in joint_names]
    return columns


def parquet_available() -> bool:
    """Whether pyarrow is installed, to write or read ``sim.parquet``."""
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        return False
    return True


# ----- events ------------------------------------------------------------------------------------------------------
def _number(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


def sim_events(result: SimResult) -> list[dict[str, Any]]:
    """The events table of ``result``, in time order: the controller's events (``landing``, ``touchdown``,
    ``touchdown-refused``, ``step-adjustment``, ``replan``: :class:`~rtgait.control.settings.ControlEvent`),
    ``push`` and ``push-end`` (``detail``: the force in N), ``damping`` (the stack's safety layer tripped, ``detail``:
    the fault's kind and what was wrong, :mod:`rtgait.stack.safety`), ``tip-over`` and ``fall`` (``detail``: its
    cause). Each is ``{"t", "tick", "kind", "side", "detail", "x", "y"}``: the time of the tick it happened at (s,
    walk clock), that tick's index, and a position (m, world frame) or ``None``: where a foot landed or was
    re-anchored, the new landing of a step adjustment."""
    rows: list[tuple[float, str, str, str, float, float]] = [
        (e.t, e.kind, e.side, e.detail, e.x, e.y) for e in result.events
    ]
    for push in result.pushes:
        force = ", ".join(f"{f:g}" for f in push.force)
        rows.append((push.start, "push", "", f"({force}) N", math.nan, math.nan))
        rows.append((push.start + push.duration, "push-end", "", f"({force}) N", math.nan, math.nan))
    for fault in result.safety_events:
        rows.append((fault.t, "damping", "", f"{fault.kind}: {fault.detail}", math.nan, math.nan))
    if result.tip_time is not None:
        rows.append((result.tip_time, "tip-over", "", "a loaded foot tilted beyond the tip angle", math.nan, math.nan))
    if result.fell and result.fall_time is not None:
        rows.append((result.fall_time, "fall", "", result.fall_cause or "", math.nan, math.nan))
    rows.sort(key=lambda row: row[0])
    n = len(result.times)
    events = []
    for t, kind, side, detail, x, y in rows:
        tick = round((t - result.run_start) / result.control_dt)
        if not 0 <= tick < n:  # a push that ends after the run (a fall)
            continue
        events.append({"t": float(result.times[tick]), "tick": int(tick), "kind": kind, "side": side, "detail": detail,
                       "x": _number(x), "y": _number(y)})  # fmt: skip
    return events


def _event_column(events: list[dict[str, Any]], n: int) -> np.ndarray:
    column = np.full(n, "", dtype=object)
    for event in events:
        label = event["kind"] + (f":{event['side']}" if event["side"] else "")
        tick = event["tick"]
        column[tick] = f"{column[tick]};{label}" if column[tick] else label
    return column


# ----- the table ---------------------------------------------------------------------------------------------------
def _sole_dict(sole: SoleRect | None) -> dict[str, float] | None:
    if sole is None:
        return None
    return {"front": sole.front, "back": sole.back, "inner": sole.inner, "outer": sole.outer}


def log_metadata(
    result: SimResult, events: list[dict[str, Any]], extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The file-level metadata of ``result``'s log (module docstring); ``extra`` adds ``scenario``, ``connection``,
    ``title`` and, off the flat floor, ``terrain`` when it has them."""
    extra = extra or {}
    log = result.log
    return {
        "format": LOG_FORMAT,
        "rtgait_version": __version__,
        "robot": result.robot,
        "mass": result.mass,
        "gravity": result.gravity,
        "controller": result.controller,
        "state": result.state,
        "sensors": None if result.sensors is None else dataclasses.asdict(result.sensors),
        "control_dt": result.control_dt,
        "physics_dt": result.physics_dt,
        "contact_lag": None if log is None else log.contact_lag,
        "omega": None if log is None else log.omega,
        "sole": _sole_dict(None if log is None else log.sole),
        "scenario": extra.get("scenario"),
        "connection": extra.get("connection"),
        "title": extra.get("title"),
        **({"terrain": extra["terrain"]} if extra.get("terrain") else {}),  # a walk off the flat floor only
        "joint_names": list(result.joint_names),
        "run_start": result.run_start,
        "walk_end": result.walk_end,
        "steps_planned": result.steps_planned,
        "steps_completed": result.steps_completed,
        "fell": result.fell,
        "fall_time": _number(result.fall_time),
        "fall_cause": result.fall_cause,
        "tip_time": _number(result.tip_time),
        "pushes": [push.summary() for push in result.pushes],
        "zmp_tracking_error_rms": _number(result.zmp_tracking_error_rms),
        "events": events,
    }


def _columns(result: SimResult, events: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Every column's values (:func:`log_columns` order)."""
    log = result.log
    if log is None:
        raise ValueError("the result has no tick log (it was not made by rtgait.sim.run_loop.run_sim_loop)")
    n = len(result.times)
    linear, angular = log.base_velocity(result.base_position, result.cog)
    dcm = result.cog[:, 0:2] + log.cog_velocity[:, 0:2] / log.omega
    values: dict[str, np.ndarray] = {
        "t": result.times,
        "tick": np.arange(n, dtype=np.int64),
        "phase": log.phase,
        "support_planned": np.array(SUPPORT_NAMES, dtype=object)[result.support],
        "support_control": np.array(SUPPORT_NAMES, dtype=object)[log.support_control],
        "controller": np.array(CONTROLLER_LEVELS, dtype=object)[log.level],
        "events": _event_column(events, n),
    }

    def put(prefix: str, array: np.ndarray, axes: Sequence[str] = _XYZ, sep: str = "_") -> None:
        for i, axis in enumerate(axes):
            values[f"{prefix}{sep}{axis}"] = array[:, i]

    put("zmp", result.zmp, "xy")
    put("zmp_planned", result.zmp_planned, "xy")
    put("zmp_command", result.zmp_command, "xy")
    put("zmp_motion", result.zmp_commanded_motion, "xy")
    put("cog", result.cog)
    put("cog_planned", result.cog_planned)
    put("cog_offset", log.com_offset, "xy")
    put("cog_vel", log.cog_velocity)
    put("cog_vel_planned", log.cog_velocity_planned, "xy")
    put("dcm", dcm, "xy")
    put("dcm_planned", result.dcm_planned, "xy")
    put("dcm_control", result.dcm, "xy")
    put("cog_control", log.estimate.com)
    put("cog_vel_control", log.estimate.com_velocity)
    put("cog_true", log.truth.com)
    put("cog_vel_true", log.truth.com_velocity)
    put("dcm_true", log.truth.dcm, "xy")
    put("base", result.base_position)
    put("base_q", result.base_quaternion, ("x", "y", "z", "w"), sep="")
    put("base_q_command", result.commanded_q[:, 3:7], ("x", "y", "z", "w"), sep="")  # Pinocchio's order: x, y, z, w
    put("base_v", linear, sep="")
    put("base_w", angular, sep="")
    values["legs_touch"] = result.legs_touch
    for i, side in enumerate(_SIDES):
        values[f"{side}_contact"] = result.contact[:, i]
        values[f"{side}_normal_force"] = result.normal_force[:, i]
        values[f"{side}_corners"] = result.corners[:, i]
        values[f"{side}_tilt"] = result.sole_tilt[:, i]
        put(f"{side}_sole", log.sole_pose[:, i, 0:3])
        values[f"{side}_sole_yaw"] = log.sole_pose[:, i, 3]
        values[f"{side}_sole_pitch"] = log.sole_pose[:, i, 4]
        values[f"{side}_sole_roll"] = log.sole_pose[:, i, 5]
        put(f"{side}_target", log.foot_target[:, i, 0:3])
        values[f"{side}_target_yaw"] = log.foot_target[:, i, 3]
        put(f"{side}_force", log.force[:, i])
        put(f"{side}_torque", log.torque[:, i])
        put(f"{side}_cop", log.cop[:, i], "xy")
        values[f"{side}_loaded"] = log.loaded[:, i]
    for prefix, array in (
        ("q", log.joint_position),
        ("q_command", result.commanded_q[:, 7:]),
        ("dq", log.joint_velocity),
        ("dq_command", log.joint_velocity_command),
        ("tau", result.torque),
    ):
        for j, name in enumerate(result.joint_names):
            values[f"{prefix}_{name}"] = array[:, j]
    return values


def write_sim_log(result: SimResult, path: str | Path, extra: dict[str, Any] | None = None) -> None:
    """Write ``result``'s log to ``path``: Parquet, zstd-compressed, floats in full float64 precision (module
    docstring). It writes ``path`` directly: call it through :func:`rtgait.outputs.write_atomic`.

    Raises:
        ImportError: pyarrow is missing.
        ValueError: the result has no tick log.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    events = sim_events(result)
    values = _columns(result, events)
    columns = log_columns(result.joint_names)
    assert [c.name for c in columns] == list(values), "log_columns and _columns disagree"
    fields, arrays = [], []
    for column in columns:
        data = values[column.name]
        if data.dtype == object:  # labels
            array = pa.array(data.tolist(), type=pa.string())
            if column.name != "events":  # a few distinct labels: each stored once
                array = array.dictionary_encode()
        else:
            array = pa.array(np.ascontiguousarray(data))
        metadata = {"unit": column.unit, "description": column.description}
        fields.append(pa.field(column.name, array.type, metadata=metadata))
        arrays.append(array)
    meta = log_metadata(result, events, extra)
    schema = pa.schema(fields, metadata={"rtgait": json.dumps(meta, allow_nan=False)})
    table = pa.Table.from_arrays(arrays, schema=schema)
    # Byte-stream split lays each float's bytes out by significance, which zstd compresses better than plain float64
    # (dictionary encoding would only waste time on them); sizes in docs/design/figures_and_replay.md.
    floats = [f.name for f in fields if pa.types.is_floating(f.type)]
    labels = [f.name for f in fields if pa.types.is_dictionary(f.type)]
    pq.write_table(table, str(path), compression="zstd", use_dictionary=labels, use_byte_stream_split=floats)


# ----- reading -----------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SimLog:
    """A ``sim.parquet`` read back.

    Attributes:
        columns: every column by name, as numpy arrays (labels as object arrays of str).
        units: each column's unit.
        metadata: the file's ``rtgait`` metadata (:func:`log_metadata`), its ``events`` included.
    """

    columns: dict[str, np.ndarray]
    units: dict[str, str]
    metadata: dict[str, Any]

    @property
    def events(self) -> list[dict[str, Any]]:
        """The events table (:func:`sim_events`)."""
        return list(self.metadata.get("events", []))


def read_sim_log(path: str | Path, columns: Sequence[str] | None = None) -> SimLog:
    """Read a ``sim.parquet`` (all columns, or only ``columns``).

    Raises:
        ImportError: pyarrow is missing.
        ValueError: the file cannot be read, or was not written by :func:`write_sim_log`.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(str(path), columns=list(columns) if columns is not None else None)
        meta = json.loads((table.schema.metadata or {}).get(b"rtgait", b"{}"))
    except (OSError, ValueError, pa.ArrowException) as error:
        raise ValueError(f"cannot read {path}: {str(error).splitlines()[0]}") from None
    if not isinstance(meta, dict) or meta.get("format") != LOG_FORMAT:
        raise ValueError(f"{path} is not an rtgait simulation log (its metadata has no format {LOG_FORMAT!r})")
    values, units = {}, {}
    for field, column in zip(table.schema, table.columns, strict=True):
        if pa.types.is_dictionary(field.type) or pa.types.is_string(field.type):
            values[field.name] = np.array(column.to_pylist(), dtype=object)
        else:
            values[field.name] = column.to_numpy()
        units[field.name] = (field.metadata or {}).get(b"unit", b"").decode()
    return SimLog(values, units, meta)
