"""The figure of a pendulum-level closed-loop run (``rtgait simulate --model lipm``): ``pendulum.png`` (or .pdf, .svg).

Per horizontal axis, against time from the walk's start: the planned ZMP, the ZMP the controller commanded and the
one the feet produced, the plan's DCM and the point mass's, with the double supports and the pushes shaded, step
adjustments and a fall marked. A third panel shows the DCM error, the quantity the feedback law drives to zero.
Drawn from a :class:`PendulumRun`: the run in memory (:meth:`PendulumRun.from_result`) or read back from its files
(:func:`read_pendulum_run`, for ``rtgait plot``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from rtgait.core.geometry.support import SUPPORT_NAMES
from rtgait.core.pendulum.loop import ClosedLoopResult
from rtgait.core.push import Push
from rtgait.viz.run_files import SIM_CSV, SUMMARY, RunFilesError, read_floats, read_summary, read_table, require_keys
from rtgait.viz.style import (
    COG_COLOR,
    DOUBLE_COLOR,
    PUSH_COLOR,
    TIME_LABEL,
    ZMP_COLOR,
    clean_ticks,
    new_figure,
    runs,
    save,
    span_limits,
)

__all__ = ["MIN_ERROR_SPAN", "PendulumRun", "draw_pendulum", "plot_pendulum", "read_pendulum_run"]

MIN_ERROR_SPAN = 4.0
"""Smallest span (mm) of the DCM error panel: a run tracked to a few micrometres shows as the flat line it is."""

_REAL_COLOR = "tab:orange"
_PLANNED_DCM_COLOR = "tab:green"
_ADJUST_COLOR = "tab:brown"


@dataclass(frozen=True, eq=False)
class PendulumRun:
    """Every tick of a closed-loop run on the point-mass pendulum, as ``pendulum.png`` draws it (SI units).

    Attributes:
        times: tick times (s) from the walk's start, ``(k,)``.
        zmp_planned, zmp_command, zmp_real: the plan's ZMP, the controller's and the one the feet produced (m),
            ``(k, 2)``; the last two NaN on the tick the mass was found fallen.
        dcm_planned, dcm: the plan's DCM and the point mass's (m), ``(k, 2)``.
        support: ``"double"``, ``"left"`` or ``"right"`` per tick (the planned support).
        pushes: the pushes on the mass.
        step_adjustments: when the planner moved a landing (s).
        controller: the controller level run.
        mass: of the point mass (kg).
        fell, fall_time: whether and when (s) it fell.
        ended_at_rest: not fallen and at rest at the end.
        title: the figure title's prefix (scenario and connection mode), may be empty.
    """

    times: np.ndarray
    zmp_planned: np.ndarray
    zmp_command: np.ndarray
    zmp_real: np.ndarray
    dcm_planned: np.ndarray
    dcm: np.ndarray
    support: np.ndarray
    pushes: tuple[Push, ...]
    step_adjustments: tuple[float, ...]
    controller: str
    mass: float
    fell: bool
    fall_time: float | None
    ended_at_rest: bool
    title: str = ""

    @classmethod
    def from_result(cls, result: ClosedLoopResult, title: str = "") -> PendulumRun:
        """The record of a closed-loop run in memory."""
        names = np.array(SUPPORT_NAMES, dtype=object)
        return cls(
            times=result.times,
            zmp_planned=result.zmp_planned,
            zmp_command=result.zmp_command,
            zmp_real=result.zmp_real,
            dcm_planned=result.dcm_planned,
            dcm=result.dcm,
            support=names[np.asarray(result.support, dtype=int)].astype(str),
            pushes=tuple(result.pushes),
            step_adjustments=tuple(float(decision.t) for decision in result.step_adjustments),
            controller=result.controller,
            mass=float(result.mass),
            fell=bool(result.fell),
            fall_time=None if result.fall_time is None else float(result.fall_time),
            ended_at_rest=bool(result.ended_at_rest),
            title=title,
        )


def read_pendulum_run(folder: Path) -> tuple[PendulumRun, dict[str, Any]]:
    """The pendulum run in ``folder`` (``sim.csv`` and ``summary.json`` of ``rtgait simulate --model lipm``).

    Raises:
        RunFilesError: a file is missing, unreadable or not what ``simulate --model lipm`` writes.
    """
    folder = Path(folder)
    summary = read_summary(folder)
    require_keys(summary, ("model", "controller", "mass", "fell", "fall_time", "ended_at_rest", "pushes"), folder,
             "a pendulum (simulate --model lipm)")  # fmt: skip
    path = folder / SIM_CSV
    if not path.is_file():
        raise RunFilesError(f"{path} is missing: {folder} does not hold a finished simulate --model lipm run")
    pairs = ("zmp_planned", "zmp_command", "zmp_real", "dcm_planned", "dcm")
    names = ["t", *(f"{pair}_{axis}" for pair in pairs for axis in "xy")]
    columns = read_table(path, (*names, "support"))
    values = read_floats(columns, names, path)
    try:
        pushes = tuple(Push(float(p["start"]), float(p["duration"]), tuple(p["force"])) for p in summary["pushes"])
        adjustments = tuple(float(entry["t"]) for entry in summary.get("step_adjustment_log", []))
        fall_time = summary["fall_time"]
        scenario = summary.get("scenario")
        run = PendulumRun(
            times=values[:, 0],
            **{pair: values[:, 1 + 2 * i : 3 + 2 * i] for i, pair in enumerate(pairs)},
            support=columns["support"].astype(str),
            pushes=pushes,
            step_adjustments=adjustments,
            controller=str(summary["controller"]),
            mass=float(summary["mass"]),
            fell=bool(summary["fell"]),
            fall_time=None if fall_time is None else float(fall_time),
            ended_at_rest=bool(summary["ended_at_rest"]),
            title="" if scenario is None else f"{scenario} ({summary.get('connection', '?')})",
        )
    except (KeyError, TypeError, ValueError) as error:
        raise RunFilesError(f"{folder / SUMMARY} is not what simulate --model lipm writes ({error})") from None
    return run, summary


def _legend_extras(run: PendulumRun) -> tuple[list[object], list[str]]:
    """Legend entries for what is not a line of the x panel: the shadings and the vertical markers."""
    handles: list[object] = [Rectangle((0, 0), 1, 1, color=DOUBLE_COLOR, alpha=0.6, lw=0)]
    labels = ["double support (both feet on the ground)"]
    if run.pushes:
        handles.append(Rectangle((0, 0), 1, 1, color=PUSH_COLOR, alpha=0.35, lw=0))
        impulses = ", ".join(f"{push.impulse_norm:.1f} N s at {push.start:.2f} s" for push in run.pushes)
        labels.append(f"push on the mass ({impulses})")
    if run.step_adjustments:
        handles.append(Line2D([], [], color=_ADJUST_COLOR, lw=1.0, ls="-."))
        labels.append(f"step adjusted ({len(run.step_adjustments)})")
    if run.fall_time is not None:
        handles.append(Line2D([], [], color="black", lw=1.0, ls="--"))
        labels.append(f"fall ({run.fall_time:.2f} s)")
    return handles, labels


def draw_pendulum(run: PendulumRun) -> Figure:
    """The run's figure (see the module docstring)."""
    t = run.times
    figure = new_figure(11, 9.0)
    axes = figure.subplots(3, 1, sharex=True)
    for axis, (ax, name) in enumerate(zip(axes[:2], ("x (forward)", "y (lateral)"), strict=True)):
        ax.plot(t, run.zmp_planned[:, axis], color=ZMP_COLOR, lw=1.4, label="planned ZMP")
        ax.plot(t, run.zmp_real[:, axis], color=_REAL_COLOR, lw=1.0, label="ZMP the feet produced")
        ax.plot(t, run.zmp_command[:, axis], color=_REAL_COLOR, lw=0.8, ls=":", label="commanded ZMP")
        ax.plot(t, run.dcm_planned[:, axis], color=_PLANNED_DCM_COLOR, lw=1.0, ls="--", label="planned DCM")
        ax.plot(t, run.dcm[:, axis], color=COG_COLOR, lw=1.0, label="DCM of the mass")
        ax.set_ylabel(f"{name} [m]")
    error = np.hypot(*(run.dcm - run.dcm_planned).T) * 1e3
    axes[2].plot(t, error, color=COG_COLOR, lw=1.0)
    axes[2].set_ylim(*span_limits(error, MIN_ERROR_SPAN, include=0.0, pad=0.05))
    axes[2].set_ylabel("DCM error [mm]\n(mass vs plan)")
    axes[2].set_xlabel(TIME_LABEL)
    for ax in axes:
        for start, end in runs(run.support == "double", t):
            ax.axvspan(start, end, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0)
        for push in run.pushes:
            ax.axvspan(push.start, push.start + push.duration, color=PUSH_COLOR, alpha=0.35, lw=0, zorder=1)
        for when in run.step_adjustments:
            ax.axvline(when, color=_ADJUST_COLOR, lw=1.0, ls="-.", zorder=2)
        if run.fall_time is not None:
            ax.axvline(run.fall_time, color="black", lw=1.0, ls="--")
        ax.set_xlim(t[0], t[-1])
        ax.grid(alpha=0.3)
        clean_ticks(ax)
    handles, labels = axes[0].get_legend_handles_labels()
    extra_handles, extra_labels = _legend_extras(run)
    figure.legend([*handles, *extra_handles], [*labels, *extra_labels], loc="outside lower center", ncol=3,
                  fontsize=8)  # fmt: skip
    if run.fell:
        outcome = f"fell at {run.fall_time:.2f} s"
    else:
        outcome = "walked, ended at rest" if run.ended_at_rest else "walked, not at rest at the end"
    figure.suptitle(f"{run.title + ': ' if run.title else ''}{run.controller}, point mass {run.mass:g} kg, {outcome}")
    return figure


def plot_pendulum(result: ClosedLoopResult | PendulumRun, path: Path, title: str = "") -> Path:
    """Write the run's figure to ``path`` (the format follows the suffix: .png, .pdf, .svg); returns ``path``.

    ``title`` (scenario and connection mode) is the figure title's prefix for a result in memory; a
    :class:`PendulumRun` carries its own."""
    run = result if isinstance(result, PendulumRun) else PendulumRun.from_result(result, title)
    return save(draw_pendulum(run), path)
