"""Support polygons and the signed ZMP margin (feasibility of a plan).

The margin is the signed distance (m) from the ZMP to the boundary of the support polygon: positive inside,
negative outside. A plan whose margin goes negative anywhere asks for a ZMP the feet cannot produce.

A support whose sole corners have no area in floating point (feet so far from the origin that a sole's size is
below the coordinates' resolution) is a segment (two vertices, the extremes along the corners' spread) or a point
(one vertex), never an error: its margin is minus the distance to it.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from rtgait.core.geometry.footsteps import Footstep, SoleRect

SUPPORT_CODES = {"double": 0, "left": 1, "right": 2}
"""The planner's support (which feet are on the ground: both, the left one, the right one) as the integer code that
per-tick records store (the pendulum's and the MuJoCo loop's results, their logs)."""

SUPPORT_NAMES = tuple(sorted(SUPPORT_CODES, key=SUPPORT_CODES.__getitem__))
"""The support of each code of :data:`SUPPORT_CODES`, by code."""


def support_polygon(feet: list[Footstep], sole: SoleRect) -> np.ndarray:
    """Counter-clockwise vertices ``(k, 2)`` (m) of the convex hull of the soles of the feet in contact."""
    if not feet:
        raise ValueError("a support polygon needs at least one foot in contact")
    corners = np.concatenate([sole.corners(foot) for foot in feet])
    if len(feet) == 1:
        return corners
    try:
        hull = ConvexHull(corners)
    except QhullError:  # flat or a point: Qhull finds no 2-D simplex
        return _degenerate_hull(corners)
    return corners[hull.vertices]  # scipy orders 2-D hull vertices counter-clockwise


def _degenerate_hull(points: np.ndarray) -> np.ndarray:
    """The hull of points with no area: the two extremes along their widest coordinate spread, or one point."""
    spread = points.max(axis=0) - points.min(axis=0)
    axis = int(np.argmax(spread))
    if not spread[axis] > 0.0:
        return points[:1].copy()
    return points[[int(np.argmin(points[:, axis])), int(np.argmax(points[:, axis]))]]


def signed_margin(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Signed distance (m) of each point ``(k, 2)`` to a convex counter-clockwise ``polygon`` ``(n, 2)``.

    Inside, the distance to the nearest edge line is the distance to the boundary (convexity); outside, it is
    the Euclidean distance to the nearest edge segment, negated.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if len(polygon) <= 2:  # a point or segment support (no area): minus the distance to it, 0 on it
        a, b = polygon[0], polygon[-1]
        edge = b - a
        length2 = float(edge @ edge)
        along = np.clip((points - a) @ edge / length2, 0.0, 1.0) if length2 > 0.0 else np.zeros(len(points))
        return -np.linalg.norm(points - (a + along[:, None] * edge), axis=1)
    start = polygon
    edge = np.roll(polygon, -1, axis=0) - polygon
    length = np.linalg.norm(edge, axis=1)
    rel = points[:, None, :] - start[None, :, :]  # (k, n, 2)
    # Left of every counter-clockwise edge = inside.
    inside_dist = (edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]) / length[None, :]
    inside = np.all(inside_dist >= 0.0, axis=1)
    along = np.clip(np.einsum("knd,nd->kn", rel, edge) / length[None, :] ** 2, 0.0, 1.0)
    nearest = start[None] + along[..., None] * edge[None]
    outside_dist = np.min(np.linalg.norm(points[:, None, :] - nearest, axis=2), axis=1)
    return np.where(inside, np.min(inside_dist, axis=1), -outside_dist)
