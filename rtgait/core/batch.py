"""Many plans at once: evaluate stacked inputs through one precomputed operator.

Everything in a plan is linear in its inputs ``y = [p0, dp0, c0, dc0, anchors...]`` (per axis), so a family of
plans that share a timing (candidate landing points, perturbed states, a sweep over step changes) is one operator
applied to a stack of inputs. The functions here stay numpy-only and allocation-light so that a decision over a
thousand candidates takes well under a millisecond.

Margins use the half-planes of the convex support polygon: ``min_k (b_k - n_k . p)`` over its edges, the signed
distance to the boundary when ``p`` is inside (exact) and a lower bound of it, negative, when outside. That is
all a feasibility test or a ranking needs, at a fraction of the cost of the exact outside distance
(:func:`rtgait.core.support.signed_margin`).
"""

from __future__ import annotations

import numpy as np

from rtgait.core.pattern import DEGREE


def segment_zmp_rows(G: np.ndarray, duration: float, n_times: int, segment: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Times (s, local to the segment) and the matrix ``M`` ``(n_times, n_inputs)`` with ``zmp(t_i) = M[i] @ y``.

    ``G`` is a plan operator (:class:`~rtgait.core.pattern.PlanOperator`); ``y`` its inputs, one column per axis.
    """
    if n_times < 2:
        raise ValueError(f"n_times must be >= 2, got {n_times}")
    times = np.linspace(0.0, duration, n_times)
    powers = times[:, None] ** np.arange(DEGREE + 1)[None, :]  # (n_times, DEGREE + 1)
    rows = 12 * segment
    return times, powers @ G[rows : rows + DEGREE + 1]


def polygon_halfplanes(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit outward normals ``(k, 2)`` and offsets ``(k,)`` of a counter-clockwise convex polygon ``(k, 2)`` (m):
    a point ``p`` is inside iff ``n . p <= b`` for every edge."""
    polygon = np.asarray(polygon, dtype=float)
    edge = np.roll(polygon, -1, axis=0) - polygon
    normal = np.column_stack([edge[:, 1], -edge[:, 0]])  # right of a counter-clockwise edge: outward
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return normal, np.einsum("kd,kd->k", normal, polygon)


def halfplane_margin(points: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``min_k (b_k - n_k . p)`` for points ``(..., 2)`` (m): the signed distance inside, a lower bound outside."""
    return np.min(offsets - points @ normals.T, axis=-1)


__all__ = ["halfplane_margin", "polygon_halfplanes", "segment_zmp_rows"]
