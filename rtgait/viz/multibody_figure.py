"""The robot's multibody ZMP against the planned one (mm, against time in s), before and after the angular-momentum
compensation: the paper's Fig. 11 (matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rtgait.viz.plan_marks import RunLike, _as_run, _finish_time_panels, _mark_changes, _shade_double_support
from rtgait.viz.run_data import FigureInfo
from rtgait.viz.style import (
    COG_COLOR,
    ZMP_COLOR,
    clean_ticks,
    new_figure,
    save,
)

__all__ = ["plot_multibody_zmp"]


def plot_multibody_zmp(
    rollout: RunLike,
    info: FigureInfo,
    path: Path,
    multibody_zmp: np.ndarray,
    compensated_zmp: np.ndarray | None = None,
    robot: str = "robot",
) -> Path:
    """Multibody ZMP of the robot's whole-body motion minus the planned ZMP (mm), along x and y against time,
    before and, when given, after the angular-momentum compensation (the paper's Fig. 11)."""
    run = _as_run(rollout)
    figure = new_figure(11, 6.5)
    axes = figure.subplots(2, 1, sharex=True)
    t = run.times
    for index, (ax, axis) in enumerate(zip(axes, "xy", strict=True)):
        planned = run.zmp[:, index]
        before = multibody_zmp[:, index] - planned
        ax.plot(t, before * 1000, color=COG_COLOR, lw=1.3, zorder=2,
                label=f"{axis}: without compensation (max {np.abs(before).max() * 1000:.1f} mm)")  # fmt: skip
        if compensated_zmp is not None:
            after = compensated_zmp[:, index] - planned
            label = f"{axis}: with angular-momentum compensation (max {np.abs(after).max() * 1000:.1f} mm)"
            ax.plot(t, after * 1000, color=ZMP_COLOR, lw=1.3, zorder=3, label=label)
        ax.axhline(0.0, color="black", lw=0.8, zorder=1)
        _shade_double_support(ax, run, label=index == 0)
        _mark_changes(ax, run, index == 0)
        ax.set_ylabel(f"{axis} error [mm]")
        clean_ticks(ax)
        ax.legend(loc="upper right", fontsize=8)
    _finish_time_panels(
        figure, axes, t, f"{info.title}: multibody ZMP minus planned ZMP ({robot})", legend_columns=3, legend=False
    )
    return save(figure, path)
