"""The scenario's obstacles in MuJoCo: a box geom where the scenario puts it, which a sole lands on as on the floor,
and the reactions the loop hands the planner when an obstacle is seen."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rtgait.core.obstacle.box import Obstacle  # noqa: E402
from rtgait.sim.contact_model import SOLE_BITS  # noqa: E402
from rtgait.sim.loop_inputs import WalkInputs  # noqa: E402
from rtgait.sim.loop_options import LoopOptions  # noqa: E402
from rtgait.sim.obstacles import add_obstacles, obstacle_geom_name  # noqa: E402


def test_a_box_stands_where_the_scenario_puts_it_and_a_sole_lands_on_it() -> None:
    box = Obstacle(x=1.0, y=-0.2, length=0.3, width=0.2, height=0.25, yaw=math.pi / 2, seen_at=1.0)
    spec = mujoco.MjSpec()
    add_obstacles(spec, [box])
    # A sole-like block with the soles' contact bits, dropped from 5 cm above the box's top.
    body = spec.worldbody.add_body(name="sole", pos=[1.0, -0.2, 0.35])
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.05, 0.02], contype=SOLE_BITS[0],
                  conaffinity=SOLE_BITS[1], mass=1.0)  # fmt: skip
    model = spec.compile()
    data = mujoco.MjData(model)
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, obstacle_geom_name(0))
    np.testing.assert_allclose(model.geom_size[geom], [0.15, 0.10, 0.125])
    np.testing.assert_allclose(model.geom_pos[geom], [1.0, -0.2, 0.125])
    mujoco.mj_forward(model, data)
    corner = data.geom_xpos[geom] + data.geom_xmat[geom].reshape(3, 3) @ model.geom_size[geom]
    np.testing.assert_allclose(corner[:2], [1.0 - 0.10, -0.2 + 0.15], atol=1e-12)  # turned a quarter turn
    for _ in range(1000):
        mujoco.mj_step(model, data)
    assert data.qpos[2] == pytest.approx(0.25 + 0.02, abs=3e-3)  # resting on the box's top, not fallen through


class _Planner:
    def __init__(self) -> None:
        self.calls: list[float] = []

    def change_deadline(self, step: int) -> float:
        return math.inf

    def first_open_step(self) -> int:
        return 1


def test_a_reaction_is_handed_the_planner_once_at_the_first_tick_at_or_after_its_time() -> None:
    planner = _Planner()
    options = LoopOptions(reactions=((0.25, lambda p, t: p.calls.append(t)),))
    inputs = WalkInputs(planner, options, stop_after=None)  # type: ignore[arg-type]
    inputs.start()
    for t in (0.0, 0.2, 0.3, 0.4):
        inputs.update(t, None)  # type: ignore[arg-type]
    assert planner.calls == [0.3]
