"""Nearest points of a convex support polygon: the saturation of a commanded ZMP, the clipping of a plant's ZMP.

A ZMP can only lie in the convex hull of the contacts. Both the DCM feedback law (:mod:`rtgait.core.laws.feedback`,
which saturates its command) and the pendulum plant (:mod:`rtgait.core.pendulum.plant`, whose real ZMP is the commanded
one clipped to the feet on the ground) need the point of the polygon nearest to a given one, every control tick, for a
polygon of 4 to 8 vertices that changes only when the contacts do. Hence two forms:

* :class:`ConvexPolygon`: validated once, then queried with Python floats (for so few vertices a float loop is
  several times faster than the fixed cost of numpy calls, and a tick must stay within a few microseconds);
* :func:`project_to_polygon`: vectorised over many points, for batches.

The nearest point of a convex polygon to an outside point ``p`` lies on an edge whose supporting line has ``p`` on
its outer side: inside an edge, ``p - q`` is that edge's outward normal; at a vertex, ``p - q`` lies in the cone of
its two edges' outward normals, so outside at least one of them, and the projection on that edge clamps to the
vertex. Only those edges are searched. A point is *inside* when it is left of every counter-clockwise edge, up to a
tolerance of :data:`INSIDE_TOLERANCE` times the polygon's squared size (a point put on an edge by a projection must
count as inside at the next query despite round-off).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["INSIDE_TOLERANCE", "ConvexPolygon", "clip_to_polygon", "project_to_polygon", "vertex_list"]

INSIDE_TOLERANCE = 1e-12
"""Negative cross product (relative to the polygon's squared size) still counted inside."""

Edge = tuple[float, float, float, float, float]
"""An edge as ``(ax, ay, ex, ey, 1/|e|^2)``: its start vertex and its vector (m)."""


def vertex_list(polygon: object) -> list[list[float]]:
    """``polygon`` (``(k, 2)`` array or pairs) as lists of floats, cheaply: what :attr:`ConvexPolygon.key` holds,
    so a caller that keeps a prepared polygon can tell every tick whether the contacts changed.

    Raises:
        ValueError: ``None``, or anything that is not ``k`` pairs of numbers.
    """
    if polygon is None:
        raise ValueError("the support polygon is None: no foot on the ground, so no ZMP exists")
    if type(polygon) is np.ndarray and polygon.ndim == 2 and polygon.shape[1:] == (2,):
        return polygon.tolist()  # the tick path: one C call
    try:
        vertices = np.array(polygon, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"polygon must be an array (k, 2) of vertices in m, got {polygon!r}") from None
    if vertices.size and (vertices.ndim != 2 or vertices.shape[1] != 2):
        raise ValueError(f"polygon must be an array (k, 2) of vertices in m, got shape {vertices.shape}")
    return vertices.tolist()


def _checked_vertex_list(polygon: object, min_vertices: int) -> list[list[float]]:
    """:func:`vertex_list`, with at least ``min_vertices`` vertices, all finite, else a ValueError."""
    points = vertex_list(polygon)
    if not points:
        raise ValueError("the support polygon is empty: no foot on the ground, so no ZMP exists")
    if len(points) < min_vertices:
        raise ValueError(f"polygon must be an array (k, 2) with k >= {min_vertices} vertices in m, got {len(points)}")
    if not all(math.isfinite(x) and math.isfinite(y) for x, y in points):
        raise ValueError("polygon vertices must be finite (m)")
    return points


class ConvexPolygon:
    """A convex polygon with counter-clockwise vertices, prepared for many nearest-point queries.

    Args:
        vertices: ``(k, 2)`` (m), counter-clockwise, convex, winding once; repeated vertices are dropped and
            collinear ones kept (a single foot's rectangle and scipy's hulls both qualify). With ``min_vertices`` 1,
            one vertex (a point contact) or two (a line contact) are accepted too: the set is then that segment.
        min_vertices: fewest vertices accepted (3 for a polygon of positive area).

    Raises:
        ValueError: an empty or non-finite polygon, too few vertices, or one that is not convex and
            counter-clockwise.
    """

    __slots__ = ("edges", "key", "tolerance")

    def __init__(self, vertices: object, min_vertices: int = 3) -> None:
        points = _checked_vertex_list(vertices, min_vertices)
        self.key = points
        """The vertices as given (lists of floats): compare with a new polygon's to know whether it changed."""
        count = len(points)
        edges: list[Edge] = []
        for i, (ax, ay) in enumerate(points):
            bx, by = points[(i + 1) % count]
            ex, ey = bx - ax, by - ay
            if ex != 0.0 or ey != 0.0:
                edges.append((ax, ay, ex, ey, 1.0 / (ex * ex + ey * ey)))
        if not edges:  # one vertex (or all repeated): a point contact
            ax, ay = points[0]
            edges.append((ax, ay, 0.0, 0.0, 0.0))
        self.edges: tuple[Edge, ...] = tuple(edges)
        xs = [x for x, _ in points]
        ys = [y for _, y in points]
        self.tolerance = INSIDE_TOLERANCE * max(max(xs) - min(xs), max(ys) - min(ys)) ** 2
        """Negative cross product (m^2) still counted inside."""
        if count >= 3:
            self._check_convex_ccw()

    def _check_convex_ccw(self) -> None:
        edges, tolerance = self.edges, self.tolerance
        turning = 0.0
        convex = len(edges) >= 3
        for i, (_, _, ex, ey, _) in enumerate(edges):
            _, _, fx, fy, _ = edges[(i + 1) % len(edges)]
            cross = ex * fy - ey * fx
            convex = convex and cross >= -tolerance
            turning += math.atan2(cross, ex * fx + ey * fy)
        if not (convex and abs(turning - 2.0 * math.pi) < 1e-6):
            raise ValueError("polygon must be convex with counter-clockwise vertices, winding once, of positive area")

    @property
    def degenerate(self) -> bool:
        """Whether the polygon is a point or a segment (one or two distinct vertices)."""
        return len(self.edges) < 3

    def nearest(self, x: float, y: float) -> tuple[float, float, bool]:
        """Nearest point of the closed polygon to ``(x, y)`` (m) and whether it differs from it:
        ``(qx, qy, moved)``."""
        if len(self.edges) < 3:
            return self._nearest_segment(x, y)
        tolerance = self.tolerance
        best = math.inf
        qx = qy = 0.0
        for ax, ay, ex, ey, inverse in self.edges:
            rx = x - ax
            ry = y - ay
            if ex * ry - ey * rx >= -tolerance:  # left of (or on) a counter-clockwise edge's line
                continue
            s = (rx * ex + ry * ey) * inverse
            s = 0.0 if s < 0.0 else (1.0 if s > 1.0 else s)
            cx = ax + s * ex
            cy = ay + s * ey
            d2 = (x - cx) ** 2 + (y - cy) ** 2
            if d2 < best:
                best, qx, qy = d2, cx, cy
        if best == math.inf:
            return x, y, False
        return qx, qy, True

    def _nearest_segment(self, x: float, y: float) -> tuple[float, float, bool]:
        # A point contact or a line contact: the set is the first edge's segment (its start for a point).
        ax, ay, ex, ey, inverse = self.edges[0]
        s = ((x - ax) * ex + (y - ay) * ey) * inverse
        s = 0.0 if s < 0.0 else (1.0 if s > 1.0 else s)
        qx, qy = ax + s * ex, ay + s * ey
        return qx, qy, not (qx == x and qy == y)


def clip_to_polygon(point: Sequence[float] | np.ndarray, polygon: object) -> np.ndarray:
    """The point of the convex counter-clockwise ``polygon`` ``(k, 2)`` nearest to ``point`` ``(2,)`` (m).

    ``point`` itself when inside. One or two vertices are accepted too (a point or line contact). An empty polygon
    raises :class:`ValueError`: with no contact there is no ZMP.
    """
    values = np.asarray(point, dtype=float)
    if values.shape != (2,) or not np.all(np.isfinite(values)):
        raise ValueError(f"point must be a finite pair (x, y) in m, got {point!r}")
    x, y = values.tolist()
    qx, qy, _ = ConvexPolygon(polygon, min_vertices=1).nearest(x, y)
    return np.array([qx, qy])


def project_to_polygon(points: np.ndarray, polygon: object) -> np.ndarray:
    """Nearest points (m) of a convex counter-clockwise ``polygon`` ``(k, 2)`` (k >= 3) to ``points`` (``(2,)`` or
    ``(n, 2)``).

    Points inside or on the boundary are returned unchanged; the result has the shape of ``points``. Vectorised
    over the points, for batches; :meth:`ConvexPolygon.nearest` does the same for one point without numpy.
    """
    array = np.asarray(points, dtype=float)
    if array.ndim not in (1, 2) or array.shape[-1] != 2 or not np.all(np.isfinite(array)):
        raise ValueError(f"points must be finite, of shape (2,) or (n, 2) in m, got shape {array.shape}")
    checked = ConvexPolygon(polygon)  # validation: convex, counter-clockwise
    vertices = np.array(checked.key)
    flat = array.reshape(-1, 2)
    edge = np.roll(vertices, -1, axis=0) - vertices
    length2 = np.einsum("kd,kd->k", edge, edge)
    edge, start, length2 = edge[length2 > 0.0], vertices[length2 > 0.0], length2[length2 > 0.0]
    rel = flat[:, None, :] - start[None, :, :]  # (n, k, 2)
    cross = edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]
    inside = np.all(cross >= -checked.tolerance, axis=1)
    along = np.clip(np.einsum("nkd,kd->nk", rel, edge) / length2[None, :], 0.0, 1.0)
    nearest = start[None] + along[..., None] * edge[None]  # nearest point of each edge, (n, k, 2)
    best = np.argmin(np.einsum("nkd,nkd->nk", flat[:, None, :] - nearest, flat[:, None, :] - nearest), axis=1)
    projected = nearest[np.arange(len(flat)), best]
    return np.where(inside[:, None], flat, projected).reshape(array.shape)
