"""zmp_sim off the flat floor: a fourth panel, the side view (x-z) of the terrain under the walk and the soles'
heights over it, drawn from the terrain's own height field; a level walk keeps its three panels; the terrain entry of
a run's files reads back to the same terrain."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.terrain import Flat, Stairs, SteppingStones, terrain_fields
from rtgait.viz.run_files import RunFilesError, read_terrain
from rtgait.viz.sim_figure import ZmpSimRun, draw_zmp_sim
from rtgait.viz.terrain_profile import PROFILE_SAMPLES

STAIRS = Stairs(0.15, 0.25, 4, "up", start=0.375)


def _run(terrain, sole_xz: np.ndarray | None) -> ZmpSimRun:
    """A short run whose soles climb one tread a step (the ZMP and COG only have to be drawable)."""
    k = 200
    t = np.linspace(0.0, 4.0, k)
    xy = np.column_stack([np.linspace(0.0, 1.0, k), np.zeros(k)])
    return ZmpSimRun(
        times=t, zmp=xy, zmp_planned=xy, zmp_command=xy, cog=xy, double=np.zeros(k, bool), double_label="double",
        single=np.ones(k, bool), stance=np.ones((k, 2), bool), sole_pose=None, sole=SoleRect(0.1, 0.1, 0.06, 0.06),
        pushes=(), tip_time=None, fall_time=None, fall_cause=None, steps_completed=4, steps_planned=4, rms=math.nan,
        robot="talos", controller="adaptive", title="stairs", terrain=terrain, sole_xz=sole_xz,
    )  # fmt: skip


def _climb(k: int = 200) -> np.ndarray:
    """(k, 2, 2): each sole standing on the tread under it, the right one a tread behind."""
    x = np.linspace(0.0, 1.25, k)
    left = np.column_stack([x, STAIRS.height(x, 0.0)])
    behind = np.maximum(x - 0.25, 0.0)
    right = np.column_stack([behind, STAIRS.height(behind, 0.0)])
    return np.stack([left, right], axis=1)


def test_the_side_view_draws_the_treads_and_the_soles() -> None:
    soles = _climb()
    figure = draw_zmp_sim(_run(STAIRS, soles))
    assert len(figure.axes) == 4
    side = figure.axes[3]
    assert side.get_xlabel() == "x (world) [m]" and side.get_ylabel() == "z (world) [m]"
    lines = {str(line.get_label()): np.asarray(line.get_xydata()) for line in side.get_lines()}
    np.testing.assert_array_equal(lines["left sole (measured)"], soles[:, 0])
    np.testing.assert_array_equal(lines["right sole (measured)"], soles[:, 1])
    (outline,) = [xy for label, xy in lines.items() if "sole" not in label]
    assert len(outline) == PROFILE_SAMPLES
    low, high = side.get_ylim()
    expected = np.maximum(STAIRS.height(outline[:, 0], 0.0), low)
    np.testing.assert_allclose(outline[:, 1], expected, atol=1e-12)  # the treads where the height field has them
    assert outline[0, 0] < soles[..., 0].min() and outline[-1, 0] > soles[..., 0].max()
    assert low < 0.0 and high > soles[..., 1].max()
    rises = np.flatnonzero(np.diff(outline[:, 1]) > 0.1)  # one riser per stair nose in view
    np.testing.assert_allclose(outline[rises, 0], STAIRS.start + STAIRS.tread * np.arange(len(rises)), atol=2e-3)
    assert len(rises) == STAIRS.count


def test_stepping_stones_are_cut_along_the_feet_s_row() -> None:
    stones = SteppingStones(0.20, 0.15, 0.10, 3, 0.2)
    x = np.linspace(0.0, 1.2, 100)
    soles = np.stack([np.column_stack([x, np.zeros_like(x)])] * 2, axis=1)
    side = draw_zmp_sim(_run(stones, soles)).axes[3]
    outline = next(np.asarray(line.get_xydata()) for line in side.get_lines() if "sole" not in str(line.get_label()))
    low = side.get_ylim()[0]
    on_stone = (outline[:, 0] > stones.start + 0.01) & (outline[:, 0] < stones.start + stones.length - 0.01)
    in_gap = (outline[:, 0] > stones.start + stones.length + 0.01) & (outline[:, 0] < stones.centre(1) - 0.11)
    assert np.all(outline[on_stone, 1] == 0.0) and np.all(outline[in_gap, 1] == low) and low > -0.5  # pit cut
    assert "terrain: stones (y = +0.10 m)" in [t.get_text() for t in side.get_legend().get_texts()]


@pytest.mark.parametrize("terrain", [None, Flat()])
def test_a_level_walk_keeps_three_panels(terrain) -> None:
    assert len(draw_zmp_sim(_run(terrain, _climb())).axes) == 3
    assert len(draw_zmp_sim(_run(STAIRS, None)).axes) == 3  # no soles' heights (sim.csv): no side view


def test_the_terrain_entry_of_a_run_reads_back() -> None:
    assert read_terrain(terrain_fields(STAIRS)) == STAIRS
    assert read_terrain(None) is None
    with pytest.raises(RunFilesError, match="terrain entry is not a terrain: terrain kind must be one of"):
        read_terrain({"kind": "lava"})
    with pytest.raises(RunFilesError, match="terrain stairs"):
        read_terrain({"kind": "stairs", "riser": 0.1})
