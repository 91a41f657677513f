"""The figure of a walk in physics: ``zmp_sim.png`` (or ``.pdf``, ``.svg``), planned and measured ZMP against time.

In the style of every rtgait figure (:mod:`rtgait.viz.style`): time on the walk's clock (t = 0 when the planner
starts, as in the plan figures; the start transition from half-sitting at negative times, shaded), units in square
brackets, the planned double supports shaded, pushes and the tip-over and fall marked. Three panels: x and y against
time with the **edges of the stance soles** (the extent along that axis of the sole the plan stands on, both in
double support, from its measured pose and the sole rectangle: where the measured ZMP must be), and the **ZMP
error** (measured minus planned, mm) in the planned single supports, where the title's RMS is taken. A walk off the
flat floor has a fourth panel, a side view (x-z) of the terrain and the soles' heights over it
(:mod:`rtgait.viz.terrain_profile`).

The figure is drawn from a small record, :class:`ZmpSimRun`, made from the run in memory
(:meth:`ZmpSimRun.from_result`) or read back from a finished run's files (:func:`read_zmp_sim_run`: ``sim.parquet``,
or ``sim.csv`` and ``summary.json`` without it), so ``rtgait plot DIR`` remakes the figure the run wrote. No MuJoCo is
needed to read or draw.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.terrain import Flat, TerrainKind
from rtgait.sim.log_file import LOG_FILE, parquet_available, read_sim_log
from rtgait.viz.run_files import (
    SIM_CSV,
    RunFilesError,
    read_floats,
    read_summary,
    read_table,
    read_terrain,
    require_keys,
)
from rtgait.viz.walk_title import velocity_commands, walk_title

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from rtgait.sim.result import SimResult

__all__ = ["ZMP_SIM_FIGURE", "ZmpSimRun", "draw_zmp_sim", "plot_zmp_sim", "read_zmp_sim_run", "sole_extent"]

ZMP_SIM_FIGURE = "zmp_sim"
"""File stem of the figure."""

_TRANSITION_COLOR = "#e8eef7"  # a pale blue: the start transition, unlike the grey double supports
_COMMAND_COLOR = "tab:green"
_SOLE_COLOR = "tab:olive"
_DAMPING_COLOR = "tab:brown"
_ERROR_MIN_SPAN = 0.02  # m: the error panel spans at least 20 mm, so a good walk's millimetres are not blown up


@dataclass(frozen=True, eq=False)
class ZmpSimRun:
    """What ``zmp_sim`` draws (SI units, times on the walk's clock; ``k`` ticks).

    Attributes:
        times: tick times (s), ``(k,)``.
        zmp, zmp_planned, zmp_command: measured (NaN in the air), planned and commanded ZMP (m), ``(k, 2)``.
        cog: measured COM (m), ``(k, 2)`` or more columns.
        double: the ticks shaded as double support, ``(k,)``.
        double_label: their legend entry (planned, or measured when the plan's support is not in the files).
        single: the ticks of the walk in planned single support (the error panel's), ``(k,)``.
        stance: which soles the plan stands on (left, right), ``(k, 2)``.
        sole_pose: the measured soles' ``(x, y, yaw)`` (m, rad), ``(k, 2, 3)``, or ``None`` (no sole edges drawn).
        sole: the sole rectangle (m), or ``None``.
        pushes: ``(start, duration, impulse)`` of each push (s, s, N s: the impulse's magnitude).
        tip_time, fall_time: when a loaded foot tipped over and when the robot fell (s), or ``None``.
        fall_cause: why it fell, or ``None``.
        steps_completed, steps_planned: touch-downs completed and steps of the walk.
        rms: RMS distance of the measured ZMP from the plan in single support (m), NaN without one.
        robot, controller, title: the robot's name, the controller level, the title's first line (what was walked).
        damping_time: when the stack's safety layer tripped and the joints began to damp (s), or ``None``.
        terrain: the terrain walked on, or ``None`` (the flat floor).
        sole_xz: the measured soles' ``(x, z)`` (m), ``(k, 2, 2)`` (left, right), for the terrain's side view, or
            ``None``.
    """

    times: np.ndarray
    zmp: np.ndarray
    zmp_planned: np.ndarray
    zmp_command: np.ndarray
    cog: np.ndarray
    double: np.ndarray
    double_label: str
    single: np.ndarray
    stance: np.ndarray
    sole_pose: np.ndarray | None
    sole: SoleRect | None
    pushes: tuple[tuple[float, float, float], ...]
    tip_time: float | None
    fall_time: float | None
    fall_cause: str | None
    steps_completed: int
    steps_planned: int
    rms: float
    robot: str
    controller: str
    title: str = ""
    damping_time: float | None = None
    terrain: TerrainKind | None = None
    sole_xz: np.ndarray | None = None

    @property
    def off_flat(self) -> bool:
        """Whether the figure has the terrain's side view: a terrain other than flat and the soles' heights."""
        return self.terrain is not None and not isinstance(self.terrain, Flat) and self.sole_xz is not None

    @classmethod
    def from_result(cls, result: SimResult, title: str = "", terrain: TerrainKind | None = None) -> ZmpSimRun:
        """The record of a run in memory on ``terrain`` (``None``: the flat floor); the soles' size and heights from
        its tick log (``None`` without one)."""
        return cls(
            times=result.times,
            zmp=result.zmp,
            zmp_planned=result.zmp_planned,
            zmp_command=result.zmp_command,
            cog=result.cog,
            double=(result.support == 0) & (result.times >= 0.0),
            double_label="double support (planned)",
            single=(result.support != 0) & (result.times >= 0.0),
            stance=_stance(result.support),
            sole_pose=result.sole_pose,
            sole=None if result.log is None else result.log.sole,
            pushes=tuple((p.start, p.duration, p.impulse_norm) for p in result.pushes),
            tip_time=result.tip_time,
            fall_time=result.fall_time if result.fell else None,
            fall_cause=result.fall_cause,
            steps_completed=result.steps_completed,
            steps_planned=result.steps_planned,
            rms=result.zmp_tracking_error_rms,
            robot=result.robot,
            controller=result.controller,
            title=title,
            damping_time=result.safety_events[0].t if result.safety_events else None,
            terrain=terrain,
            sole_xz=None if result.log is None else result.log.sole_pose[:, :, [0, 2]],
        )


def _stance(support: np.ndarray) -> np.ndarray:
    """Which soles (left, right) a support code (:data:`~rtgait.core.geometry.support.SUPPORT_CODES`) stands on,
    ``(k, 2)``."""
    support = np.asarray(support)
    return np.column_stack([support != 2, support != 1])


def sole_extent(sole_pose: np.ndarray, stance: np.ndarray, sole: SoleRect) -> np.ndarray:
    """Extent of the stance soles along x and y at each tick (m), ``(k, 2, 2)``: ``[:, axis] = (low, high)``.

    The corners of each sole, ``R(yaw) (local corner) + (x, y)`` with the local corners of
    :meth:`rtgait.core.geometry.footsteps.SoleRect.corners` (``inner`` toward the other foot), taken over the feet with
    ``stance``; NaN where there is none.
    """
    f, b, i, o = sole.front, sole.back, sole.inner, sole.outer
    local = np.array(
        [[[f, -i], [f, o], [-b, o], [-b, -i]], [[f, -o], [f, i], [-b, i], [-b, -o]]]  # left, right
    )  # (2 feet, 4 corners, 2)
    yaw = sole_pose[:, :, 2, None]  # (k, 2, 1)
    c, s = np.cos(yaw), np.sin(yaw)
    x = sole_pose[:, :, 0, None] + c * local[None, :, :, 0] - s * local[None, :, :, 1]
    y = sole_pose[:, :, 1, None] + s * local[None, :, :, 0] + c * local[None, :, :, 1]
    corners = np.stack([x, y], axis=1)  # (k, axis, foot, corner)
    on = np.asarray(stance, dtype=bool)[:, None, :, None]
    low = np.where(on, corners, np.inf).min(axis=(2, 3))
    high = np.where(on, corners, -np.inf).max(axis=(2, 3))
    extent = np.stack([low, high], axis=-1)
    extent[~np.asarray(stance, dtype=bool).any(axis=1)] = math.nan
    return extent


def draw_zmp_sim(run: ZmpSimRun) -> Figure:
    """The figure of ``run`` (module docstring)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from rtgait.viz.style import (
        COG_COLOR,
        DOUBLE_COLOR,
        PUSH_COLOR,
        REF_COLOR,
        TIME_LABEL,
        ZMP_COLOR,
        clean_ticks,
        new_figure,
        runs,
        span_limits,
    )
    from rtgait.viz.terrain_profile import draw_terrain_profile

    if run.off_flat:
        figure = new_figure(10.0, 10.5)
        grid = figure.add_gridspec(4, 1, height_ratios=[3, 3, 2, 3.5])
        first = figure.add_subplot(grid[0])
        axes = [first, figure.add_subplot(grid[1], sharex=first), figure.add_subplot(grid[2], sharex=first)]
        for ax in axes[:2]:
            ax.tick_params(labelbottom=False)
        draw_terrain_profile(figure.add_subplot(grid[3]), run.terrain, run.sole_xz)  # type: ignore[arg-type]
    else:
        figure = new_figure(10.0, 7.5)
        axes = figure.subplots(3, 1, sharex=True, height_ratios=[3, 3, 2])
    t = run.times
    closed = run.controller != "open-loop"
    extent = None
    if run.sole_pose is not None and run.sole is not None:
        extent = sole_extent(run.sole_pose, run.stance, run.sole)
    error = np.where(run.single[:, None], run.zmp - run.zmp_planned, math.nan)
    for index, ax in enumerate(axes):
        if t[0] < 0.0:
            ax.axvspan(t[0], 0.0, color=_TRANSITION_COLOR, lw=0, zorder=0)
        for start, end in runs(run.double, t):  # the measured ZMP moves between the feet there
            ax.axvspan(start, end, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0)
        for start, duration, _ in run.pushes:
            ax.axvspan(start, start + duration, color=PUSH_COLOR, alpha=0.35, lw=0, zorder=1)
        if run.tip_time is not None:
            ax.axvline(run.tip_time, color="tab:purple", lw=1.2, ls="--")
        if run.fall_time is not None:
            ax.axvline(run.fall_time, color="tab:red", lw=1.6)
        if run.damping_time is not None:
            ax.axvline(run.damping_time, color=_DAMPING_COLOR, lw=1.4, ls=":")
        ax.grid(True, lw=0.3)
        ax.set_xlim(float(t[0]), float(t[-1]))
        if index == 2:
            continue
        axis = index
        if extent is not None:
            low, high = extent[:, axis, 0], extent[:, axis, 1]
            ax.fill_between(t, low, high, color=_SOLE_COLOR, alpha=0.12, lw=0, zorder=1)
            ax.plot(t, low, color=_SOLE_COLOR, lw=0.6, zorder=2, label="_sole low")
            ax.plot(t, high, color=_SOLE_COLOR, lw=0.6, zorder=2, label="_sole high")
        ax.plot(t, run.zmp_planned[:, axis], color=REF_COLOR, lw=1.2, label="planned ZMP")
        if closed:
            ax.plot(t, run.zmp_command[:, axis], color=_COMMAND_COLOR, lw=0.8, label="commanded ZMP (feedback)")
        ax.plot(t, run.zmp[:, axis], color=ZMP_COLOR, lw=0.8, label="measured ZMP (contact CoP)")
        ax.plot(t, run.cog[:, axis], color=COG_COLOR, lw=0.8, ls="--", label="measured COG")
        ax.set_ylabel(f"{'xy'[axis]} (world) [m]")
        clean_ticks(ax)

    ax = axes[2]
    ax.axhline(0.0, color=REF_COLOR, lw=0.6)
    ax.plot(t, error[:, 0], color=ZMP_COLOR, lw=0.8, label="x")
    ax.plot(t, error[:, 1], color="tab:orange", lw=0.8, label="y")
    ax.set_ylim(*span_limits(error, _ERROR_MIN_SPAN, include=0.0))
    ax.set_ylabel("ZMP error [mm]\n(measured " + "\N{MINUS SIGN}" + " planned,\nsingle support)")
    ax.legend(loc="upper right", fontsize=8, ncols=2)
    clean_ticks(ax, y_scale=1000.0)
    ax.set_xlabel(TIME_LABEL)

    handles, labels = axes[0].get_legend_handles_labels()
    if extent is not None:
        handles.append((Patch(color=_SOLE_COLOR, alpha=0.12, lw=0), Line2D([], [], color=_SOLE_COLOR, lw=0.6)))
        labels.append("stance sole edges (measured pose)")
    handles += [Patch(color=DOUBLE_COLOR, alpha=0.6, lw=0), Patch(color=_TRANSITION_COLOR, lw=0)]
    labels += [run.double_label, "start transition (from half-sitting)"]
    if run.pushes:
        handles.append(Patch(color=PUSH_COLOR, alpha=0.35, lw=0))
        labels.append("push " + ", ".join(f"{impulse:.0f} N s at {start:.2f} s" for start, _, impulse in run.pushes))
    if run.tip_time is not None:
        handles.append(Line2D([], [], color="tab:purple", lw=1.2, ls="--"))
        labels.append(f"a foot tipped over ({run.tip_time:.2f} s)")
    if run.fall_time is not None:
        handles.append(Line2D([], [], color="tab:red", lw=1.6))
        labels.append(f"fell ({run.fall_time:.2f} s)")
    if run.damping_time is not None:
        handles.append(Line2D([], [], color=_DAMPING_COLOR, lw=1.4, ls=":"))
        labels.append(f"damping: the safety layer tripped ({run.damping_time:.2f} s)")
    figure.legend(handles, labels, loc="outside lower center", fontsize=8, ncols=4, frameon=False)

    if run.fall_time is not None:
        outcome = f"fell at {run.fall_time:.2f} s ({run.fall_cause})"
    else:
        outcome = f"walked {run.steps_completed}/{run.steps_planned} steps"
    if run.tip_time is not None:
        outcome += f", a foot tipped over at {run.tip_time:.2f} s"
    if run.damping_time is not None:
        outcome += f", damping from {run.damping_time:.2f} s"
    if np.isfinite(run.rms):
        outcome += f"; ZMP {run.rms * 1e3:.0f} mm RMS from the plan in single support"
    robot = f"{run.robot} in MuJoCo, {run.controller}"
    title = f"{run.title}\n{robot}: {outcome}" if run.title else f"{robot}\n{outcome}"
    axes[0].set_title(title, fontsize=10)
    return figure


def plot_zmp_sim(run: ZmpSimRun, path: str | Path, fmt: str | None = None) -> Path:
    """Draw ``run`` (:func:`draw_zmp_sim`) into ``path`` in the format ``fmt`` (``png``, ``pdf``, ``svg``; default
    the one its suffix names); returns the path."""
    import matplotlib

    from rtgait.viz.style import DPI, save

    figure = draw_zmp_sim(run)
    path = Path(path)
    if fmt is None or path.suffix.lstrip(".").lower() == fmt:
        return save(figure, path)
    # A temporary name of another suffix (rtgait.outputs.write_atomic): save's choices, with the format given.
    metadata = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
    with matplotlib.rc_context({"svg.hashsalt": "rtgait"}):
        figure.savefig(path, dpi=DPI, format=fmt, metadata=metadata)
    return path


# ----- reading a finished run ---------------------------------------------------------------------------------------
_PARQUET_COLUMNS = (
    "t", "zmp_x", "zmp_y", "zmp_planned_x", "zmp_planned_y", "zmp_command_x", "zmp_command_y", "cog_x", "cog_y",
    "support_planned", "left_sole_x", "left_sole_y", "left_sole_yaw",
    "right_sole_x", "right_sole_y", "right_sole_yaw", "left_sole_z", "right_sole_z",
)  # fmt: skip
_CSV_COLUMNS = (
    "t", "zmp_x", "zmp_y", "zmp_planned_x", "zmp_planned_y", "zmp_command_x", "zmp_command_y", "cog_x", "cog_y",
    "left_contact", "right_contact",
)  # fmt: skip


def _title(facts: dict[str, Any]) -> str:
    if facts.get("title"):
        return str(facts["title"])
    scenario, connection = facts.get("scenario"), facts.get("connection")
    return walk_title(scenario, connection, velocity_commands(facts)) if scenario and connection else (scenario or "")


def _outcome(facts: dict[str, Any]) -> dict[str, Any]:
    """The outcome entries of a summary or a log's metadata, as :class:`ZmpSimRun` fields."""
    rms = facts.get("zmp_tracking_error_rms")
    # summary.json's safety record, or the log's damping event
    first_fault = (facts.get("safety") or {}).get("first_event") or next(
        (e for e in facts.get("events", []) if e.get("kind") == "damping"), None
    )
    return {
        "pushes": tuple(
            (float(p["start"]), float(p["duration"]), float(p["impulse_norm"])) for p in facts.get("pushes", [])
        ),
        "tip_time": facts.get("tip_time"),
        "fall_time": facts.get("fall_time") if facts.get("fall") or facts.get("fell") else None,
        "fall_cause": facts.get("fall_cause"),
        "steps_completed": int(facts["steps_completed"]),
        "steps_planned": int(facts["steps_planned"]),
        "rms": math.nan if rms is None else float(rms),
        "robot": str(facts["robot"]),
        "controller": str(facts["controller"]),
        "title": _title(facts),
        "damping_time": None if first_fault is None else float(first_fault["t"]),
        "terrain": read_terrain(facts.get("terrain")),
    }


def _per_side(columns: dict[str, np.ndarray], axes: tuple[str, ...]) -> np.ndarray:
    """The soles' ``<side>_sole_<axis>`` columns, ``(k, 2, len(axes))`` (left, right)."""
    return np.stack([np.column_stack([columns[f"{s}_sole_{a}"] for a in axes]) for s in ("left", "right")], axis=1)


def _from_parquet(path: Path) -> ZmpSimRun:
    try:
        log = read_sim_log(path, _PARQUET_COLUMNS)
    except ValueError as error:  # includes pyarrow's "no such column"
        raise RunFilesError(str(error)) from None
    c, meta = log.columns, log.metadata
    sole = meta.get("sole")
    pose = _per_side(c, ("x", "y", "yaw"))
    times = c["t"]
    return ZmpSimRun(
        times=times,
        zmp=np.column_stack([c["zmp_x"], c["zmp_y"]]),
        zmp_planned=np.column_stack([c["zmp_planned_x"], c["zmp_planned_y"]]),
        zmp_command=np.column_stack([c["zmp_command_x"], c["zmp_command_y"]]),
        cog=np.column_stack([c["cog_x"], c["cog_y"]]),
        double=(c["support_planned"] == "double") & (times >= 0.0),
        double_label="double support (planned)",
        single=(c["support_planned"] != "double") & (times >= 0.0),
        stance=np.column_stack([c["support_planned"] != "right", c["support_planned"] != "left"]),
        sole_pose=pose,
        sole=None if sole is None else SoleRect(**sole),
        sole_xz=_per_side(c, ("x", "z")),
        **_outcome(meta),
    )


def _from_csv(folder: Path, summary: dict[str, Any]) -> ZmpSimRun:
    require_keys(summary, ("robot", "controller", "steps_completed", "steps_planned"), folder, "a MuJoCo simulation")
    path = folder / SIM_CSV
    if not path.is_file():
        raise RunFilesError(f"{path} is missing: {folder} does not hold a finished rtgait simulate run")
    table = read_table(path, _CSV_COLUMNS)
    column = dict(zip(_CSV_COLUMNS, read_floats(table, _CSV_COLUMNS, path).T, strict=True))

    def pair(name: str) -> np.ndarray:
        return np.column_stack((column[f"{name}_x"], column[f"{name}_y"]))

    times = column["t"]
    contact = np.column_stack((column["left_contact"], column["right_contact"])) > 0.5
    return ZmpSimRun(
        times=times,
        zmp=pair("zmp"),
        zmp_planned=pair("zmp_planned"),
        zmp_command=pair("zmp_command"),
        cog=pair("cog"),
        double=contact.all(axis=1) & (times >= 0.0),  # sim.csv has no planned support: the measured one
        double_label="both feet on the floor (measured)",
        single=(contact.sum(axis=1) == 1) & (times >= 0.0),
        stance=contact,
        sole_pose=None,
        sole=None,
        **_outcome(summary),
    )


def read_zmp_sim_run(folder: str | Path) -> ZmpSimRun:
    """The figure's record of the finished ``rtgait simulate`` (MuJoCo) run in ``folder``: from ``sim.parquet``, or,
    without it (or without pyarrow), from ``sim.csv`` and ``summary.json`` with a warning: that figure has no sole
    edges and shades the measured double supports (``sim.csv`` has neither the soles' poses nor the plan's support).

    Raises:
        RunFilesError: the files are missing or are not those of a MuJoCo simulation (one line).
    """
    folder = Path(folder)
    summary = read_summary(folder)
    parquet = folder / LOG_FILE
    if parquet.is_file() and parquet_available():
        return _from_parquet(parquet)
    run = _from_csv(folder, summary)  # read and checked first: a folder that is no run is one error line
    why = "pyarrow is not installed" if parquet.is_file() else f"the run has no {LOG_FILE}"
    warnings.warn(
        f"zmp_sim drawn from sim.csv ({why}): without sole edges, with the measured double supports", stacklevel=2
    )
    return run
