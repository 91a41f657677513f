"""Swing feet checked against the terrain: the sole swept along a swing stays clear of every edge.

A swing from ``start`` to ``end`` (:func:`~rtgait.core.geometry.swing.swing_pose`, ``height`` above the higher
foothold) is sampled at ``samples`` instants; at each the sole (tilted from the start surface's pitch and roll to the
landing's with the horizontal progress) is laid over a grid and its *gap*, the sole's height minus the terrain's
under it, is taken at its lowest point (m). A swing passes when

* the gap never falls below ``-EDGE_TOLERANCE`` (the sole does not cut into a stair nose or a stone), and
* over its middle, ``s`` in ``[RISE_SHARE, 1 - RISE_SHARE]`` (where the foot crosses from one foothold's surface to
  the other's), the gap is at least ``clearance`` (m).
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.swing import RISE_SHARE, swing_pose
from rtgait.core.geometry.terrain import EDGE_TOLERANCE, Terrain, sole_points

MIN_SWING_CLEARANCE = 0.02
"""Clearance over the terrain a swing keeps over its middle (m), checked before the walk."""


def swing_gaps(
    terrain: Terrain, start: Footstep, end: Footstep, height: float, sole: SoleRect, samples: int = 41
) -> tuple[np.ndarray, np.ndarray]:
    """``(s, gap)``: swing progress and the sole's lowest gap over the terrain at each (m)."""
    s_values = np.linspace(0.0, 1.0, samples)
    points = []
    for s in s_values:
        x, y, z, yaw = swing_pose(start, end, float(s), height)
        travel = math.hypot(end.x - start.x, end.y - start.y)
        k = min(math.hypot(x - start.x, y - start.y) / travel, 1.0) if travel > 0.0 else float(s)
        pitch = start.pitch + k * (end.pitch - start.pitch)
        roll = start.roll + k * (end.roll - start.roll)
        points.append(sole_points(Footstep(x, y, yaw, end.side, z, pitch, roll), sole))
    grid = np.stack(points)  # (samples, n, 3)
    ground = np.asarray(terrain.height(grid[..., 0], grid[..., 1]), float)
    return s_values, (grid[..., 2] - ground).min(axis=1)


def check_swing(
    terrain: Terrain,
    start: Footstep,
    end: Footstep,
    height: float,
    sole: SoleRect,
    step: int,
    clearance: float = MIN_SWING_CLEARANCE,
) -> float:
    """The lowest gap (m) of ``step``'s swing over its middle; :class:`ValueError` naming the step when it cuts into
    the terrain or passes closer than ``clearance`` (module docstring)."""
    s, gap = swing_gaps(terrain, start, end, height, sole)
    inside = (s > 0.0) & (s < 1.0)
    worst = int(np.argmin(np.where(inside, gap, np.inf)))
    if gap[worst] < -EDGE_TOLERANCE:
        raise ValueError(
            f"step {step}'s swing cuts {-gap[worst]:.3g} m into the terrain at {s[worst]:.0%} of the swing: raise "
            f"step_height (now {height:g} m)"
        )
    middle = (s >= RISE_SHARE) & (s <= 1.0 - RISE_SHARE)
    lowest = float(gap[middle].min())
    if lowest < clearance:
        raise ValueError(
            f"step {step}'s swing passes {lowest:.3g} m over the terrain mid-swing, less than the {clearance:g} m "
            f"clearance: raise step_height (now {height:g} m)"
        )
    return lowest


__all__ = ["MIN_SWING_CLEARANCE", "check_swing", "swing_gaps"]
