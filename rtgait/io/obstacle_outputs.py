"""What ``rtgait plan`` writes and prints for a scenario with obstacles: each connection mode's walk around them
(the summary's ``obstacle_walks``), the figure like the paper's Fig. 1, and the lines of the report."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.obstacle.avoid import Avoidance, ObstacleReaction
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.obstacle.walk import ObstacleRun, avoiding_rollout
from rtgait.core.planner.config import CONNECTION_MODES
from rtgait.scenario.scenario import Scenario

__all__ = [
    "closest_sole_distance", "obstacle_report_lines", "obstacle_runs", "obstacle_summary", "sim_obstacle_facts",
    "sim_obstacle_lines",
]  # fmt: skip


def obstacle_runs(scenario: Scenario, own: ObstacleRun | None = None) -> list[ObstacleRun]:
    """The scenario's walk under each of the paper's connection modes (real-time, quasi-real-time), reacting to its
    obstacles; ``own``: the run already made in the scenario's own mode, reused."""
    runs = []
    for mode in CONNECTION_MODES:
        if own is not None and own.connection == mode:
            runs.append(own)
            continue
        walk = dataclasses.replace(scenario, connection=mode)
        rollout, seen = avoiding_rollout(walk.planner_config(), walk.strides(), walk.dt, walk.sole, walk.obstacles,
                                         walk.changes)  # fmt: skip
        runs.append(ObstacleRun(mode, rollout, seen))
    return runs


def _avoidance(avoidance: Avoidance) -> dict[str, Any]:
    box = avoidance.obstacle
    chosen = avoidance.chosen
    return {
        "obstacle": {"x": box.x, "y": box.y, "length": box.length, "width": box.width, "height": box.height,
                     "yaw": box.yaw, "seen_at": box.seen_at},
        "seen_tick": avoidance.time,
        "first_open_step": avoidance.first_open,
        "side": None if chosen is None else chosen.side,
        "footprints_moved": 0 if chosen is None or chosen.detour is None else chosen.detour.moved,
        "largest_move": 0.0 if chosen is None or chosen.detour is None else chosen.detour.largest_move,
        "change": 0.0 if chosen is None or chosen.detour is None else chosen.detour.cost,
        "predicted_by": avoidance.predicted_by,
        "candidates": [
            {"side": c.side, "possible": c.detour is not None, "change": None if c.detour is None else c.detour.cost,
             "predicted_zmp_margin": c.zmp_margin, "reason": c.reason}
            for c in avoidance.candidates
        ],
    }  # fmt: skip


def obstacle_summary(runs: list[ObstacleRun]) -> list[dict[str, Any]]:
    """Per connection mode, JSON-ready (m, s; ``change``: the sum of the footprints' squared moves, m^2): what the
    walk did on seeing each obstacle and its smallest ZMP margin over the walk."""
    out = []
    for run in runs:
        result = run.rollout
        worst = result.worst_index
        out.append({
            "connection": run.connection,
            "avoided": all(a.avoided for a in run.avoidances),
            "zmp_margin_min": result.zmp_margin_min,
            "zmp_margin_min_time": float(result.times[worst]),
            "zmp_outside": result.zmp_outside,
            "avoidances": [_avoidance(a) for a in run.avoidances],
        })  # fmt: skip
    return out


def obstacle_report_lines(summary: list[dict[str, Any]]) -> list[str]:
    """The report's lines, one per connection mode."""
    lines = []
    for walk in summary:
        parts = []
        for a in walk["avoidances"]:
            if a["side"] is None:
                parts.append(f"no detour within the step limits at {a['seen_tick']:.3f} s")
            elif a["side"] == "none":
                parts.append("the walk was already clear of it")
            else:
                moved = f"{a['footprints_moved']} footprints moved, at most {a['largest_move']:.3f} m"
                step = a["first_open_step"]
                parts.append(f"seen at {a['seen_tick']:.3f} s, steps {a['side']} from step {step} ({moved})")
        where = "inside" if not walk["zmp_outside"] else "OUTSIDE the support polygon"
        lines.append(f"obstacle    {walk['connection']}: {'; '.join(parts)}; ZMP {where}, min margin "
                     f"{walk['zmp_margin_min'] * 1e3:+.1f} mm at {walk['zmp_margin_min_time']:.3f} s")  # fmt: skip
    return lines


# ----- in physics ------------------------------------------------------------------------------------------------
_GRID = 9  # sample points along each side of a sole: the distance is that of its nearest sample (a few mm coarse)


def closest_sole_distance(sole_pose: np.ndarray, sole: SoleRect, box: Obstacle) -> float:
    """Smallest distance (m) between the box and either sole over a run, ``sole_pose`` the soles' ground poses
    ``(k, 2, 3)`` (x, y, yaw; left then right), each sole sampled on a grid of its rectangle: 0 where one overlaps
    the box's footprint (the soles' heights are not looked at: a swing passing over the box counts)."""
    u = np.linspace(-sole.back, sole.front, _GRID)
    best = np.inf
    for side, (low, high) in enumerate(((-sole.inner, sole.outer), (-sole.outer, sole.inner))):
        U, V = (a.ravel() for a in np.meshgrid(u, np.linspace(low, high, _GRID)))
        x, y, yaw = (sole_pose[:, side, i, None] for i in range(3))
        points = np.stack([x + np.cos(yaw) * U - np.sin(yaw) * V, y + np.sin(yaw) * U + np.cos(yaw) * V], axis=-1)
        local = box.to_local(points)
        outside = np.maximum(np.abs(local) - (0.5 * box.length, 0.5 * box.width), 0.0)
        best = min(best, float(np.hypot(outside[..., 0], outside[..., 1]).min(initial=np.inf)))
    return best


def sim_obstacle_facts(
    reactions: tuple[tuple[float, ObstacleReaction], ...], sole_pose: np.ndarray, sole: SoleRect
) -> list[dict[str, Any]]:
    """Per obstacle of a MuJoCo run, JSON-ready: what the walk did on seeing it (``None``: never seen) and the
    closest the soles came to it (m, :func:`closest_sole_distance`)."""
    out = []
    for _, reaction in reactions:
        facts = _avoidance(reaction.result) if reaction.result is not None else {"side": None, "seen_tick": None}
        facts["closest_sole_distance"] = closest_sole_distance(sole_pose, sole, reaction.obstacle)
        out.append(facts)
    return out


def sim_obstacle_lines(summary: dict[str, Any]) -> list[str]:
    """The lines ``rtgait simulate`` prints for the obstacles of a run."""
    lines = []
    for facts in summary.get("obstacles", []):
        if facts["seen_tick"] is None:
            did = "never seen"
        elif facts["side"] is None:
            did = f"seen at {facts['seen_tick']:.3f} s, no detour within the step limits"
        else:
            did = f"seen at {facts['seen_tick']:.3f} s, steps {facts['side']} from step {facts['first_open_step']}"
        closest = facts["closest_sole_distance"]
        lines.append(f"obstacle    {did}; the soles came {closest * 1e3:.0f} mm from it at the closest"
                     + (" (they touched it)" if closest <= 0.0 else ""))  # fmt: skip
    return lines
