"""A terrain given as a grid of heights: its interpolation, and footholds fitted to it under each sole, checked
against the analytic slope the grid samples and against planes known in closed form."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, place_footsteps, standing_feet
from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.geometry.terrain import Slope, terrain_fields, terrain_from_fields
from rtgait.core.geometry.terrain_walk import TerrainWalkError, place_walk, sole_plane

SOLE = SoleRect(0.105, 0.105, 0.065, 0.065)  # Talos
ANGLE = math.radians(5.0)
XS = np.linspace(0.0, 3.5, 71)  # 5 cm
YS = np.linspace(-0.5, 0.5, 11)  # 10 cm


def _ramp_grid() -> Heightfield:
    row = math.tan(ANGLE) * np.clip(XS - 0.5, 0.0, 2.0)
    return Heightfield(np.tile(row, (len(YS), 1)), (3.5, 1.0), (0.0, -0.5))


def _plane_grid(a: float, b: float, c: float) -> Heightfield:
    """The plane ``h = a + b x + c y`` sampled on the grid (exact between samples: it is planar)."""
    return Heightfield(a + b * XS[None, :] + c * YS[:, None], (3.5, 1.0), (0.0, -0.5))


def _walk(steps: int = 14, length: float = 0.2) -> list[Footstep]:
    return place_footsteps(standing_feet(0.19), [Stride(length, 0.19)] * steps + [Stride(0.0, 0.19)])


def test_the_grid_is_the_slope_it_samples_and_level_at_zero_outside():
    grid, slope = _ramp_grid(), Slope(ANGLE, 2.0, 0.5)
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0.0, 3.5, 5000), rng.uniform(-0.5, 0.5, 5000)
    assert np.abs(grid.height(x, y) - slope.height(x, y)).max() < 1e-12
    assert grid.height(3.6, 0.0) == 0.0 and grid.height(1.0, 0.6) == 0.0 and grid.height(-0.1, 0.0) == 0.0


def test_a_cell_is_two_triangles_cut_along_the_rising_diagonal():
    # One cell of corners h00 = 1 and the others 0: on the diagonal u = v the height falls linearly from 1 to 0;
    # off it, the triangle's plane (not the bilinear 1 - u - v + uv).
    grid = Heightfield(np.array([[1.0, 0.0], [0.0, 0.0]]), (1.0, 1.0), (0.0, 0.0))
    assert grid.height(0.25, 0.25) == pytest.approx(0.75)
    assert grid.height(0.75, 0.25) == pytest.approx(0.25)  # u >= v: h00 + u (h10 - h00) + v (h11 - h10)
    assert grid.height(0.25, 0.75) == pytest.approx(0.25)


def test_footholds_on_the_ramp_grid_are_the_analytic_slopes():
    grid_prints = place_walk(_ramp_grid(), _walk(), SOLE, 0.5)
    slope_prints = place_walk(Slope(ANGLE, 2.0, 0.5), _walk(), SOLE, 0.5)
    on_ramp = 0
    for grid_foot, slope_foot in zip(grid_prints, slope_prints, strict=True):
        if 0.5 + SOLE.back <= grid_foot.x <= 2.5 - SOLE.front:  # the whole sole on the ramp
            on_ramp += 1
            assert grid_foot.z == pytest.approx(math.tan(ANGLE) * (grid_foot.x - 0.5), abs=1e-12)
            assert grid_foot.pitch == pytest.approx(-ANGLE, abs=1e-12)
            assert grid_foot.roll == pytest.approx(0.0, abs=1e-12)
            assert grid_foot.z == pytest.approx(slope_foot.z, abs=1e-12)
        elif grid_foot.x >= 2.5 + SOLE.back:  # on the level top
            assert (grid_foot.z, grid_foot.pitch) == pytest.approx((math.tan(ANGLE) * 2.0, 0.0), abs=1e-12)
    assert on_ramp >= 8


@pytest.mark.parametrize("yaw", [0.0, 0.4, -0.3])
def test_the_sole_plane_of_a_tilted_plane_is_that_plane(yaw: float):
    # h = a + b x + c y; along the heading (cos, sin) it rises b cos + c sin, to the left -b sin + c cos.
    a, b, c = 0.02, 0.08, -0.05
    foot = Footstep(1.3, 0.1, yaw, "left")
    z, pitch, roll, residual = sole_plane(_plane_grid(a, b, c), foot, SOLE)
    assert z == pytest.approx(a + b * 1.3 + c * 0.1, abs=1e-12)
    assert pitch == pytest.approx(-math.atan(b * math.cos(yaw) + c * math.sin(yaw)), abs=1e-12)
    assert roll == pytest.approx(math.atan(-b * math.sin(yaw) + c * math.cos(yaw)), abs=1e-12)
    assert residual < 1e-12


def test_a_sole_across_a_discontinuity_is_refused_naming_the_step():
    heights = np.where(XS[None, :] >= 1.0, 0.05, 0.0) * np.ones((len(YS), 1))  # a 5 cm step between samples
    grid = Heightfield(heights, (3.5, 1.0), (0.0, -0.5))
    with pytest.raises(TerrainWalkError, match=r"^step 4 at x = 1 m.*discontinuity or on ground too rough.*misses"):
        place_walk(grid, _walk(steps=6, length=0.25), SOLE, 0.5)


def test_ground_too_steep_for_a_sole_is_refused():
    grid = _plane_grid(0.0, 0.0, 0.0)
    steep = Heightfield(np.where(XS[None, :] > 0.35, 0.7 * (XS[None, :] - 0.35), 0.0) + 0 * YS[:, None], (3.5, 1.0),
                        (0.0, -0.5))  # fmt: skip
    assert place_walk(grid, _walk(steps=2), SOLE, 0.5)[2].level
    with pytest.raises(TerrainWalkError, match=r"tilted 0\.6\d* rad: steeper"):
        place_walk(steep, _walk(steps=6, length=0.25), SOLE, 0.5, max_rise=0.5)


def test_standing_feet_off_level_ground_are_refused():
    with pytest.raises(TerrainWalkError, match="standing foot F\\[0\\] must stand on level ground"):
        place_walk(_plane_grid(0.01, 0.0, 0.0), _walk(steps=2), SOLE, 0.5)


def test_grids_compare_by_their_heights_and_refuse_bad_input():
    assert _ramp_grid() == _ramp_grid() and hash(_ramp_grid()) == hash(_ramp_grid())
    assert _ramp_grid() != _plane_grid(0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="at least 2 x 2"):
        Heightfield(np.zeros((1, 5)), (1.0, 1.0))
    with pytest.raises(ValueError, match="finite"):
        Heightfield(np.array([[0.0, np.nan], [0.0, 0.0]]), (1.0, 1.0))
    with pytest.raises(ValueError, match="terrain size must be two numbers within \\(0, 200\\] m"):
        Heightfield(np.zeros((2, 2)), (0.0, 1.0))


def test_a_grid_s_fields_read_back_as_the_same_grid():
    # What summary.json and sim.parquet keep of a run's terrain, and rtgait plot draws again.
    grid = _ramp_grid()
    fields = json.loads(json.dumps(terrain_fields(grid)))
    assert fields["kind"] == "heightfield" and len(fields["heights"]) == len(YS)
    assert terrain_from_fields(fields) == grid
