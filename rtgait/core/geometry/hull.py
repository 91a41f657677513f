"""Vectorised geometry for batched ZMP margins: the support polygon of two axis-aligned soles, and the extreme of a
linear function over a fixed set of points, both over a leading batch of cases.

Two-sole support polygon. The convex hull of two axis-aligned boxes ``A`` and ``B`` is bounded by the four sides of
their bounding box (each always a hull edge of positive length: the box reaching that side lends its whole side) and
by at most one *bridge* per quadrant ``(sx, sy)``: when the box that reaches farthest in ``sx`` is not the one that
reaches farthest in ``sy``, the hull runs straight from the first one's ``(sx, sy)`` corner to the second one's. So
the hull's edge lines are always 8 (a missing bridge has offset ``+inf``) and its vertices 8 (a quadrant without a
bridge repeats its corner), which vectorises over cases. Inside, the signed margin of a point ``p`` is
``min_e (c_e - n_e . p)`` over these lines (unit outward normals ``n_e``), exactly what
:func:`rtgait.core.geometry.support.signed_margin` computes on the same polygon; outside it is minus the distance to the
nearest edge segment (:func:`outside_margin`).

Extremes over a tick set. Within one phase of a plan, the ZMP relative to a point of the phase is
``r_t = s_t D + b_t beta``: two fixed shape functions sampled at the phase's ticks, ``(s_t, b_t)``, times two
case-dependent 2-vectors. For an edge, ``n . r_t = s_t (n . D) + b_t (n . beta)`` is a linear function of the point
``(s_t, b_t)``, whose maximum over the ticks sits at a vertex of their convex hull: :class:`PointChain` finds it by
a binary search over the hull's edge normals, ``O(log T)`` per query instead of ``O(T)``.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.geometry.footsteps import SoleRect

QUADRANTS = ((1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0))
"""Quadrant directions ``(sx, sy)`` in counter-clockwise order, starting from bottom-right."""
N_LINES = 8
"""Edge lines of a two-sole hull: 4 bounding-box sides (right, top, left, bottom), then one bridge per quadrant."""
_BOX_NORMALS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])


def sole_extents(sole: SoleRect, left: bool) -> tuple[float, float, float, float]:
    """``(x0, x1, y0, y1)`` of a yaw-0 sole around its ankle (m): ``inner`` faces the other foot."""
    if left:
        return -sole.back, sole.front, -sole.inner, sole.outer
    return -sole.back, sole.front, -sole.outer, sole.inner


def single_sole_margin(sole: SoleRect) -> float:
    """Signed margin of the ankle in its own sole (m): its distance to the nearest side."""
    return min(sole.front, sole.back, sole.inner, sole.outer)


def two_box_hull(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Edge lines of the convex hull of boxes ``a`` and ``b`` (each ``(R, 4)``: ``x0, x1, y0, y1``, m).

    Returns the unit outward normals' components ``nx, ny`` and the offsets ``c``, each ``(R, 8)`` (``n . p <= c``
    inside; ``c = +inf`` for a missing bridge): right, top, left and bottom sides, then the bridges of
    :data:`QUADRANTS`.
    """
    rows = a.shape[0]
    nx, ny, c = np.zeros((rows, N_LINES)), np.zeros((rows, N_LINES)), np.empty((rows, N_LINES))
    nx[:, 0], ny[:, 1], nx[:, 2], ny[:, 3] = 1.0, 1.0, -1.0, -1.0
    c[:, 0] = np.maximum(a[:, 1], b[:, 1])
    c[:, 1] = np.maximum(a[:, 3], b[:, 3])
    c[:, 2] = -np.minimum(a[:, 0], b[:, 0])
    c[:, 3] = -np.minimum(a[:, 2], b[:, 2])
    for k, (cx, cy, bridge) in enumerate(_quadrant_corners(a, b)):
        (xx, xy), (yx, yy) = cx, cy
        sx, sy = QUADRANTS[k]
        # Outward normal of the segment from the x-extreme corner to the y-extreme one: (dy, -dx), turned outward.
        dx, dy = yx - xx, yy - xy
        sign = np.where(dy * sx - dx * sy < 0.0, -1.0, 1.0)
        length = np.hypot(dx, dy)
        ok = bridge & (length > 0.0)
        scale = sign / np.where(ok, length, 1.0)
        kx, ky = dy * scale, -dx * scale
        nx[:, 4 + k] = np.where(ok, kx, sx)
        ny[:, 4 + k] = np.where(ok, ky, sy)
        c[:, 4 + k] = np.where(ok, kx * xx + ky * xy, np.inf)
    return nx, ny, c


def two_box_vertices(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Counter-clockwise vertices ``(R, 8, 2)`` of the hull of boxes ``a`` and ``b`` (as :func:`two_box_hull`); a
    quadrant without a bridge repeats its corner."""
    vertices = np.empty((a.shape[0], 2 * len(QUADRANTS), 2))
    for k, (cx, cy, _) in enumerate(_quadrant_corners(a, b)):
        sx, sy = QUADRANTS[k]
        # Counter-clockwise within the quadrant: from the y-extreme to the x-extreme where sx sy < 0, else back.
        first, second = (cy, cx) if sx * sy < 0 else (cx, cy)
        vertices[:, 2 * k, 0], vertices[:, 2 * k, 1] = first
        vertices[:, 2 * k + 1, 0], vertices[:, 2 * k + 1, 1] = second
    return vertices


def _quadrant_corners(a: np.ndarray, b: np.ndarray):
    """Per quadrant: the corner of the box reaching farthest along ``sx`` (ties: farther along ``sy``), that of the
    box reaching farthest along ``sy``, and whether they differ (a bridge)."""
    for sx, sy in QUADRANTS:
        ax, ay = a[:, 1 if sx > 0 else 0], a[:, 3 if sy > 0 else 2]
        bx, by = b[:, 1 if sx > 0 else 0], b[:, 3 if sy > 0 else 2]
        ex_a, ey_a, ex_b, ey_b = sx * ax, sy * ay, sx * bx, sy * by
        x_is_a = (ex_a > ex_b) | ((ex_a == ex_b) & (ey_a >= ey_b))
        y_is_a = (ey_a > ey_b) | ((ey_a == ey_b) & (ex_a >= ex_b))
        yield (
            (np.where(x_is_a, ax, bx), np.where(x_is_a, ay, by)),
            (np.where(y_is_a, ax, bx), np.where(y_is_a, ay, by)),
            x_is_a != y_is_a,
        )


def outside_margin(px: np.ndarray, py: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Minus the distance (m) of the points ``(px, py)`` ``(R, T)`` to the polygon of ``vertices`` ``(R, V, 2)`` (one
    polygon per row): the signed margin of a point outside it (:func:`rtgait.core.geometry.support.signed_margin`).
    Zero-length edges (repeated vertices) count as points."""
    best = np.full(px.shape, np.inf)
    ends = np.roll(vertices, -1, axis=1)
    for k in range(vertices.shape[1]):  # per edge: (R, T) arrays stay small and in cache
        vx, vy = vertices[:, k, 0:1], vertices[:, k, 1:2]
        ex, ey = ends[:, k, 0:1] - vx, ends[:, k, 1:2] - vy
        length2 = ex * ex + ey * ey
        rx, ry = px - vx, py - vy
        along = np.clip((rx * ex + ry * ey) / np.where(length2 > 0.0, length2, 1.0), 0.0, 1.0)
        gx, gy = rx - along * ex, ry - along * ey
        np.minimum(best, gx * gx + gy * gy, out=best)
    return -np.sqrt(best)


class PointChain:
    """Convex hull of a fixed 2-D point set, for the maximum of many linear functions over the set at once.

    ``argmax(vx, vy)`` is the index (into the original points) of a point maximising ``vx * s + vy * b``: the vertex
    between the two hull edges whose outward normals bracket the direction ``(vx, vy)``, found by binary search on
    the normals' angles. Ties (a direction normal to an edge) go to either end of that edge: their values are equal.
    """

    def __init__(self, points: np.ndarray) -> None:
        points = np.asarray(points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
            raise ValueError(f"points must have shape (n, 2) with n >= 1, got {points.shape}")
        self.points = points
        hull = _convex_hull(points)
        self.vertices = hull
        if len(hull) == 1:
            self.angles = np.zeros(0)
            return
        p = points[hull]
        edge = np.roll(p, -1, axis=0) - p
        angles = np.arctan2(-edge[:, 0], edge[:, 1])  # outward normal (e_y, -e_x) of a counter-clockwise edge
        # Counter-clockwise normals turn left: unwrap them into one increasing run [phi_0, phi_0 + 2 pi).
        self.angles = angles[0] + np.mod(angles - angles[0], 2.0 * math.pi)
        self.angles[0] = angles[0]

    def argmax(self, vx: np.ndarray, vy: np.ndarray) -> np.ndarray:
        """Indices of maximising points for directions ``(vx, vy)`` (any shape; zero picks any point)."""
        hull, angles = self.vertices, self.angles
        if len(hull) == 1:
            return np.zeros(np.shape(vx), dtype=int)
        psi = np.arctan2(vy, vx)
        psi = angles[0] + np.mod(psi - angles[0], 2.0 * math.pi)
        index = np.searchsorted(angles, psi, side="left")
        return hull[np.where(index >= len(hull), 0, index)]

    def maximum(self, vx: np.ndarray, vy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``max_t (vx s_t + vy b_t)`` and its index ``t``, per direction."""
        index = self.argmax(vx, vy)
        s, b = self.points[index, 0], self.points[index, 1]
        return vx * s + vy * b, index


_CHAINS: dict[bytes, PointChain] = {}
_CHAIN_CACHE_SIZE = 4096


def point_chain(points: np.ndarray) -> PointChain:
    """A :class:`PointChain` of ``points``, shared with every earlier call on the same points: the phases of a walk
    (and of walks with the same timing) mostly sample the same shapes at the same ticks."""
    points = np.ascontiguousarray(points, dtype=float)
    key = points.tobytes() + bytes(str(points.shape), "ascii")
    chain = _CHAINS.get(key)
    if chain is None:
        if len(_CHAINS) >= _CHAIN_CACHE_SIZE:
            del _CHAINS[next(iter(_CHAINS))]  # the oldest: dicts keep insertion order
        chain = _CHAINS[key] = PointChain(points)
    return chain


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """Indices of the hull's vertices, counter-clockwise, no collinear ones (Andrew's monotone chain).

    Duplicate points keep their first index, so a tie between equal points goes to the earliest."""
    order = np.lexsort((np.arange(len(points)), points[:, 1], points[:, 0]))
    pts = points[order]
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0.0, axis=1)
    order, pts = order[keep], pts[keep]
    if len(pts) <= 2:
        return order

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    lower: list[int] = []
    for i in range(len(pts)):
        while len(lower) >= 2 and cross(pts[lower[-2]], pts[lower[-1]], pts[i]) <= 0.0:
            lower.pop()
        lower.append(i)
    upper: list[int] = []
    for i in range(len(pts) - 1, -1, -1):
        while len(upper) >= 2 and cross(pts[upper[-2]], pts[upper[-1]], pts[i]) <= 0.0:
            upper.pop()
        upper.append(i)
    chain = lower[:-1] + upper[:-1]
    return order[np.array(chain, dtype=int)]


__all__ = [
    "N_LINES", "QUADRANTS", "PointChain", "outside_margin", "point_chain", "single_sole_margin", "sole_extents",
    "two_box_hull", "two_box_vertices",
]  # fmt: skip
