"""The paper's Fig. 1 from a walk with obstacles: a top view per connection mode of the footsteps planned before the
obstacle was seen, the obstacle, the changed footsteps, and the COG and ZMP paths.

Positions in m (equal aspect); the smallest ZMP margin of each walk is marked as in the plan's top view (green dot
inside, red cross outside) and given in mm in the panel's title.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.obstacle.walk import ObstacleRun
from rtgait.viz.figure_files import OBSTACLE_FIGURE
from rtgait.viz.style import COG_COLOR, SIDE_COLORS, ZMP_COLOR, clean_ticks, new_figure, save

__all__ = ["OBSTACLE_FIGURE", "draw_obstacle_walks", "plot_obstacle_walks", "verdict"]

_MOVED = 1e-3  # m: a footprint moved by more than this is drawn as changed


def verdict(run: ObstacleRun) -> str:
    """One line: what the walk did with its obstacles and whether its planned ZMP stayed inside the soles."""
    margin = run.rollout.zmp_margin_min
    parts = []
    for avoidance in run.avoidances:
        chosen = avoidance.chosen
        if chosen is None:
            parts.append(f"no detour at {avoidance.time:.2f} s (walks into it)")
        elif chosen.side == "none":
            parts.append("already clear")
        else:
            parts.append(f"steps {chosen.side} from step {avoidance.first_open} (seen {avoidance.time:.2f} s)")
    inside = "ZMP inside" if margin >= 0.0 else "ZMP LEAVES the support polygon"
    return f"{'; '.join(parts)}; {inside}: min margin {margin * 1e3:+.1f} mm"


def _soles(ax, sole: SoleRect, feet: Sequence[Footstep], moved: Sequence[bool], label_moved: bool) -> None:
    for foot, was_moved in zip(feet, moved, strict=True):
        colour = SIDE_COLORS[foot.side]
        ax.add_patch(Polygon(sole.corners(foot), closed=True, facecolor=colour, alpha=0.4 if was_moved else 0.15,
                             edgecolor="black" if was_moved else colour, lw=1.4 if was_moved else 0.8,
                             hatch="///" if was_moved else None))  # fmt: skip
    if label_moved:
        ax.add_patch(Polygon(np.zeros((3, 2)), facecolor="0.6", alpha=0.4, hatch="///", edgecolor="black",
                             label="footstep changed on seeing it"))  # fmt: skip


def draw_obstacle_walks(runs: Sequence[ObstacleRun], sole: SoleRect, title: str) -> Figure:
    """One top-view panel per run (module docstring)."""
    figure = new_figure(11, 3.2 * len(runs) + 1.2)
    axes = figure.subplots(len(runs), 1, sharex=True, squeeze=False)[:, 0]
    for ax, run in zip(axes, runs, strict=True):
        walked = run.rollout.footprints
        before = run.avoidances[0].before if run.avoidances else tuple(walked)
        offset = len(walked) - len(before)
        moved = [offset + i >= 0 and np.hypot(f.x - before[i].x, f.y - before[i].y) > _MOVED
                 for i, f in enumerate(walked[-len(before):])]  # fmt: skip
        moved = [False] * (len(walked) - len(moved)) + moved
        _soles(ax, sole, walked, moved, any(moved))
        for foot, was_moved in zip(before, moved[-len(before) :], strict=True):
            if was_moved:
                ax.add_patch(Polygon(sole.corners(foot), closed=True, fill=False, ls="--", edgecolor="0.35", lw=0.9))
        ax.plot([], [], ls="--", color="0.35", label="planned before the obstacle was seen")
        for k, avoidance in enumerate(run.avoidances):
            box = avoidance.obstacle
            ax.add_patch(Polygon(box.corners(), closed=True, facecolor="0.25", edgecolor="black", alpha=0.8,
                                 label="obstacle" if k == 0 else None))  # fmt: skip
            seen = int(np.searchsorted(run.rollout.times, avoidance.time))
            cog = run.rollout.values[seen, :2]
            ax.plot(*cog, marker="*", ms=14, color="gold", mec="black", zorder=6,
                    label="COG when the obstacle is seen" if k == 0 else None)  # fmt: skip
            ax.annotate(f"seen {avoidance.time:.2f} s", cog, xytext=(0, -16), textcoords="offset points", ha="center",
                        fontsize=8)  # fmt: skip
        cog = np.stack([run.rollout.column("cog_x"), run.rollout.column("cog_y")], axis=1)
        zmp = np.stack([run.rollout.column("zmp_x"), run.rollout.column("zmp_y")], axis=1)
        ax.plot(cog[:, 0], cog[:, 1], color=COG_COLOR, lw=1.5, label="COG")
        ax.plot(zmp[:, 0], zmp[:, 1], color=ZMP_COLOR, lw=1.1, label="ZMP (planned)")
        worst = run.rollout.worst_index
        inside = run.rollout.zmp_margin_min >= 0.0
        ax.plot(*zmp[worst], marker="o" if inside else "X", ms=10, color="tab:green" if inside else "red",
                mec="black", zorder=5, label="smallest ZMP margin")  # fmt: skip
        ax.set_aspect("equal", adjustable="datalim")
        ax.autoscale_view()
        ax.set_ylabel("y [m]")
        ax.grid(True, alpha=0.3)
        clean_ticks(ax)
        ax.set_title(f"{run.connection}: {verdict(run)}", fontsize=10)
    axes[-1].set_xlabel("x [m]")
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    figure.suptitle(f"{title}: footsteps changed in real time around an obstacle (top view)")
    return figure


def plot_obstacle_walks(runs: Sequence[ObstacleRun], sole: SoleRect, title: str, path: Path) -> Path:
    """Write :func:`draw_obstacle_walks` to ``path`` (its suffix picks the format)."""
    return save(draw_obstacle_walks(runs, sole, title), path)
