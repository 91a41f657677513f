"""Figures of a rollout in the spirit of the paper's Figs. 4-9 (matplotlib, rendered off-screen with Agg).

Each ``plot_*`` function draws one PNG from a :class:`~rtgait.core.rollout.Rollout` and a :class:`FigureInfo`
(title, sole, the footprints as planned before any change) and returns the path written. The figures are built
with matplotlib's object API and the Agg canvas directly, so nothing touches pyplot's global state or needs a
display.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from rtgait.core.footsteps import Footstep, SoleRect
from rtgait.core.rollout import Rollout

__all__ = [
    "FIGURE_FILES",
    "FigureInfo",
    "plot_multibody_zmp",
    "plot_top_view",
    "plot_zmp_cog",
    "plot_zmp_deviation",
    "plot_zmp_margin",
    "render_all",
    "support_extents",
]

DPI = 100
FIGURE_FILES = ("zmp_cog.png", "zmp_deviation.png", "top_view.png", "zmp_margin.png")
"""File names written by :func:`render_all`, in order."""

# One colour per quantity across all figures, so a reader who learnt one figure can read the others.
ZMP_COLOR = "tab:blue"
REF_COLOR = "black"
COG_COLOR = "tab:red"
BAND_COLOR = "tab:green"
DOUBLE_COLOR = "0.85"
CHANGE_COLOR = "tab:purple"
SIDE_COLORS = {"left": "tab:blue", "right": "tab:orange"}
MOVED_TOLERANCE = 1e-3  # a footprint moved by more than this (m, or rad of yaw) counts as changed


@dataclass(frozen=True)
class FigureInfo:
    """What the figures need besides the rollout.

    Attributes:
        title: prefix of every figure title, e.g. ``"fig4 (real-time)"``.
        sole: sole rectangle around the foot frame (m), for support polygons and footprint outlines.
        nominal_footprints: footprints ``F[0..]`` as planned before any change; footprints that differ from
            them are highlighted in the top view. ``None``: nothing highlighted.
    """

    title: str
    sole: SoleRect
    nominal_footprints: Sequence[Footstep] | None = None


# ----- data helpers ---------------------------------------------------------------------------------------------


def support_extents(rollout: Rollout, sole: SoleRect) -> tuple[np.ndarray, np.ndarray]:
    """Per tick, the support polygon's lower and upper bounds along x and y, each shape ``(k, 2)`` (m)."""
    lower = np.empty((len(rollout.times), 2))
    upper = np.empty_like(lower)
    for q, polygon in rollout.polygons.items():
        mask = rollout.phase == q
        lower[mask] = polygon.min(axis=0)
        upper[mask] = polygon.max(axis=0)
    return lower, upper


def _runs(mask: np.ndarray, times: np.ndarray) -> list[tuple[float, float]]:
    """``(start, end)`` times (s) of each run of consecutive true ticks; a run ends where the next tick starts."""
    if not mask.any():
        return []
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)  # index one past the run
    dt = float(times[1] - times[0]) if len(times) > 1 else 0.0
    last = float(times[-1]) + dt
    return [(float(times[s]), float(times[e]) if e < len(times) else last) for s, e in zip(starts, ends, strict=True)]


def _moved(footprints: Sequence[Footstep], nominal: Sequence[Footstep] | None) -> list[bool]:
    if nominal is None or len(nominal) != len(footprints):
        return [False] * len(footprints)
    return [
        bool(np.hypot(a.x - b.x, a.y - b.y) > MOVED_TOLERANCE or abs(a.yaw - b.yaw) > MOVED_TOLERANCE)
        for a, b in zip(footprints, nominal, strict=True)
    ]


# ----- drawing helpers ------------------------------------------------------------------------------------------


def _new_figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), dpi=DPI, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _save(figure: Figure, path: Path) -> Path:
    path = Path(path)
    figure.savefig(path, dpi=DPI)
    return path


def _shade_double_support(ax: Axes, rollout: Rollout, label: bool) -> None:
    for k, (t0, t1) in enumerate(_runs(rollout.support == "double", rollout.times)):
        text = "double support" if label and k == 0 else None
        ax.axvspan(t0, t1, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0, label=text)


def _mark_changes(ax: Axes, rollout: Rollout, label: bool) -> None:
    for k, (t, step) in enumerate(rollout.changes):
        text = "change decided" if label and k == 0 else None
        ax.axvline(t, color=CHANGE_COLOR, ls=":", lw=1.8, zorder=3, label=text)
        # The step number on the marker links the time plot to the footprint numbers of the top view.
        ax.annotate(
            f"step {step}",
            (t, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(3, -3),
            textcoords="offset points",
            va="top",
            fontsize=8,
            color=CHANGE_COLOR,
        )


def _mark_outside(ax: Axes, rollout: Rollout, values: np.ndarray, label: bool) -> None:
    outside = rollout.margin < 0.0
    if outside.any():
        ax.plot(
            rollout.times[outside],
            values[outside],
            ls="none",
            marker=".",
            ms=3,
            color="red",
            zorder=4,
            label="ZMP outside support polygon" if label else None,
        )


# ----- the figures ----------------------------------------------------------------------------------------------


def plot_zmp_cog(rollout: Rollout, info: FigureInfo, path: Path) -> Path:
    """ZMP (planned and reference) and COG along x and y against time, with the support polygon's extent.

    The band is the support polygon's extent along each axis (m): a ZMP outside the band is outside the
    polygon; red dots mark every tick where the ZMP is outside the polygon in the plane.
    """
    lower, upper = support_extents(rollout, info.sole)
    figure = _new_figure(11, 7.5)
    axes = figure.subplots(2, 1, sharex=True)
    t = rollout.times
    for index, (ax, axis) in enumerate(zip(axes, "xy", strict=True)):
        first = index == 0
        _shade_double_support(ax, rollout, first)
        ax.fill_between(
            t, lower[:, index], upper[:, index], color=BAND_COLOR, alpha=0.18, lw=0, zorder=1,
            label="support polygon extent" if first else None,
        )  # fmt: skip
        zmp = rollout.column(f"zmp_{axis}")
        ax.plot(t, rollout.column(f"cog_{axis}"), color=COG_COLOR, lw=1.6, zorder=3, label="COG" if first else None)
        ax.plot(t, zmp, color=ZMP_COLOR, lw=1.6, zorder=3, label="ZMP (planned)" if first else None)
        ax.plot(
            t, rollout.column(f"zmp_ref_{axis}"), color=REF_COLOR, ls="--", lw=1.0, zorder=3,
            label="ZMP reference (footsteps only)" if first else None,
        )  # fmt: skip
        _mark_outside(ax, rollout, zmp, first)
        _mark_changes(ax, rollout, first)
        ax.set_ylabel(f"{axis} [m]")
    _finish_time_panels(figure, axes, t, f"{info.title}: ZMP and COG", legend_columns=4)
    return _save(figure, path)


def _finish_time_panels(
    figure: Figure, axes: Sequence[Axes], t: np.ndarray, title: str, legend_columns: int, legend: bool = True
) -> None:
    """Grid, time range and labels shared by the x-over-y panels against time."""
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.set_xlim(t[0], t[-1])
    axes[-1].set_xlabel("time [s]")
    axes[0].set_title("sagittal (x)", fontsize=10, loc="left")
    axes[1].set_title("lateral (y)", fontsize=10, loc="left")
    figure.suptitle(title)
    if legend:
        figure.legend(loc="outside lower center", ncol=legend_columns, fontsize=9)


def plot_zmp_deviation(rollout: Rollout, info: FigureInfo, path: Path) -> Path:
    """``zmp - zmp_ref`` (m) along x and y during the free first segment of each plan, where it can differ.

    Outside those windows the planned ZMP is the footsteps' reference by construction, so only the windows
    are drawn (shaded); the deviation is what absorbs a changed step.
    """
    free = rollout.free_segment_mask(rollout.plans)
    # The initial plan starts from rest and always swings the ZMP away from its reference first (the
    # anticipatory shift that starts the COG moving); the maximum worth reporting is that of the connections.
    connecting = rollout.free_segment_mask()
    windows = _runs(free, rollout.times)
    figure = _new_figure(11, 6.5)
    axes = figure.subplots(2, 1, sharex=True)
    t = rollout.times
    for index, (ax, axis) in enumerate(zip(axes, "xy", strict=True)):
        first = index == 0
        deviation = rollout.column(f"zmp_{axis}") - rollout.column(f"zmp_ref_{axis}")
        for k, (t0, t1) in enumerate(windows):
            ax.axvspan(t0, t1, color=DOUBLE_COLOR, alpha=0.6, lw=0, zorder=0,
                       label="free first segment of a plan" if first and k == 0 else None)  # fmt: skip
        # NaN outside the windows breaks the line there instead of drawing zeros that were never free.
        initial = free & ~connecting
        ax.plot(t, np.where(connecting, deviation, np.nan), color=ZMP_COLOR, lw=1.6, zorder=3,
                label="ZMP - ZMP reference, replans" if first else None)  # fmt: skip
        ax.plot(t, np.where(initial, deviation, np.nan), color=ZMP_COLOR, lw=1.2, ls="--", alpha=0.7, zorder=3,
                label="ZMP - ZMP reference, initial plan (start from rest)" if first else None)  # fmt: skip
        ax.axhline(0.0, color="black", lw=0.8, zorder=2)
        if connecting.any():
            worst = int(np.argmax(np.where(connecting, np.abs(deviation), -1.0)))
            ax.plot(t[worst], deviation[worst], "o", color="red", ms=5, zorder=4,
                    label="largest deviation of a replan" if first else None)  # fmt: skip
            ax.annotate(
                f"{deviation[worst] * 1000:+.1f} mm at {t[worst]:.2f} s",
                (t[worst], deviation[worst]),
                xytext=(8, 0),
                textcoords="offset points",
                fontsize=8,
                color="red",
                va="center",
            )
        _mark_changes(ax, rollout, first)
        ax.set_ylabel(f"{axis} deviation [m]")
    _finish_time_panels(figure, axes, t, f"{info.title}: ZMP deviation in the connecting segments", legend_columns=3)
    return _save(figure, path)


def plot_top_view(rollout: Rollout, info: FigureInfo, path: Path) -> Path:
    """Top view (m, equal aspect): soles of all footprints, ZMP and COG paths, and the worst ZMP margin."""
    prints = rollout.footprints
    corners = np.concatenate([info.sole.corners(foot) for foot in prints])
    span = np.ptp(corners, axis=0) + 0.1
    # Size the figure to the walk's shape: a fixed box would leave a straight walk as a thin strip in a sea
    # of empty axes. About 9.5 in of plot width, the height following the aspect, within readable bounds.
    plot_height = float(np.clip(9.5 * span[1] / span[0], 2.5, 8.0))
    figure = _new_figure(11, plot_height + 2.3)
    ax = figure.add_subplot()
    moved = _moved(prints, info.nominal_footprints)
    seen: set[str] = set()
    for index, (foot, was_moved) in enumerate(zip(prints, moved, strict=True)):
        key = f"{foot.side} foot" + (" (moved by a change)" if was_moved else "")
        ax.add_patch(
            Polygon(
                info.sole.corners(foot),
                closed=True,
                facecolor=SIDE_COLORS[foot.side],
                alpha=0.35 if was_moved else 0.18,
                edgecolor="black" if was_moved else SIDE_COLORS[foot.side],
                lw=1.6 if was_moved else 1.0,
                hatch="///" if was_moved else None,
                label=None if key in seen else key,
            )
        )
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
    ax.plot(rollout.column("cog_x"), rollout.column("cog_y"), color=COG_COLOR, lw=1.5, label="COG")
    ax.plot(rollout.column("zmp_x"), rollout.column("zmp_y"), color=ZMP_COLOR, lw=1.3, label="ZMP (planned)")
    worst = rollout.worst_index
    margin = rollout.zmp_margin_min
    colour = "red" if margin < 0.0 else "tab:green"
    point = (rollout.column("zmp_x")[worst], rollout.column("zmp_y")[worst])
    polygon = rollout.polygons[int(rollout.phase[worst])]
    ax.add_patch(Polygon(polygon, closed=True, fill=False, edgecolor=colour, lw=1.4, ls="-.",
                         label="support polygon at the worst instant"))  # fmt: skip
    verdict = "OUTSIDE" if margin < 0.0 else "inside"
    ax.plot(*point, marker="X" if margin < 0.0 else "o", ms=11, color=colour, mec="black", zorder=5,
            label=f"min ZMP margin {margin * 1000:+.1f} mm ({verdict}) at {rollout.times[worst]:.2f} s")  # fmt: skip
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{info.title}: footprints, ZMP and COG (top view; numbers = step landing there)")
    figure.legend(loc="outside lower center", ncol=3, fontsize=8)
    return _save(figure, path)


def plot_zmp_margin(rollout: Rollout, info: FigureInfo, path: Path) -> Path:
    """Signed ZMP margin to the support polygon (m, positive inside) against time."""
    figure = _new_figure(11, 4.5)
    ax = figure.add_subplot()
    t = rollout.times
    _shade_double_support(ax, rollout, True)
    ax.plot(t, rollout.margin, color=ZMP_COLOR, lw=1.5, label="ZMP margin")
    ax.fill_between(t, rollout.margin, 0.0, where=rollout.margin < 0.0, color="red", alpha=0.35, lw=0,
                    label="outside the support polygon")  # fmt: skip
    ax.axhline(0.0, color="black", lw=1.0)
    worst = rollout.worst_index
    margin = rollout.zmp_margin_min
    colour = "red" if margin < 0.0 else "tab:green"
    ax.plot(t[worst], margin, "o", color=colour, mec="black", ms=7, zorder=5)
    ax.annotate(
        f"min {margin * 1000:+.1f} mm at {t[worst]:.2f} s",
        (t[worst], margin),
        xytext=(10, -4),
        textcoords="offset points",
        fontsize=9,
        color=colour,
        va="top",
    )
    _mark_changes(ax, rollout, True)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time [s]")
    ax.set_ylabel("margin [m] (> 0 inside)")
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{info.title}: signed ZMP margin to the support polygon")
    ax.legend(loc="lower right", fontsize=8)
    return _save(figure, path)


def plot_multibody_zmp(
    rollout: Rollout,
    info: FigureInfo,
    path: Path,
    multibody_zmp: np.ndarray,
    compensated_zmp: np.ndarray | None = None,
    robot: str = "robot",
) -> Path:
    """Multibody ZMP of the robot's whole-body motion minus the planned ZMP (m), along x and y against time,
    before and, when given, after the angular-momentum compensation (the paper's Fig. 11)."""
    figure = _new_figure(11, 6.5)
    axes = figure.subplots(2, 1, sharex=True)
    t = rollout.times
    for index, (ax, axis) in enumerate(zip(axes, "xy", strict=True)):
        planned = rollout.column(f"zmp_{axis}")
        before = multibody_zmp[:, index] - planned
        ax.plot(t, before * 1000, color=COG_COLOR, lw=1.3, zorder=2,
                label=f"{axis}: without compensation (max {np.abs(before).max() * 1000:.1f} mm)")  # fmt: skip
        if compensated_zmp is not None:
            after = compensated_zmp[:, index] - planned
            label = f"{axis}: with angular-momentum compensation (max {np.abs(after).max() * 1000:.1f} mm)"
            ax.plot(t, after * 1000, color=ZMP_COLOR, lw=1.3, zorder=3, label=label)
        ax.axhline(0.0, color="black", lw=0.8, zorder=1)
        _shade_double_support(ax, rollout, label=False)
        _mark_changes(ax, rollout, index == 0)
        ax.set_ylabel(f"{axis} error [mm]")
        ax.legend(loc="upper right", fontsize=8)
    _finish_time_panels(
        figure, axes, t, f"{info.title}: multibody ZMP minus planned ZMP ({robot})", legend_columns=3, legend=False
    )
    return _save(figure, path)


def render_all(rollout: Rollout, info: FigureInfo, folder: Path) -> list[Path]:
    """Write the four figures (:data:`FIGURE_FILES`) into ``folder``; returns their paths."""
    folder = Path(folder)
    plots = (plot_zmp_cog, plot_zmp_deviation, plot_top_view, plot_zmp_margin)
    return [plot(rollout, info, folder / name) for plot, name in zip(plots, FIGURE_FILES, strict=True)]
