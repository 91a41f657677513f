"""The figure of a walk in physics: ``zmp_sim.png`` (or ``.pdf``, ``.svg``), planned and measured ZMP against time.

In the style of every rtgait figure (:mod:`rtgait.viz.style`): time on the walk's clock (t = 0 when the planner
starts; the start transition from half-sitting at negative times, shaded), units in square brackets, the planned
double supports shaded, pushes and the tip-over and fall marked.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rtgait.viz.style import (
    COG_COLOR,
    DOUBLE_COLOR,
    DPI,
    PUSH_COLOR,
    REF_COLOR,
    TIME_LABEL,
    ZMP_COLOR,
    clean_ticks,
    new_figure,
    runs,
    save,
)

if TYPE_CHECKING:
    from rtgait.sim.result import SimResult

__all__ = ["ZMP_SIM_FIGURE", "plot_zmp_sim"]

ZMP_SIM_FIGURE = "zmp_sim"
"""File stem of the figure."""

_TRANSITION_COLOR = "#e8eef7"  # a pale blue: the start transition, unlike the grey double supports


def plot_zmp_sim(result: SimResult, path: str | Path, title: str = "", fmt: str | None = None) -> Path:
    """Planned, commanded and measured ZMP and the measured COG, x and y against the walk's clock, written to
    ``path`` in the format ``fmt`` (``png``, ``pdf``, ``svg``; default the one its suffix names); returns the path."""
    import matplotlib
    from matplotlib.patches import Patch

    figure = new_figure(10.0, 6.0)
    axes = figure.subplots(2, 1, sharex=True)
    t = result.times
    double = (result.support == 0) & (t >= 0.0)  # the start transition is shaded on its own
    closed = result.controller != "open-loop"
    for axis, ax in enumerate(axes):
        if t[0] < 0.0:
            ax.axvspan(t[0], 0.0, color=_TRANSITION_COLOR, lw=0, zorder=0)
        for start, end in runs(double, t):  # the measured ZMP moves between the feet there
            ax.axvspan(start, end, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0)
        for push in result.pushes:
            ax.axvspan(push.start, push.start + push.duration, color=PUSH_COLOR, alpha=0.35, lw=0, zorder=1)
        ax.plot(t, result.zmp_planned[:, axis], color=REF_COLOR, lw=1.2, label="planned ZMP")
        if closed:
            ax.plot(t, result.zmp_command[:, axis], color="tab:green", lw=0.8, label="commanded ZMP (feedback)")
        ax.plot(t, result.zmp[:, axis], color=ZMP_COLOR, lw=0.8, label="measured ZMP (contact CoP)")
        ax.plot(t, result.cog[:, axis], color=COG_COLOR, lw=0.8, ls="--", label="measured COG")
        if result.tip_time is not None:
            ax.axvline(result.tip_time, color="tab:purple", lw=1.2, ls="--", label=f"tipped ({result.tip_time:.2f} s)")
        if result.fell and result.fall_time is not None:
            ax.axvline(result.fall_time, color="tab:red", lw=1.6, label=f"fell ({result.fall_time:.2f} s)")
        ax.set_ylabel(f"{'xy'[axis]} [m]")
        ax.grid(True, lw=0.3)
        ax.set_xlim(float(t[0]), float(t[-1]))
        clean_ticks(ax)
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [Patch(color=DOUBLE_COLOR, alpha=0.6, lw=0), Patch(color=_TRANSITION_COLOR, lw=0)]
    labels += ["double support (planned)", "start transition"]
    if result.pushes:
        handles.append(Patch(color=PUSH_COLOR, alpha=0.35, lw=0))
        labels.append("push")
    axes[0].legend(handles, labels, loc="upper left", fontsize=8, ncols=3)
    axes[1].set_xlabel(TIME_LABEL)
    outcome = (
        f"fell at {result.fall_time:.2f} s ({result.fall_cause})"
        if result.fell
        else f"walked {result.steps_completed}/{result.steps_planned} steps"
    )
    if result.tip_time is not None:
        outcome += f", a foot tipped over at {result.tip_time:.2f} s"
    rms = result.zmp_tracking_error_rms
    if np.isfinite(rms):
        outcome += f"; ZMP {rms * 1e3:.0f} mm RMS from the plan"
    head = f"{title}: " if title else ""
    axes[0].set_title(f"{head}{result.robot} in MuJoCo, {result.controller}\n{outcome}", fontsize=10)
    path = Path(path)
    if fmt is None or path.suffix.lstrip(".").lower() == fmt:
        return save(figure, path)
    # A temporary name of another suffix (rtgait.outputs.write_atomic): save's choices, with the format given.
    metadata = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
    with matplotlib.rc_context({"svg.hashsalt": "rtgait"}):
        figure.savefig(path, dpi=DPI, format=fmt, metadata=metadata)
    return path
