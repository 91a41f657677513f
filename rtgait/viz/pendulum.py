"""The figure of a pendulum-level closed-loop run (``rtgait simulate --model lipm``): ``pendulum.png``.

Per horizontal axis, against time: the planned ZMP, the ZMP the controller commanded and the one the feet produced,
the plan's DCM and the point mass's, with the pushes shaded and a fall marked. A third panel shows the DCM error,
the quantity the feedback law drives to zero.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from rtgait.core.closed_loop import ClosedLoopResult


def plot_pendulum(result: ClosedLoopResult, path: Path, title: str = "") -> None:
    """Write the run's figure to ``path`` (the format follows the suffix: .png, .pdf, .svg)."""
    t = result.times
    # No pyplot: a Figure of its own, so no global state and no GUI backend (as in rtgait.viz.figures).
    fig = Figure(figsize=(10, 8.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 1, sharex=True)
    for axis, (ax, name) in enumerate(zip(axes[:2], ("x (forward)", "y (lateral)"), strict=True)):
        ax.plot(t, result.zmp_planned[:, axis], color="tab:blue", lw=1.2, label="planned ZMP")
        ax.plot(t, result.zmp_real[:, axis], color="tab:orange", lw=1.0, label="ZMP the feet produced")
        ax.plot(t, result.zmp_command[:, axis], color="tab:orange", lw=0.8, ls=":", label="commanded ZMP")
        ax.plot(t, result.dcm_planned[:, axis], color="tab:green", lw=1.0, ls="--", label="planned DCM")
        ax.plot(t, result.dcm[:, axis], color="tab:red", lw=1.0, label="DCM of the mass")
        ax.set_ylabel(f"{name} [m]")
    error = np.hypot(*(result.dcm - result.dcm_planned).T) * 1e3
    axes[2].plot(t, error, color="tab:red", lw=1.0)
    axes[2].set_ylabel("DCM error [mm]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        for push in result.pushes:
            ax.axvspan(push.start, push.start + push.duration, color="tab:purple", alpha=0.2, lw=0)
        if result.fall_time is not None:
            ax.axvline(result.fall_time, color="black", lw=1.0, ls="--")
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    if result.pushes:
        handles.append(Rectangle((0, 0), 1, 1, color="tab:purple", alpha=0.2))
        labels.append("push")
    if result.fall_time is not None:
        handles.append(Line2D([], [], color="black", lw=1.0, ls="--"))
        labels.append(f"fall ({result.fall_time:.2f} s)")
    axes[0].legend(handles, labels, loc="upper left", fontsize=8, ncol=3)
    if result.fell:
        outcome = f"fell at {result.fall_time:.2f} s"
    else:
        outcome = "walked, ended at rest" if result.ended_at_rest else "walked, not at rest at the end"
    fig.suptitle(f"{title + ': ' if title else ''}{result.controller}, point mass {result.mass:g} kg, {outcome}")
    fig.savefig(path, dpi=110)
