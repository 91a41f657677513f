"""Figures of a planned walk in the spirit of the paper's Figs. 4-9 (matplotlib, drawn off-screen with Agg).

Each ``draw_*`` function makes one figure from a :class:`~rtgait.viz.run_data.PlanRun` (a rollout in memory, or a
finished run read back from its files) and a :class:`FigureInfo` (title, sole, the footprints as planned before any
change); each ``plot_*`` function writes one to a path whose suffix picks the format (png, pdf, svg) and also takes
a :class:`~rtgait.core.analysis.rollout.Rollout` directly. :func:`render_all` writes the four figures of ``rtgait
plan``. The ZMP deviation figure is drawn by :mod:`rtgait.viz.deviation_figure`, the robot's multibody ZMP by
:mod:`rtgait.viz.multibody_figure`; the marks they share are :mod:`rtgait.viz.plan_marks`.

Conventions (:mod:`rtgait.viz.style`): positions in m, deviations and margins in mm, time in s from the walk's
start, units in square brackets.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.terrain import Flat
from rtgait.viz.deviation_figure import draw_zmp_deviation
from rtgait.viz.figure_files import PLAN_FIGURES, figure_file, plan_figure_files
from rtgait.viz.plan_marks import (
    RunLike,
    _as_run,
    _finish_time_panels,
    _margin_caption,
    _mark_changes,
    _mark_outside,
    _shade_double_support,
)
from rtgait.viz.run_data import FigureInfo, PlanRun
from rtgait.viz.style import (
    BAND_COLOR,
    COG_COLOR,
    REF_COLOR,
    SIDE_COLORS,
    TIME_LABEL,
    ZMP_COLOR,
    clean_ticks,
    new_figure,
    save,
    span_limits,
)
from rtgait.viz.terrain_profile import draw_terrain_profile

__all__ = [
    "DRAW",
    "FIGURE_FILES",
    "FigureInfo",
    "draw_top_view",
    "draw_zmp_cog",
    "draw_zmp_margin",
    "plot_top_view",
    "plot_zmp_cog",
    "plot_zmp_deviation",
    "plot_zmp_margin",
    "render_all",
    "support_extents",
]

FIGURE_FILES = tuple(plan_figure_files("png"))
"""File names written by :func:`render_all` in the default format, in order."""

MOVED_TOLERANCE = 1e-3  # a footprint moved by more than this (m, or rad of yaw) counts as changed
MARKER_GID = "margin-marker"
"""``gid`` of the artist marking the minimum ZMP margin (top view, margin figure), for tools and tests."""

# ----- data helpers ---------------------------------------------------------------------------------------------


def support_extents(run: RunLike, sole: SoleRect | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per tick, the support polygon's lower and upper bounds along x and y, each shape ``(k, 2)`` (m).

    ``sole`` is not needed (the run's polygons are built with it); kept for the callers that pass it."""
    run = _as_run(run)
    lower = np.full((len(run.times), 2), np.nan)
    upper = np.full_like(lower, np.nan)
    for q, polygon in run.polygons.items():
        mask = run.phase == q
        lower[mask] = polygon.min(axis=0)
        upper[mask] = polygon.max(axis=0)
    return lower, upper


def _moved(footprints: Sequence[Footstep], nominal: Sequence[Footstep] | None) -> list[bool]:
    if nominal is None or len(nominal) != len(footprints):
        return [False] * len(footprints)
    return [
        bool(np.hypot(a.x - b.x, a.y - b.y) > MOVED_TOLERANCE or abs(a.yaw - b.yaw) > MOVED_TOLERANCE)
        for a, b in zip(footprints, nominal, strict=True)
    ]


# ----- the figures ----------------------------------------------------------------------------------------------


def draw_zmp_cog(run: PlanRun, info: FigureInfo) -> Figure:
    """ZMP (planned and reference) and COG along x and y against time, with the support polygon's extent; off the
    flat floor a third panel draws the COG height and the feet's heights, and with the terrain known
    (:attr:`FigureInfo.terrain`) a last one its side view (x-z) under the planned feet.

    The band is the support polygon's extent along each axis (m): a ZMP outside the band is outside the
    polygon; red dots mark every tick where the ZMP is outside the polygon in the plane.
    """
    lower, upper = support_extents(run)
    side_view = info.terrain is not None and not isinstance(info.terrain, Flat) and run.feet_xz is not None
    rows = 2 if run.heights is None else 3
    if side_view:  # the terrain's side view under the time panels, on an x axis of its own
        figure = new_figure(11, 2.5 * rows + 4.0)
        grid = figure.add_gridspec(rows + 1, 1, height_ratios=[1.0] * rows + [1.4])
        axes = [figure.add_subplot(grid[0])]
        axes += [figure.add_subplot(grid[row], sharex=axes[0]) for row in range(1, rows)]
        for ax in axes[:-1]:
            ax.tick_params(labelbottom=False)
    else:
        figure = new_figure(11, 7.5 if run.heights is None else 10.0)
        axes = figure.subplots(rows, 1, sharex=True)
    t = run.times
    for index, (ax, axis) in enumerate(zip(axes[:2], "xy", strict=True)):
        first = index == 0
        _shade_double_support(ax, run, first)
        ax.fill_between(t, lower[:, index], upper[:, index], color=BAND_COLOR, alpha=0.18, lw=0, zorder=1,
                        label="support polygon's extent along the axis" if first else None)  # fmt: skip
        zmp = run.zmp[:, index]
        ax.plot(t, run.cog[:, index], color=COG_COLOR, lw=1.6, zorder=3, label="COG" if first else None)
        ax.plot(t, zmp, color=ZMP_COLOR, lw=1.6, zorder=3, label="ZMP (planned)" if first else None)
        ax.plot(t, run.zmp_ref[:, index], color=REF_COLOR, ls="--", lw=1.0, zorder=3,
                label="ZMP reference (footsteps only)" if first else None)  # fmt: skip
        _mark_outside(ax, run, zmp, first)
        _mark_changes(ax, run, first)
        ax.set_ylabel(f"{axis} [m]")
        clean_ticks(ax)
    if run.heights is not None:
        _heights_panel(axes[2], run)
    _finish_time_panels(figure, axes, t, f"{info.title}: ZMP and COG", legend_columns=3)
    if side_view:  # after the figure's legend, which keeps to the time panels
        draw_terrain_profile(figure.add_subplot(grid[rows]), info.terrain, run.feet_xz, "planned")  # type: ignore[arg-type]
    return figure


def _heights_panel(ax: Axes, run: PlanRun) -> None:
    """The COG height and both feet's heights (m) against time."""
    t, heights = run.times, run.heights
    _shade_double_support(ax, run, False)
    ax.plot(t, heights[:, 0], color=COG_COLOR, lw=1.6, zorder=3)
    ax.plot(t, heights[:, 1], color=SIDE_COLORS["left"], lw=1.2, zorder=3, label="left foot height")
    ax.plot(t, heights[:, 2], color=SIDE_COLORS["right"], lw=1.2, zorder=3, label="right foot height")
    ax.set_ylabel("z [m]")
    ax.set_title("vertical (z): COG and feet", fontsize=10, loc="left")
    clean_ticks(ax)


def draw_top_view(run: PlanRun, info: FigureInfo) -> Figure:
    """Top view (m, equal aspect): soles of all footprints, ZMP and COG paths, and the minimum ZMP margin."""
    prints = run.footprints
    corners = np.concatenate([info.sole.corners(foot) for foot in prints])
    span = np.ptp(corners, axis=0) + 0.1
    # Size the figure to the walk's shape: a fixed box would leave a straight walk as a thin strip in a sea
    # of empty axes. About 9.5 in of plot width, the height following the aspect, within readable bounds.
    plot_height = float(np.clip(9.5 * span[1] / span[0], 2.5, 8.0))
    figure = new_figure(11, plot_height + 2.5)
    ax = figure.add_subplot()
    moved = _moved(prints, info.nominal_footprints)
    seen: set[str] = set()
    for index, (foot, was_moved) in enumerate(zip(prints, moved, strict=True)):
        key = f"{foot.side} foot" + (" (moved by a change)" if was_moved else "")
        colour = SIDE_COLORS[foot.side]
        ax.add_patch(Polygon(info.sole.corners(foot), closed=True, facecolor=colour, alpha=0.35 if was_moved else 0.18,
                             edgecolor="black" if was_moved else colour, lw=1.6 if was_moved else 1.0,
                             hatch="///" if was_moved else None, label=None if key in seen else key))  # fmt: skip
        seen.add(key)
        # F[i + 1] is where step i lands; F[0], F[1] are the standing feet (step 0).
        ax.annotate(str(max(index - 1, 0)), (foot.x, foot.y), ha="center", va="center", fontsize=8, color="0.15")
    if info.nominal_footprints is not None:
        # Drawn after the soles so the outlines stay visible where the moved footprints overlap them.
        for index in (i for i, was_moved in enumerate(moved) if was_moved):
            ax.add_patch(
                Polygon(
                    info.sole.corners(info.nominal_footprints[index]),
                    closed=True,
                    fill=False,
                    ls="--",
                    edgecolor="0.4",
                    lw=0.9,
                    label=None if "planned" in seen else "where it was planned before the change",
                )
            )
            seen.add("planned")
    ax.plot(run.cog[:, 0], run.cog[:, 1], color=COG_COLOR, lw=1.5, label="COG")
    ax.plot(run.zmp[:, 0], run.zmp[:, 1], color=ZMP_COLOR, lw=1.3, label="ZMP (planned)")
    worst = run.marker.index
    margin = run.zmp_margin_min
    colour = "red" if margin < 0.0 else "tab:green"
    polygon = run.polygons[int(run.phase[worst])]
    ax.add_patch(Polygon(polygon, closed=True, fill=False, edgecolor=colour, lw=1.4, ls="-.",
                         label="support polygon at the marked instant"))  # fmt: skip
    ax.plot(run.zmp[worst, 0], run.zmp[worst, 1], marker="X" if margin < 0.0 else "o", ms=11, color=colour,
            mec="black", zorder=5, gid=MARKER_GID, label=_margin_caption(run))  # fmt: skip
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    clean_ticks(ax)
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{info.title}: footprints, ZMP and COG (top view; numbers = step landing there)")
    figure.legend(loc="outside lower center", ncol=2, fontsize=8)
    return figure


def draw_zmp_margin(run: PlanRun, info: FigureInfo) -> Figure:
    """Signed ZMP margin to the support polygon (mm, positive inside) against time, the minimum marked."""
    figure = new_figure(11, 4.8)
    ax = figure.add_subplot()
    t = run.times
    margin = run.margin * 1000.0
    _shade_double_support(ax, run, True)
    ax.plot(t, margin, color=ZMP_COLOR, lw=1.5, label="ZMP margin")
    outside = margin < 0.0
    if outside.any():  # an empty fill would still put its label in the legend
        ax.fill_between(t, margin, 0.0, where=outside, color="red", alpha=0.35, lw=0,
                        label="ZMP outside the support polygon")  # fmt: skip
    ax.axhline(0.0, color="black", lw=1.0)
    worst = run.marker.index
    colour = "red" if run.zmp_margin_min < 0.0 else "tab:green"
    ax.plot(t[worst], margin[worst], "o", color=colour, mec="black", ms=7, zorder=5, gid=MARKER_GID,
            label=_margin_caption(run))  # fmt: skip
    _mark_changes(ax, run, True)
    # Room below the lowest point for the marker, and zero always in view: the margin's sign is the verdict.
    low, high = span_limits(margin, 20.0, include=0.0, pad=0.12)
    ax.set_ylim(low, high)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("ZMP margin [mm] (> 0: inside)")
    clean_ticks(ax)
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{info.title}: signed ZMP margin to the support polygon")
    figure.legend(loc="outside lower center", ncol=3, fontsize=8)
    return figure


DRAW: dict[str, Callable[[PlanRun, FigureInfo], Figure]] = {
    "zmp_cog": draw_zmp_cog,
    "zmp_deviation": draw_zmp_deviation,
    "top_view": draw_top_view,
    "zmp_margin": draw_zmp_margin,
}
"""The four figures of ``rtgait plan`` by file stem (:data:`~rtgait.viz.figure_files.PLAN_FIGURES` order)."""


def plot_zmp_cog(rollout: RunLike, info: FigureInfo, path: Path) -> Path:
    """Write :func:`draw_zmp_cog` to ``path`` (format from the suffix); returns ``path``."""
    return save(draw_zmp_cog(_as_run(rollout), info), path)


def plot_zmp_deviation(rollout: RunLike, info: FigureInfo, path: Path) -> Path:
    """Write :func:`draw_zmp_deviation` to ``path`` (format from the suffix); returns ``path``."""
    return save(draw_zmp_deviation(_as_run(rollout), info), path)


def plot_top_view(rollout: RunLike, info: FigureInfo, path: Path) -> Path:
    """Write :func:`draw_top_view` to ``path`` (format from the suffix); returns ``path``."""
    return save(draw_top_view(_as_run(rollout), info), path)


def plot_zmp_margin(rollout: RunLike, info: FigureInfo, path: Path) -> Path:
    """Write :func:`draw_zmp_margin` to ``path`` (format from the suffix); returns ``path``."""
    return save(draw_zmp_margin(_as_run(rollout), info), path)


def render_all(rollout: RunLike, info: FigureInfo, folder: Path, fmt: str = "png") -> list[Path]:
    """Write the four figures (:data:`~rtgait.viz.figure_files.PLAN_FIGURES`) into ``folder`` in the format ``fmt``
    (png, pdf or svg); returns their paths."""
    run = _as_run(rollout)
    folder = Path(folder)
    return [save(DRAW[stem](run, info), folder / figure_file(stem, fmt)) for stem in PLAN_FIGURES]
