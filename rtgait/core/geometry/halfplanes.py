"""A convex polygon as half-planes, and the margin of points against them, vectorised over many points."""

from __future__ import annotations

import numpy as np

__all__ = ["halfplane_margin", "polygon_halfplanes"]


def polygon_halfplanes(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit outward normals ``(k, 2)`` and offsets ``(k,)`` of a counter-clockwise convex polygon ``(k, 2)`` (m):
    a point ``p`` is inside iff ``n . p <= b`` for every edge.

    A degenerate polygon (:func:`~rtgait.core.geometry.support.support_polygon` of feet with no area in floating
    point) has half-planes too: a segment's two edge lines bound its line, a point's four axis half-planes the
    point."""
    polygon = np.asarray(polygon, dtype=float)
    if len(polygon) == 1:
        normals = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
        return normals, normals @ polygon[0]
    edge = np.roll(polygon, -1, axis=0) - polygon
    normal = np.column_stack([edge[:, 1], -edge[:, 0]])  # right of a counter-clockwise edge: outward
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return normal, np.einsum("kd,kd->k", normal, polygon)


def halfplane_margin(points: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``min_k (b_k - n_k . p)`` for points ``(..., 2)`` (m): the signed distance inside, a lower bound outside."""
    return np.min(offsets - points @ normals.T, axis=-1)
