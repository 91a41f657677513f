"""What ``rtgait play`` draws over the terrain: the footprints at their footholds' height and the ZMP and DCM markers
on the terrain's surface, into a MuJoCo scene (no window: the user geoms are read back); on the flat floor, as
before (the footprints 1 mm and the markers 5 mm above z = 0)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rtgait.core.geometry.footsteps import Footstep, SoleRect  # noqa: E402
from rtgait.core.geometry.terrain import Stairs  # noqa: E402
from rtgait.viz.live_view import draw_walk  # noqa: E402

SOLE = SoleRect(front=0.12, back=0.08, inner=0.06, outer=0.07)
STAIRS = Stairs(0.15, 0.25, 4, "up", start=0.375)
F32 = 1e-7  # m: the scene's geoms are float32


def _walk(terrain, prints: list[Footstep], zmp: tuple[float, float]) -> SimpleNamespace:
    """The parts of a live walk that :func:`draw_walk` reads."""
    last = SimpleNamespace(phase=3, zmp_planned=zmp, zmp_measured=zmp, dcm=zmp, dcm_planned=zmp)
    loop = SimpleNamespace(
        last=last, planner=SimpleNamespace(started=False), footprints=lambda: prints, sim=SimpleNamespace(
            terrain=terrain), push_acting=None, base_position=(0.0, 0.0, 1.0),
    )  # fmt: skip
    return SimpleNamespace(loop=loop)


def _drawn(walk: SimpleNamespace) -> tuple[np.ndarray, np.ndarray]:
    """Positions of the boxes (footprints) and the spheres (markers) drawn, in order."""
    model = mujoco.MjModel.from_xml_string("<mujoco/>")
    scene = mujoco.MjvScene(model, 50)
    draw_walk(scene, walk, SOLE)
    geoms = [scene.geoms[i] for i in range(scene.ngeom)]
    boxes = np.array([g.pos for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_BOX])
    spheres = np.array([g.pos for g in geoms if g.type == mujoco.mjtGeom.mjGEOM_SPHERE])
    return boxes, spheres


def test_footprints_and_markers_stand_on_the_treads() -> None:
    prints = [Footstep(x, y, 0.0, side, z=float(STAIRS.height(x, y)))
              for x, y, side in ((0.25, -0.1, "right"), (0.5, 0.1, "left"), (0.75, -0.1, "right"))]  # fmt: skip
    boxes, spheres = _drawn(_walk(STAIRS, prints, (0.7, 0.0)))
    assert len(boxes) == 3 and len(spheres) == 4
    for foot, box in zip(prints, boxes, strict=True):
        assert box[2] == pytest.approx(foot.z + 0.001, abs=F32)
        assert box[2] - float(STAIRS.height(box[0], box[1])) == pytest.approx(0.001, abs=F32)  # on the tread under it
    np.testing.assert_allclose(spheres[:, 2], STAIRS.height(0.7, 0.0) + 0.005, atol=F32)  # the third tread, 0.45 m


def test_on_the_flat_floor_as_before() -> None:
    prints = [Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.2, -0.1, 0.0, "right")]
    boxes, spheres = _drawn(_walk(None, prints, (0.1, 0.0)))
    np.testing.assert_array_equal(boxes[:, 2], np.float32(0.001))
    np.testing.assert_array_equal(spheres[:, 2], np.float32(0.005))
