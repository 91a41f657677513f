"""rtgait.core.geometry.polygon: the per-point and the vectorised nearest point agree, and both agree with a brute-force
search over a dense sampling of the polygon's boundary; bad polygons are refused."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from rtgait.core.geometry.polygon import ConvexPolygon, clip_to_polygon, project_to_polygon


def _random_polygon(rng: np.random.Generator) -> np.ndarray:
    hull = ConvexHull(rng.uniform(-0.2, 0.2, size=(12, 2)))
    return hull.points[hull.vertices]  # counter-clockwise in 2-D


def _brute_force(point: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    s = np.linspace(0.0, 1.0, 4001)[:, None]
    boundary = np.concatenate([a + s * (b - a) for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True)])
    return boundary[np.argmin(np.linalg.norm(boundary - point, axis=1))]


def test_the_two_forms_agree_with_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(20):
        polygon = _random_polygon(rng)
        points = rng.uniform(-0.4, 0.4, size=(30, 2))
        batch = project_to_polygon(points, polygon)
        prepared = ConvexPolygon(polygon)
        for point, projected in zip(points, batch, strict=True):
            qx, qy, moved = prepared.nearest(*point.tolist())
            np.testing.assert_allclose((qx, qy), projected, atol=1e-15)
            inside = ConvexHull(np.vstack([polygon, point])).volume <= ConvexHull(polygon).volume * (1 + 1e-12)
            assert moved == (not inside)
            if moved:
                np.testing.assert_allclose(projected, _brute_force(point, polygon), atol=1e-4)
            else:
                np.testing.assert_array_equal(projected, point)


def test_point_and_line_contacts():
    np.testing.assert_array_equal(clip_to_polygon((1.0, 2.0), np.array([[0.5, 0.5]])), [0.5, 0.5])
    np.testing.assert_allclose(clip_to_polygon((0.5, 2.0), [[0.0, 0.0], [1.0, 0.0]]), [0.5, 0.0])
    assert ConvexPolygon([[0.0, 0.0], [1.0, 0.0]], min_vertices=1).degenerate


@pytest.mark.parametrize(
    ("polygon", "message"),
    [
        ([], "empty"),
        ([[0.0, 0.0], [1.0, 0.0]], "k >= 3"),
        ([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]], "counter-clockwise"),
        ([[0.0, 0.0], [1.0, 0.0], [np.nan, 1.0]], "finite"),
        ([[0.0, 0.0], [2.0, 0.0], [1.0, 0.2], [1.0, 1.0], [0.0, 1.0]], "convex"),
    ],
)
def test_bad_polygons_are_refused(polygon, message):
    with pytest.raises(ValueError, match=message):
        ConvexPolygon(polygon)
