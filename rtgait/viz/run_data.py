"""What the figures draw, taken from a run in memory or read back from the files a finished run wrote (numpy only).

The figures of ``rtgait plan`` are drawn from a small record, :class:`PlanRun`, never from the planner's own
objects; it is made either from the rollout in memory (:meth:`PlanRun.from_rollout`) or from the run's files
(:func:`read_plan_run`), so ``rtgait plot DIR`` remakes the very figures the run wrote: the files carry everything
a figure shows (``trajectory.csv`` per tick, ``summary.json`` for the rest). The pendulum figure's record,
:class:`rtgait.viz.pendulum.PendulumRun`, is read with the helpers here.

Also here, because ``summary.json`` and the figures must agree on it: which tick is *the* minimum ZMP margin
(:func:`margin_marker`), and the figure file names for each format. No matplotlib: :mod:`rtgait.io.plan_files` uses this
module on a core install.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.support import support_polygon

if TYPE_CHECKING:
    from rtgait.core.analysis.rollout import Rollout

__all__ = [
    "FIGURE_FORMATS",
    "MARGIN_TIE_TOLERANCE",
    "OBSTACLE_FIGURE",
    "PENDULUM_FIGURE",
    "PLAN_FIGURES",
    "FigureInfo",
    "MarginMarker",
    "PlanRun",
    "RunFilesError",
    "figure_file",
    "margin_marker",
    "plan_figure_files",
    "read_floats",
    "read_plan_run",
    "read_summary",
    "read_table",
    "require_keys",
    "run_kind",
]

FIGURE_FORMATS = ("png", "pdf", "svg")
"""File formats of the figures (``--format``); png is the default."""

PLAN_FIGURES = ("zmp_cog", "zmp_deviation", "top_view", "zmp_margin")
"""The figures of ``rtgait plan``, by file stem, in the order they are written and listed."""

OBSTACLE_FIGURE = "obstacle"
"""The figure of a plan with obstacles (:mod:`rtgait.viz.obstacle_figure`), by file stem."""

PENDULUM_FIGURE = "pendulum"
"""The figure of ``rtgait simulate --model lipm``, by file stem."""

MARGIN_TIE_TOLERANCE = 1e-9
"""Margins (m) within this of the minimum are tied with it: far below anything physical, far above the round-off of
the margin computation and of the 10 significant digits the CSV files keep."""

_TIME_TOLERANCE = 1e-9  # s: far below any control period, far above the round-off of tick times

PLAN_CSV = "trajectory.csv"
SIM_CSV = "sim.csv"
SIM_PARQUET = "sim.parquet"
SUMMARY = "summary.json"
# Columns only the MuJoCo loop writes into its sim.csv (rtgait.io.sim_run.SIM_CSV_COLUMNS): a run that has them is a
# simulation of the robot, whose figure is not drawn here.
_MUJOCO_COLUMNS = ("base_qw", "left_contact")


def figure_file(stem: str, fmt: str = "png") -> str:
    """The file name of the figure ``stem`` in the format ``fmt`` (:data:`FIGURE_FORMATS`)."""
    if fmt not in FIGURE_FORMATS:
        raise ValueError(f"figure format must be one of {', '.join(FIGURE_FORMATS)}, got {fmt!r}")
    return f"{stem}.{fmt}"


def plan_figure_files(fmt: str = "png") -> list[str]:
    """The file names of the four plan figures (:data:`PLAN_FIGURES`) in the format ``fmt``."""
    return [figure_file(stem, fmt) for stem in PLAN_FIGURES]


class RunFilesError(ValueError):
    """A folder does not hold the files of a run the figures can be drawn from (one line, names the file)."""


@dataclass(frozen=True)
class FigureInfo:
    """What the plan figures need besides the run.

    Attributes:
        title: prefix of every figure title, e.g. ``"fig4 (real-time)"``.
        sole: sole rectangle around the foot frame (m), for footprint outlines.
        nominal_footprints: footprints ``F[0..]`` as planned before any change; footprints that differ from
            them are highlighted in the top view. ``None``: nothing highlighted.
    """

    title: str
    sole: SoleRect
    nominal_footprints: Sequence[Footstep] | None = None


# ----- the minimum ZMP margin ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class MarginMarker:
    """The tick shown as the walk's minimum ZMP margin, and how many ticks share that minimum.

    Attributes:
        index: the tick marked (and reported as ``zmp_margin_min_time`` in ``summary.json``).
        tied: ticks whose margin is within :data:`MARGIN_TIE_TOLERANCE` of the minimum (1: a unique minimum).
        tied_duration: how long the margin stays at its minimum over the walk (s): ``tied`` ticks of ``dt``.
        reason: why this tick, for a figure's caption (empty for a unique minimum).
    """

    index: int
    tied: int
    tied_duration: float
    reason: str


def margin_marker(times: np.ndarray, margin: np.ndarray, change_times: Sequence[float] = ()) -> MarginMarker:
    """Which tick to mark (and report) as the minimum ZMP margin.

    The minimum is often reached at many ticks: a ZMP resting on the stance ankle in single support is the same
    half sole width from the edges at every such tick, in every step. The first of them (what ``argmin`` gives) is
    the first lift-off, which tells nothing about the walk. The rule:

    * one tick at the minimum: that tick;
    * several (within :data:`MARGIN_TIE_TOLERANCE`) and a footstep change decided in the walk: the first tied tick
      at or after the first change's decision, the instant the figures are about (the margin while the change is
      absorbed);
    * otherwise (no change, or no tie after it): the first tied tick.

    The minimum itself is ``margin.min()`` in every case.
    """
    margin = np.asarray(margin, dtype=float)
    times = np.asarray(times, dtype=float)
    tied = np.flatnonzero(margin <= margin.min() + MARGIN_TIE_TOLERANCE)
    dt = float(times[1] - times[0]) if len(times) > 1 else 0.0
    duration = len(tied) * dt
    if len(tied) == 1:
        return MarginMarker(int(tied[0]), 1, duration, "")
    if len(change_times):
        first_change = min(change_times)
        after = tied[times[tied] >= first_change - 1e-12]
        if len(after):
            return MarginMarker(int(after[0]), len(tied), duration, "first after the change")
    return MarginMarker(int(tied[0]), len(tied), duration, "first instant")


# ----- a plan run ----------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PlanRun:
    """Every tick of a planned walk, as the plan figures draw it.

    Attributes:
        times: tick times (s) from the walk's start, ``(k,)``.
        cog, zmp, zmp_ref: COG, planned ZMP and the footsteps' reference ZMP, x and y (m), ``(k, 2)``.
        support: ``"double"``, ``"left"`` or ``"right"`` (the foot on the ground) per tick.
        phase: phase index per tick.
        margin: signed ZMP margin to the support polygon (m, positive inside) per tick.
        polygons: the support polygon of each phase sampled (counter-clockwise vertices, m), by phase index.
        footprints: the footprints ``F[0..]`` as walked.
        changes: ``(decision time (s), step)`` of every footstep change, in the order they were handed over.
        free_segments: ``(start, end)`` (s) of the free first segment of every plan, the initial plan's first.
        heights: COG, left and right foot heights (m), ``(k, 3)``, of a walk whose COG height changes (off the flat
            floor); ``None`` on level ground.
    """

    times: np.ndarray
    cog: np.ndarray
    zmp: np.ndarray
    zmp_ref: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    margin: np.ndarray
    polygons: dict[int, np.ndarray]
    footprints: list[Footstep]
    changes: list[tuple[float, int]]
    free_segments: list[tuple[float, float]]
    heights: np.ndarray | None = None

    @classmethod
    def from_rollout(cls, rollout: Rollout) -> PlanRun:
        """The record of a rollout in memory."""
        column = rollout.column
        return cls(
            times=rollout.times,
            cog=np.column_stack([column("cog_x"), column("cog_y")]),
            zmp=np.column_stack([column("zmp_x"), column("zmp_y")]),
            zmp_ref=np.column_stack([column("zmp_ref_x"), column("zmp_ref_y")]),
            support=rollout.support,
            phase=rollout.phase,
            margin=rollout.margin,
            polygons={int(q): _canonical(polygon) for q, polygon in rollout.polygons.items()},
            footprints=list(rollout.footprints),
            changes=[(float(t), int(step)) for t, step in rollout.changes],
            free_segments=plan_free_segments(rollout),
            heights=_heights(column("cog_z"), column("lfoot_z"), column("rfoot_z")),
        )

    def column(self, name: str) -> np.ndarray:
        """``cog_x``, ``zmp_y``, ``zmp_ref_x``, ... by the trajectory's column name (m)."""
        quantity, axis = name.rsplit("_", 1)
        table = {"cog": self.cog, "zmp": self.zmp, "zmp_ref": self.zmp_ref}[quantity]
        return table[:, "xy".index(axis)]

    @property
    def marker(self) -> MarginMarker:
        """The tick shown as the minimum ZMP margin (:func:`margin_marker`)."""
        return margin_marker(self.times, self.margin, [t for t, _ in self.changes])

    @property
    def zmp_margin_min(self) -> float:
        """Smallest signed ZMP margin over the walk (m)."""
        return float(self.margin.min())

    def free_mask(self, initial: bool) -> np.ndarray:
        """Ticks inside the free first segment of the initial plan (``initial``) or of the connected replans."""
        segments = self.free_segments[:1] if initial else self.free_segments[1:]
        mask = np.zeros(len(self.times), dtype=bool)
        for start, end in segments:
            # 1 ns either side: a tick on a boundary stays in whether its time was computed or read back from the
            # CSV's 10 digits (the deviation is zero there, where the plan meets its reference, so nothing moves).
            mask |= (self.times >= start - _TIME_TOLERANCE) & (self.times <= end + _TIME_TOLERANCE)
        return mask


def _heights(cog_z: np.ndarray, left_z: np.ndarray, right_z: np.ndarray) -> np.ndarray | None:
    """The heights of a walk whose COG height changes, ``None`` for one at a constant height."""
    return np.column_stack([cog_z, left_z, right_z]) if np.ptp(cog_z) > 0.0 else None


def plan_free_segments(rollout: Rollout) -> list[tuple[float, float]]:
    """``(start, end)`` (s) of the free first segment of each plan of ``rollout``, the initial plan's first."""
    return [(float(plan.t), float(plan.first_segment_end)) for plan in rollout.plans]


def _footstep(entry: Any, where: str) -> Footstep:
    try:
        tilt = {key: float(entry[key]) for key in ("z", "pitch", "roll") if key in entry}  # off level ground
        return Footstep(float(entry["x"]), float(entry["y"]), float(entry["yaw"]), entry["side"], **tilt)
    except (KeyError, TypeError, ValueError) as error:
        raise RunFilesError(f"{where}: a footprint must have x, y, yaw and side ({error})") from None


def read_table(path: Path, required: Sequence[str]) -> dict[str, np.ndarray]:
    """The columns of a CSV file written by rtgait, as text arrays by name; refuses one missing ``required``."""
    try:
        with open(path, encoding="utf-8") as stream, warnings.catch_warnings():
            # An empty body is no warning here (its stream's repr would be the message): "no rows" is said below.
            warnings.simplefilter("ignore")
            header = stream.readline().strip().split(",")
            # ndmin=2: a run of a single tick is still a table of one row.
            table = np.loadtxt(stream, delimiter=",", dtype=str, ndmin=2)
    except OSError as error:
        raise RunFilesError(f"cannot read {path}: {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise RunFilesError(f"cannot read {path}: not a text file") from None
    except ValueError as error:  # numpy's "the number of columns changed from 27 to 22 at row 132; use `usecols`..."
        detail = str(error).split(";")[0]
        raise RunFilesError(f"cannot read {path}: it is cut short or damaged ({detail})") from None
    if table.shape[0] < 1:  # first: a header cut short also lacks columns, but "cut short" is the news
        raise RunFilesError(f"{path} has no rows: it is cut short or damaged")
    missing = [name for name in required if name not in header]
    if missing:
        raise RunFilesError(f"{path} has no column {missing[0]}: not a file rtgait wrote for this kind of run")
    if table.shape[1] != len(header):
        raise RunFilesError(f"{path} has rows that do not match its header: it is cut short or damaged")
    return {name: table[:, index] for index, name in enumerate(header)}


def read_floats(columns: dict[str, np.ndarray], names: Sequence[str], path: Path) -> np.ndarray:
    """The columns ``names`` of a :func:`read_table` as one float array ``(k, len(names))``."""
    try:
        return np.column_stack([columns[name].astype(float) for name in names])
    except ValueError as error:
        raise RunFilesError(f"{path}: a value of {', '.join(names)} is not a number ({error})") from None


def read_summary(folder: Path) -> dict[str, Any]:
    """The ``summary.json`` of the run in ``folder``."""
    path = Path(folder) / SUMMARY
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RunFilesError(f"{path} is missing: {folder} does not hold a finished rtgait run") from None
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise RunFilesError(f"cannot read {path}: {error}") from None
    if not isinstance(summary, dict):
        raise RunFilesError(f"{path} is not a run's summary (not a JSON object)")
    return summary


def require_keys(summary: dict[str, Any], keys: Sequence[str], folder: Path, kind: str) -> None:
    """Refuse a summary without one of ``keys``: not the summary of ``kind`` run, or one older than the figures."""
    missing = [key for key in keys if key not in summary]
    if missing:
        raise RunFilesError(
            f"{Path(folder) / SUMMARY} has no {missing[0]!r}: not the summary of {kind} run, or one written by an "
            "older rtgait (run it again)"
        )


def _canonical(polygon: np.ndarray) -> np.ndarray:
    """``polygon`` (counter-clockwise) without collinear vertices, starting at its lowest-x (then lowest-y) vertex.

    The same support polygon comes out of the hull with another first vertex, or with a collinear corner kept
    when the feet's poses went through the CSV's 10 digits; one form for both makes runs comparable."""
    before = np.roll(polygon, 1, axis=0) - polygon
    after = np.roll(polygon, -1, axis=0) - polygon
    turn = np.abs(before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0])
    kept = polygon[turn > 1e-10] if np.count_nonzero(turn > 1e-10) >= 3 else polygon  # m^2: far below a sole's
    first = np.lexsort((kept[:, 1], kept[:, 0]))[0]
    return np.roll(kept, -first, axis=0)


def _polygons(columns: dict[str, np.ndarray], phase: np.ndarray, sole: SoleRect) -> dict[int, np.ndarray]:
    """Each phase's support polygon from the foot poses of its first tick: the feet on the ground then."""
    poses = {
        side: np.column_stack([columns[f"{prefix}_{k}"].astype(float) for k in ("x", "y", "yaw")])
        for side, prefix in (("left", "lfoot"), ("right", "rfoot"))
    }
    support = columns["support"]
    polygons: dict[int, np.ndarray] = {}
    for q in np.unique(phase):
        k = int(np.flatnonzero(phase == q)[0])
        sides = ("left", "right") if support[k] == "double" else (str(support[k]),)
        feet = [Footstep(*(float(v) for v in poses[side][k]), side) for side in sides]  # type: ignore[arg-type]
        polygons[int(q)] = _canonical(support_polygon(feet, sole))
    return polygons


def read_plan_run(folder: Path) -> tuple[PlanRun, FigureInfo, dict[str, Any]]:
    """The plan run in ``folder`` (``trajectory.csv`` and ``summary.json`` of ``rtgait plan``): the record, the
    figures' titles and sole, and the summary.

    Raises:
        RunFilesError: a file is missing, unreadable or not what ``rtgait plan`` writes.
    """
    folder = Path(folder)
    summary = read_summary(folder)
    keys = ("scenario", "connection", "sole", "footprints", "changes", "free_segments")
    require_keys(summary, keys, folder, "a plan")
    path = folder / PLAN_CSV
    if not path.is_file():
        raise RunFilesError(f"{path} is missing: {folder} does not hold a finished rtgait plan run")
    numeric = ("t", "cog_x", "cog_y", "zmp_x", "zmp_y", "zmp_ref_x", "zmp_ref_y", "zmp_margin", "phase")
    feet = tuple(f"{foot}_{k}" for foot in ("lfoot", "rfoot") for k in ("x", "y", "yaw"))
    columns = read_table(path, (*numeric, *feet, "support"))
    values = read_floats(columns, (*numeric, *feet), path)
    height_names = ("cog_z", "lfoot_z", "rfoot_z")
    heights = None
    if all(name in columns for name in height_names):  # written by every rtgait plan; older runs may lack them
        z = read_floats(columns, height_names, path)
        heights = _heights(z[:, 0], z[:, 1], z[:, 2])
    try:
        sole = SoleRect(**{key: float(summary["sole"][key]) for key in ("front", "back", "inner", "outer")})
        nominal = summary.get("nominal_footprints")
        info = FigureInfo(
            title=f"{summary['scenario']} ({summary['connection']})",
            sole=sole,
            nominal_footprints=None if nominal is None else [_footstep(f, str(path)) for f in nominal],
        )
        changes = [(float(c["decided_at"]), int(c["step"])) for c in summary["changes"]]
        free = [(float(start), float(end)) for start, end in summary["free_segments"]]
        footprints = [_footstep(f, SUMMARY) for f in summary["footprints"]]
        phase = values[:, numeric.index("phase")].astype(int)
        polygons = _polygons(columns, phase, sole)
    except (KeyError, TypeError, ValueError) as error:
        raise RunFilesError(f"{folder / SUMMARY} or {path} is not what rtgait plan writes ({error})") from None
    if not free:
        raise RunFilesError(f"{folder / SUMMARY} lists no plan in free_segments")
    run = PlanRun(
        times=values[:, 0],
        cog=values[:, 1:3],
        zmp=values[:, 3:5],
        zmp_ref=values[:, 5:7],
        support=columns["support"].astype(str),
        phase=phase,
        margin=values[:, numeric.index("zmp_margin")],
        polygons=polygons,
        footprints=footprints,
        changes=changes,
        free_segments=free,
        heights=heights,
    )
    return run, info, summary


# ----- which kind of run ---------------------------------------------------------------------------------------


def _csv_header(path: Path) -> list[str]:
    try:
        with open(path, encoding="utf-8") as stream:
            return stream.readline().strip().split(",")
    except (OSError, UnicodeDecodeError) as error:
        raise RunFilesError(f"cannot read {path}: {error}") from None


def run_kind(folder: Path) -> str:
    """``"plan"``, ``"lipm"`` or ``"mujoco"``: the kind of finished run in ``folder``, told by its summary and its
    files (``sim.parquet`` or the robot's columns of ``sim.csv`` for a MuJoCo simulation).

    Raises:
        RunFilesError: not a folder, or no run in it.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise RunFilesError(f"{folder} is not a folder" if folder.exists() else f"{folder} does not exist")
    summary = read_summary(folder)
    sim = folder / SIM_CSV
    if summary.get("model") == "lipm":
        return "lipm"
    if (
        (folder / SIM_PARQUET).is_file()
        or summary.get("model") == "mujoco"
        or "walk_start" in summary
        or (sim.is_file() and set(_MUJOCO_COLUMNS) <= set(_csv_header(sim)))
    ):
        return "mujoco"
    if (folder / PLAN_CSV).is_file() or "zmp_margin_min" in summary:
        return "plan"
    raise RunFilesError(f"{folder} holds no trajectory.csv (rtgait plan) or sim.csv (rtgait simulate)")
