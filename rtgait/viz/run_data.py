"""What the figures draw, taken from a run in memory or read back from the files a finished run wrote (numpy only).

The figures of ``rtgait plan`` are drawn from a small record, :class:`PlanRun`, never from the planner's own
objects; it is made either from the rollout in memory (:meth:`PlanRun.from_rollout`) or from the run's files
(:func:`read_plan_run`), so ``rtgait plot DIR`` remakes the very figures the run wrote: the files carry everything
a figure shows (``trajectory.csv`` per tick, ``summary.json`` for the rest). The pendulum figure's record,
:class:`rtgait.viz.pendulum.PendulumRun`, is read with the same readers.

The files are read by :mod:`rtgait.viz.run_files`; which tick is *the* minimum ZMP margin, on which ``summary.json``
and the figures must agree, is :mod:`rtgait.viz.margin_marker`; the figure file names are
:mod:`rtgait.viz.figure_files`. No matplotlib: :mod:`rtgait.io.plan_files` uses these modules on a core install.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.support import support_polygon
from rtgait.core.geometry.terrain import TerrainKind
from rtgait.viz.margin_marker import MarginMarker, margin_marker
from rtgait.viz.run_files import (
    PLAN_CSV,
    SUMMARY,
    RunFilesError,
    read_floats,
    read_summary,
    read_table,
    read_terrain,
    require_keys,
)

if TYPE_CHECKING:
    from rtgait.core.analysis.rollout import Rollout

__all__ = ["FigureInfo", "PlanRun", "read_plan_run"]

_TIME_TOLERANCE = 1e-9  # s: far below any control period, far above the round-off of tick times


@dataclass(frozen=True)
class FigureInfo:
    """What the plan figures need besides the run.

    Attributes:
        title: prefix of every figure title, e.g. ``"fig4 (real-time)"``.
        sole: sole rectangle around the foot frame (m), for footprint outlines.
        nominal_footprints: footprints ``F[0..]`` as planned before any change; footprints that differ from
            them are highlighted in the top view. ``None``: nothing highlighted.
        terrain: the terrain walked on (``None``: the flat floor); off the flat floor ``zmp_cog`` draws its side
            view under the planned feet.
    """

    title: str
    sole: SoleRect
    nominal_footprints: Sequence[Footstep] | None = None
    terrain: TerrainKind | None = None


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
        feet_xz: the planned feet's ``(x, z)`` (m), ``(k, 2, 2)`` (left, right); ``None`` read from an old run
            without the heights.
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
    feet_xz: np.ndarray | None = None

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
            feet_xz=_feet_xz(*(column(f"{foot}_{axis}") for foot in ("lfoot", "rfoot") for axis in "xz")),
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


def _feet_xz(*columns: np.ndarray) -> np.ndarray:
    """The feet's ``(x, z)``, ``(k, 2, 2)``, from the columns left x, left z, right x, right z."""
    return np.stack([np.column_stack(columns[:2]), np.column_stack(columns[2:])], axis=1)


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
    heights = feet_xz = None
    if all(name in columns for name in height_names):  # written by every rtgait plan; older runs may lack them
        z = read_floats(columns, height_names, path)
        heights = _heights(z[:, 0], z[:, 1], z[:, 2])
        x = values[:, [len(numeric) + feet.index("lfoot_x"), len(numeric) + feet.index("rfoot_x")]]
        feet_xz = _feet_xz(x[:, 0], z[:, 1], x[:, 1], z[:, 2])
    try:
        sole = SoleRect(**{key: float(summary["sole"][key]) for key in ("front", "back", "inner", "outer")})
        nominal = summary.get("nominal_footprints")
        info = FigureInfo(
            title=f"{summary['scenario']} ({summary['connection']})",
            sole=sole,
            nominal_footprints=None if nominal is None else [_footstep(f, str(path)) for f in nominal],
            terrain=read_terrain((summary.get("terrain") or {}).get("fields")),
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
        feet_xz=feet_xz,
    )
    return run, info, summary
