"""The terrain and the obstacles in the 3D replay: the boxes the page draws are the geoms of the MuJoCo scene built from
the same description (read back from the compiled model), the footprints and the ZMP lie on the treads, an obstacle
turns solid when the walk sees it, and a flat floor draws as before. A robot with no geometry keeps it fast."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
mujoco = pytest.importorskip("mujoco")
pytest.importorskip("meshcat")
pytest.importorskip("umsgpack")

from pages import Decoded, decode  # noqa: E402

from rtgait.core.geometry.footsteps import Footstep  # noqa: E402
from rtgait.core.geometry.terrain import Flat, Heightfield, Slope, Stairs, Step, SteppingStones, TerrainKind  # noqa: E402
from rtgait.core.obstacle.box import Obstacle  # noqa: E402
from rtgait.scenario.loading import load_scenario  # noqa: E402
from rtgait.sim.config import SimConfig  # noqa: E402
from rtgait.sim.contact_model import add_floor  # noqa: E402
from rtgait.sim.obstacles import add_obstacles  # noqa: E402
from rtgait.sim.terrain import add_terrain  # noqa: E402
from rtgait.viz import replay_scene  # noqa: E402
from rtgait.viz.replay import write_replay_html  # noqa: E402

TERRAINS = {
    "stairs up": Stairs(0.15, 0.25, 6, "up", start=0.375),
    "stairs down": Stairs(0.15, 0.25, 6, "down", start=0.4),
    "slope up": Slope(math.radians(10.0), 2.0),
    "slope down": Slope(-math.radians(10.0), 2.0, start=0.6),
    "stones": SteppingStones(0.20, 0.15, 0.10, 4, 0.2),
    "step down": Step(-0.03, 0.7),
}
OBSTACLES = (Obstacle(1.2, -0.1, 0.3, 0.2, 0.3, yaw=0.4, seen_at=0.5), Obstacle(2.0, 0.2, 0.2, 0.2, 0.0, seen_at=0.0))
TIMES = np.linspace(0.0, 2.0, 21)  # s


def _scene_page(tmp_path: Path, terrain: TerrainKind | None, footprints=(), obstacles=(), **options) -> Decoded:
    """The replay page of a robot with no geometry (the universe only) over ``terrain``, read back."""
    model, visual = pin.Model(), pin.GeometryModel()
    zmp = np.column_stack([np.linspace(0.0, 2.0, len(TIMES)), np.zeros(len(TIMES))])
    path = tmp_path / "replay.html"
    write_replay_html(path, model, visual, TIMES, np.zeros((len(TIMES), 0)), footprints=footprints, zmp=zmp,
                      terrain=terrain, obstacles=obstacles, **options)  # fmt: skip
    return decode(path.read_text(encoding="utf-8"))


def _mujoco_scene(terrain: TerrainKind, obstacles=()) -> tuple[mujoco.MjModel, mujoco.MjData]:
    spec = mujoco.MjSpec()
    add_floor(spec, SimConfig())
    add_terrain(spec, terrain, SimConfig())
    add_obstacles(spec, obstacles)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _boxes(decoded: Decoded, prefix: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each box drawn under ``prefix``: its full sizes (m) and its pose (4 x 4, relative to its parent node)."""
    poses = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in decoded.commands if c["type"] == "set_transform"}
    boxes = {}
    for command in decoded.commands:
        if command["type"] == "set_object" and command["path"].startswith(prefix) and "/edges" not in command["path"]:
            geometry = command["object"]["geometries"][0]
            assert geometry["type"] == "BoxGeometry"
            size = np.array([geometry["width"], geometry["height"], geometry["depth"]])
            boxes[command["path"]] = (size, poses[command["path"]])
    return boxes


def _geom_pose(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = data.geom_xmat[geom].reshape(3, 3)
    pose[:3, 3] = data.geom_xpos[geom]
    return pose


@pytest.mark.parametrize("name", list(TERRAINS))
def test_the_replay_draws_the_boxes_of_the_mujoco_scene(name: str, tmp_path: Path) -> None:
    terrain = TERRAINS[name]
    model, data = _mujoco_scene(terrain)
    drawn = _boxes(_scene_page(tmp_path, terrain), "/rtgait/terrain/")
    geoms = [g for g in range(model.ngeom) if model.geom(g).name.startswith("terrain_")]
    assert len(drawn) == len(geoms) > 0
    for geom in geoms:
        size, pose = drawn[f"/rtgait/terrain/{model.geom(geom).name}"]
        np.testing.assert_allclose(size, 2.0 * model.geom_size[geom], atol=1e-12)
        np.testing.assert_allclose(pose, _geom_pose(model, data, geom), atol=1e-12)


def test_obstacles_are_the_mujoco_boxes_faint_until_seen_then_solid(tmp_path: Path) -> None:
    model, data = _mujoco_scene(Flat(), OBSTACLES)
    decoded = _scene_page(tmp_path, None, obstacles=OBSTACLES)
    solid = _boxes(decoded, "/rtgait/obstacles/")
    for index, obstacle in enumerate(OBSTACLES):
        geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"obstacle_{index}")
        truth = _geom_pose(model, data, geom)
        node = f"/rtgait/obstacles/obstacle_{index}"
        size, turn = solid[f"{node}/seen/box"]
        np.testing.assert_allclose(size, 2.0 * model.geom_size[geom], atol=1e-12)
        positions = decoded.positions[f"{node}/seen"]  # the animated node that carries the solid box
        seen = decoded.times >= obstacle.seen_at - 1e-6
        np.testing.assert_allclose(positions[seen], np.tile(truth[:3, 3], (seen.sum(), 1)), atol=1e-6)
        assert np.all(positions[~seen, 2] < -100.0)  # out of the scene before it is seen
        world = np.eye(4)
        world[:3, 3] = positions[-1]
        np.testing.assert_allclose(world @ turn, truth, atol=1e-6)
        ghost_size, ghost_pose = solid[f"{node}/ghost"]
        assert not any(f"{node}/ghost".startswith(moving) for moving in decoded.positions)  # under no animated node
        np.testing.assert_allclose(ghost_pose, truth, atol=1e-12)  # in place from the start, just inside the box
        assert np.all(ghost_size < size) and np.all(ghost_size > size - 0.01)
    assert (~(decoded.times >= OBSTACLES[0].seen_at - 1e-6)).sum() > 0  # the first one is seen during the replay


def test_a_stairs_walk_stands_its_footprints_and_zmp_on_the_treads(tmp_path: Path) -> None:
    scenario = load_scenario("stairs-up")
    terrain = scenario.terrain.terrain
    prints = scenario.nominal_footprints()
    decoded = _scene_page(tmp_path, terrain, footprints=prints)
    page = (tmp_path / "replay.html").read_text(encoding="utf-8")
    assert len(_boxes(decoded, "/rtgait/terrain/")) == terrain.count  # five treads and the landing on the floor
    poses = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in decoded.commands if c["type"] == "set_transform"}
    for index, foot in enumerate(prints):
        pose = poses[f"/rtgait/footprints/{index:03d}_{foot.side}"]
        assert pose[2, 3] == pytest.approx(foot.z + 0.5 * replay_scene.FOOTPRINT_THICKNESS, abs=1e-12)
        assert pose[2, 3] - float(terrain.height(pose[0, 3], pose[1, 3])) == pytest.approx(0.001, abs=1e-9)
    zmp = decoded.positions["/rtgait/zmp"]  # on the tread under it, not inside the stairs
    heights = np.asarray(terrain.height(zmp[:, 0], zmp[:, 1]))
    np.testing.assert_allclose(zmp[:, 2], heights + replay_scene.PATH_LIFT, atol=1e-6)
    assert zmp[:, 2].max() > 0.5
    assert "<span>terrain (stairs, as in MuJoCo)</span>" in page


def test_the_grid_is_the_floor_under_stairs_down_and_the_zmp_stays_out_of_the_pit(tmp_path: Path) -> None:
    stairs = TERRAINS["stairs down"]
    decoded = _scene_page(tmp_path, stairs)
    grid = [c for c in decoded.commands if c["type"] == "set_transform" and c["path"] == "/Grid"][-1]
    shift = [c for c in decoded.commands if c["type"] == "set_transform" and c["path"] == "/rtgait"][-1]
    z = np.array(grid["matrix"]).reshape(4, 4).T[2, 3] - np.array(shift["matrix"]).reshape(4, 4).T[2, 3]
    assert z == pytest.approx(-0.9)  # the floor: the foot of the stairs
    stones = TERRAINS["stones"]
    on_stones = [Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.4, -0.1, 0.0, "right")]
    zmp = _scene_page(tmp_path, stones, footprints=on_stones).positions["/rtgait/zmp"]
    assert np.all(np.abs(zmp[:, 2] - replay_scene.PATH_LIFT) < 1e-6)  # over the pit on y = 0 too


def test_a_flat_floor_draws_as_without_a_terrain(tmp_path: Path) -> None:
    def content(decoded: Decoded) -> str:
        text = repr([c for c in decoded.commands if c["type"] != "set_object"])
        objects = [(c["path"], c["object"]["geometries"][0].get("type")) for c in decoded.commands
                   if c["type"] == "set_object"]  # fmt: skip
        return re.sub(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", "", text) + repr(objects)

    prints = [Footstep(0.0, 0.1, 0.0, "left"), Footstep(0.2, -0.1, 0.0, "right")]
    without = _scene_page(tmp_path, None, footprints=prints)
    flat = _scene_page(tmp_path, Flat(), footprints=prints)
    assert content(flat) == content(without)
    assert not any(c["path"].startswith(("/rtgait/terrain", "/rtgait/obstacles")) for c in without.commands)
    np.testing.assert_array_equal(flat.positions["/rtgait/zmp"], without.positions["/rtgait/zmp"])


@pytest.mark.parametrize(
    ("options", "message"),
    [({"terrain": "stairs"}, "terrain must be None or a terrain"), ({"obstacles": [(1.0, 0.0)]}, "obstacles[0] must")],
)
def test_bad_terrain_or_obstacles_are_refused(options: dict, message: str, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        _scene_page(tmp_path, **{"terrain": None, **options})
    assert not (tmp_path / "replay.html").exists()


def test_a_height_field_is_drawn_as_the_triangles_mujoco_collides(tmp_path: Path) -> None:
    # A rough grid that dips below the level ground: its mesh, and the MuJoCo boxes framing it.
    rng = np.random.default_rng(5)
    terrain = Heightfield(rng.uniform(-0.03, 0.05, (6, 9)), (1.6, 0.5), (0.4, -0.25))
    decoded = _scene_page(tmp_path, terrain)
    (mesh,) = [c for c in decoded.commands if c["type"] == "set_object" and c["path"] == "/rtgait/terrain/terrain_grid"]
    geometry = mesh["object"]["geometries"][0]
    # meshcat sends typed arrays as msgpack extensions: their bytes in .data.
    vertices = np.frombuffer(geometry["data"]["attributes"]["position"]["array"].data, "<f4").reshape(-1, 3)
    faces = np.frombuffer(geometry["data"]["index"]["array"].data, "<u4").reshape(-1, 3)
    assert len(vertices) == 6 * 9 and len(faces) == 2 * 5 * 8
    np.testing.assert_allclose(vertices[:, 2], terrain.height(vertices[:, 0], vertices[:, 1]), atol=1e-7)
    # Each triangle lies in the surface MuJoCo builds: its centroid at the terrain's height there.
    corners = vertices[faces.astype(int)]
    centroid = corners.mean(axis=1)
    np.testing.assert_allclose(centroid[:, 2], terrain.height(centroid[:, 0], centroid[:, 1]), atol=1e-6)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(normals[:, 2] > 0.0)  # counter-clockwise from above: lit from above
    model, data = _mujoco_scene(terrain)
    frame = [g for g in range(model.ngeom) if model.geom(g).name.startswith("terrain_") and model.geom_type[g] == 6]
    assert len(frame) == 4  # before, after, left and right of the grid, at the level ground
    for geom in frame:
        path = f"/rtgait/terrain/{model.geom(geom).name}"
        size, pose = _boxes(decoded, path)[path]
        np.testing.assert_allclose(size, 2.0 * model.geom_size[geom], atol=1e-12)
        np.testing.assert_allclose(pose, _geom_pose(model, data, geom), atol=1e-12)
