"""The ZMP deviation figure of a planned walk: ``zmp - zmp_ref`` (mm) along x and y in the free first segment of
each plan, the only windows where the planned ZMP may leave its reference (matplotlib)."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from rtgait.viz.plan_marks import _finish_time_panels, _mark_changes
from rtgait.viz.run_data import FigureInfo, PlanRun
from rtgait.viz.style import (
    DOUBLE_COLOR,
    MINUS,
    ZMP_COLOR,
    clean_ticks,
    new_figure,
    runs,
    signed_mm,
    span_limits,
)

__all__ = ["MIN_DEVIATION_SPAN", "draw_zmp_deviation"]

MIN_DEVIATION_SPAN = 4.0
"""Smallest y span (mm) of a deviation panel: a replan that keeps the ZMP within a fraction of a mm of its reference
shows as the flat line it is, not as noise blown up to the panel's height."""


def _deviation_panel(ax: Axes, run: PlanRun, index: int, first: bool) -> None:
    """One axis of :func:`draw_zmp_deviation`, in mm, scaled on the replans."""
    t = run.times
    deviation = (run.zmp[:, index] - run.zmp_ref[:, index]) * 1000.0
    connecting = run.free_mask(initial=False)
    initial = run.free_mask(initial=True) & ~connecting
    for k, (t0, t1) in enumerate(runs(initial | connecting, t)):
        ax.axvspan(
            t0,
            t1,
            color=DOUBLE_COLOR,
            alpha=0.6,
            lw=0,
            zorder=0,
            label="free first segment of a plan (the ZMP may leave its reference)" if first and k == 0 else None,
        )
    # NaN outside the windows breaks the line there instead of drawing zeros that were never free.
    ax.plot(t, np.where(connecting, deviation, np.nan), color=ZMP_COLOR, lw=1.6, zorder=3, gid="deviation-replans",
            label=f"ZMP {MINUS} ZMP reference, replans" if first else None)  # fmt: skip
    ax.plot(t, np.where(initial, deviation, np.nan), color=ZMP_COLOR, lw=1.2, ls="--", alpha=0.7, zorder=3,
            gid="deviation-initial",
            label=f"ZMP {MINUS} ZMP reference, initial plan (start from rest)" if first else None)  # fmt: skip
    ax.axhline(0.0, color="black", lw=0.8, zorder=2)
    # The initial plan always swings the ZMP far from its reference (the anticipatory shift that starts the COG
    # moving from rest); scaled on it, the replans' deviations, which the figure is about, would be flat lines.
    scale_on = connecting if connecting.any() else initial
    low, high = span_limits(deviation[scale_on], MIN_DEVIATION_SPAN, include=0.0)
    ax.set_ylim(low, high)
    if connecting.any():
        worst = int(np.argmax(np.where(connecting, np.abs(deviation), -1.0)))
        ax.plot(t[worst], deviation[worst], "o", color="red", ms=5, zorder=4,
                label="largest deviation of a replan" if first else None)  # fmt: skip
        ax.annotate(f"{signed_mm(deviation[worst] / 1000.0)} at {t[worst]:.2f} s", (t[worst], deviation[worst]),
                    xytext=(8, 0), textcoords="offset points", fontsize=8, color="red", va="center")  # fmt: skip
    start = np.where(initial, deviation, np.nan)
    if np.any(initial) and (np.nanmin(start) < low or np.nanmax(start) > high):
        _mark_off_scale(ax, t, start, low, high)
    _mark_changes(ax, run, first)
    ax.set_ylabel(f"{'xy'[index]} deviation [mm]")
    clean_ticks(ax)


def _mark_off_scale(ax: Axes, t: np.ndarray, values: np.ndarray, low: float, high: float) -> None:
    """Mark the initial plan's extreme, clipped off the scale, by a triangle on the axes' edge, and write its value
    above the panel (inside it, the words would cover the replans' curves)."""
    extreme = int(np.nanargmax(np.abs(values)))
    below = values[extreme] < low
    ax.plot(t[extreme], low if below else high, marker="v" if below else "^", ms=8, color=ZMP_COLOR, mec="black",
            mew=0.6, clip_on=False, zorder=6, gid="deviation-off-scale")  # fmt: skip
    arrow = "\N{BLACK DOWN-POINTING TRIANGLE}" if below else "\N{BLACK UP-POINTING TRIANGLE}"
    ax.set_title(f"initial plan off scale ({arrow}): {signed_mm(values[extreme] / 1000.0)} at {t[extreme]:.2f} s",
                 loc="right", fontsize=9, color=ZMP_COLOR)  # fmt: skip


def draw_zmp_deviation(run: PlanRun, info: FigureInfo) -> Figure:
    """``zmp - zmp_ref`` (mm) along x and y during the free first segment of each plan, where it can differ.

    Outside those windows the planned ZMP is the footsteps' reference by construction, so only the windows are
    drawn (shaded); the deviation is what absorbs a changed step. Each panel is scaled on the replans' deviation
    (at least :data:`MIN_DEVIATION_SPAN` mm); the initial plan's start from rest is drawn dashed, clipped where it
    leaves that scale, and its extreme written at the edge.
    """
    figure = new_figure(11, 6.5)
    axes = figure.subplots(2, 1, sharex=True)
    for index, ax in enumerate(axes):
        _deviation_panel(ax, run, index, index == 0)
    _finish_time_panels(figure, axes, run.times, f"{info.title}: ZMP deviation in the free first segments",
                        legend_columns=3)  # fmt: skip
    return figure
