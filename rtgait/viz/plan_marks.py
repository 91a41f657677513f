"""The marks the figures of a planned walk share (matplotlib): double supports shaded, footstep changes and a ZMP
outside the support polygon marked, the time panels' grid and labels (time in s), the minimum margin's caption (mm).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from rtgait.core.analysis.rollout import Rollout
from rtgait.viz.run_data import PlanRun
from rtgait.viz.style import (
    CHANGE_COLOR,
    DOUBLE_COLOR,
    TIME_LABEL,
    runs,
    signed_mm,
)

__all__ = ["RunLike"]  # the rest are the figures' own helpers

RunLike = Rollout | PlanRun


def _as_run(run: RunLike) -> PlanRun:
    return run if isinstance(run, PlanRun) else PlanRun.from_rollout(run)


def _shade_double_support(ax: Axes, run: PlanRun, label: bool) -> None:
    for k, (t0, t1) in enumerate(runs(run.support == "double", run.times)):
        text = "double support (both feet on the ground)" if label and k == 0 else None
        ax.axvspan(t0, t1, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0, label=text)


def _mark_changes(ax: Axes, run: PlanRun, label: bool) -> None:
    for k, (t, step) in enumerate(run.changes):
        text = "footstep change decided" if label and k == 0 else None
        ax.axvline(t, color=CHANGE_COLOR, ls=":", lw=1.8, zorder=3, label=text)
        # The step number on the marker links the time plot to the footprint numbers of the top view.
        ax.annotate(f"step {step}", (t, 1.0), xycoords=("data", "axes fraction"), xytext=(3, -3),
                    textcoords="offset points", va="top", fontsize=8, color=CHANGE_COLOR)  # fmt: skip


def _mark_outside(ax: Axes, run: PlanRun, values: np.ndarray, label: bool) -> None:
    outside = run.margin < 0.0
    if outside.any():
        ax.plot(run.times[outside], values[outside], ls="none", marker=".", ms=3, color="red", zorder=4,
                label="ZMP outside the support polygon" if label else None)  # fmt: skip


def _finish_time_panels(
    figure: Figure, axes: Sequence[Axes], t: np.ndarray, title: str, legend_columns: int, legend: bool = True
) -> None:
    """Grid, time range and labels shared by the x-over-y panels against time."""
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.set_xlim(t[0], t[-1])
    axes[-1].set_xlabel(TIME_LABEL)
    axes[0].set_title("sagittal (x)", fontsize=10, loc="left")
    axes[1].set_title("lateral (y)", fontsize=10, loc="left")
    figure.suptitle(title)
    if legend:
        figure.legend(loc="outside lower center", ncol=legend_columns, fontsize=9)


def _margin_caption(run: PlanRun) -> str:
    """What the minimum-margin marker shows: the value, inside or out, when, and whether the minimum is tied."""
    marker = run.marker
    margin = run.zmp_margin_min
    verdict = "OUTSIDE" if margin < 0.0 else "inside"
    text = f"min ZMP margin {signed_mm(margin)} ({verdict}) at {run.times[marker.index]:.2f} s"
    if marker.tied > 1:
        text += f"\n(reached for {marker.tied_duration:.2f} s in all; marked: the {marker.reason})"
    return text
