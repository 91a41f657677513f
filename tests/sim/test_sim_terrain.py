"""The scenario's terrain in MuJoCo: rays cast down onto the built scene meet it at the height the terrain description
gives (stairs up and down, slopes up and down, stepping stones and their pit, a step, a height field's grid), with the
floor's friction."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rtgait.core.geometry.terrain import Flat, Heightfield, Slope, Stairs, Step, SteppingStones, surface  # noqa: E402
from rtgait.sim.config import SimConfig  # noqa: E402
from rtgait.sim.contact_model import add_floor  # noqa: E402
from rtgait.sim.terrain import add_terrain  # noqa: E402

TERRAINS = {
    "stairs up": Stairs(0.10, 0.22, 6, "up"),
    "stairs down": Stairs(0.15, 0.25, 6, "down", start=0.4),
    "slope up": Slope(math.radians(10.0), 2.0),
    "slope down": Slope(-math.radians(10.0), 2.0, start=0.6),
    "stones": SteppingStones(0.20, 0.15, 0.10, 4, 0.2),
    "step down": Step(-0.03, 0.7),
    "step up": Step(0.03, 0.7),
    "flat": Flat(),
}


def _scene(terrain, config: SimConfig) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec()
    add_floor(spec, config)
    add_terrain(spec, terrain, config)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _ray_height(model: mujoco.MjModel, data: mujoco.MjData, x: float, y: float) -> float:
    top = 3.0
    geom = np.zeros(1, dtype=np.int32)
    distance = mujoco.mj_ray(model, data, np.array([x, y, top]), np.array([0.0, 0.0, -1.0]), None, 1, -1, geom)
    assert distance >= 0.0, f"no ground under ({x}, {y})"
    return top - distance


@pytest.mark.parametrize("name", list(TERRAINS))
def test_the_built_ground_lies_where_the_terrain_description_puts_it(name: str) -> None:
    terrain = TERRAINS[name]
    model, data = _scene(terrain, SimConfig())
    # Points along both feet's lines and the centre line, away from every edge by 1 cm (on an edge the ray may hit
    # either side): heights and, on the slope, the surface's normal.
    xs = np.arange(-1.0, 4.0, 0.0137)
    for y in (-0.1, 0.0, 0.1):
        for x in xs:
            if abs(float(terrain.height(x + 0.01, y)) - float(terrain.height(x - 0.01, y))) > 1e-3 and not isinstance(
                terrain, Slope
            ):
                continue  # too close to an edge
            expected = float(terrain.height(x, y))
            assert _ray_height(model, data, x, y) == pytest.approx(expected, abs=1e-9 if expected else 1e-12), (x, y)


def test_a_slope_box_has_the_surface_s_tilt_and_the_floor_s_friction() -> None:
    terrain = Slope(math.radians(10.0), 2.0)
    config = SimConfig(friction=0.7)
    model, data = _scene(terrain, config)
    ramp = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_1")
    normal = data.geom_xmat[ramp].reshape(3, 3)[:, 2]
    _, pitch, _ = surface(terrain, 1.5, 0.0, 0.0)
    assert pitch == pytest.approx(-math.radians(10.0))
    np.testing.assert_allclose(normal, [math.sin(pitch), 0.0, math.cos(pitch)], atol=1e-12)  # (-sin a, 0, cos a)
    assert model.geom_friction[ramp][0] == pytest.approx(0.7)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    np.testing.assert_array_equal(model.geom_friction[ramp], model.geom_friction[floor])
    np.testing.assert_array_equal(model.geom_solref[ramp], model.geom_solref[floor])


def test_the_floor_goes_down_to_the_lowest_level_and_flat_adds_nothing() -> None:
    model, _ = _scene(Stairs(0.15, 0.25, 6, "down"), SimConfig())
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert model.geom_pos[floor][2] == pytest.approx(-0.9)
    model, _ = _scene(Flat(), SimConfig())
    assert model.ngeom == 1


def test_the_robot_stands_on_the_top_landing_of_stairs_down(talos) -> None:
    from rtgait.sim.model import build_sim_model

    stairs = Stairs(0.15, 0.25, 6, "down")
    sim = build_sim_model(talos, SimConfig(meshes=False), terrain=stairs)
    assert sim.terrain is stairs
    floor = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert sim.model.geom_pos[floor][2] == pytest.approx(-0.9)
    data = sim.new_data()  # settled on the landing before the first stair, 0.9 m above the floor
    for site in (sim.left_sole_site, sim.right_sole_site):
        assert abs(data.site_xpos[site][2]) < 0.005


@pytest.mark.parametrize("dip", [0.0, -0.04])
def test_a_height_field_is_built_from_the_same_grid_its_footholds_are_fitted_to(dip: float) -> None:
    # A rough grid, off-centre, uneven sample spacing along x and y; with ``dip`` it goes below the level ground
    # around it (the floor then goes down and boxes frame the grid at 0).
    rng = np.random.default_rng(7)
    heights = rng.uniform(dip, 0.06, (9, 23))
    terrain = Heightfield(heights, (2.2, 0.8), (0.3, -0.35))
    model, data = _scene(terrain, SimConfig(friction=0.6))
    grid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_grid")
    assert model.geom_type[grid] == mujoco.mjtGeom.mjGEOM_HFIELD and model.geom_friction[grid][0] == pytest.approx(0.6)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert model.geom_pos[floor][2] == pytest.approx(min(0.0, heights.min()))
    x = rng.uniform(0.3 + 1e-6, 2.5 - 1e-6, 400)
    y = rng.uniform(-0.35 + 1e-6, 0.45 - 1e-6, 400)
    # The hfield stores its normalised data as float32: heights to a few 1e-9 m.
    rays = np.array([_ray_height(model, data, a, b) for a, b in zip(x, y, strict=True)])
    np.testing.assert_allclose(rays, terrain.height(x, y), atol=1e-7)
    # Around the grid the ground is level at 0.
    for a, b in ((0.1, 0.0), (2.7, 0.0), (1.0, 0.6), (1.0, -0.6)):
        assert _ray_height(model, data, a, b) == pytest.approx(0.0, abs=1e-12)


_BASE = """<mujoco><worldbody><body name="base" pos="0 0 {z}"><freejoint/><geom size="0.1" mass="1"/>
<site name="left" pos="0 0.1 -0.7"/><site name="right" pos="0 -0.1 -0.7"/></body></worldbody></mujoco>"""


@pytest.mark.parametrize("terrain", [None, Slope(-math.radians(10.0), 2.0, start=0.5)])
def test_the_base_is_too_low_by_its_height_above_the_terrain_under_it(terrain) -> None:
    # A base 0.74 m up at the start falls under 0.6 of that above the ground under it: down a ramp the ground under
    # it goes down too, and a base 0.7 m above the ramp 0.3 m down is standing (0.4 m above the floor's plane).
    from rtgait.sim.contact import ContactMonitor, FallLimits

    model = mujoco.MjModel.from_xml_string(_BASE.format(z=0.74))
    data = mujoco.MjData(model)
    sites = (model.site("left").id, model.site("right").id)
    monitor = ContactMonitor(data, *sites, 10, 1.0, FallLimits(), 0.001, terrain)
    x = 0.5 + 0.3 / math.tan(math.radians(10.0))  # 0.3 m down the ramp
    ground = 0.0 if terrain is None else -0.3
    upright = (1.0, 0.0, 0.0, 0.0)  # (qw, qx, qy, qz)
    assert monitor.fall(np.array([x, 0.0, ground + 0.7, *upright])) is None
    assert monitor.fall(np.array([x, 0.0, ground + 0.6 * 0.74 - 0.01, *upright])) == "base too low"
    assert monitor.fall(np.array([x, 0.0, ground + 0.6 * 0.74 + 0.01, *upright])) is None
