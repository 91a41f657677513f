"""Down Talos's 0.185 m stairs the folded swing leg's thigh passes the stance thigh only with the swing path bent
toward the stance foot (``walking.descent_bend``): the planned motion, posed in the MuJoCo model, measured against the
legs' own collision hulls (MuJoCo's distance between the two thighs' convex shapes, independent of the planner)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.io.sim_run import planned_walk  # noqa: E402
from rtgait.robot.motion import ERROR_FIELDS, whole_body_motion  # noqa: E402
from rtgait.scenario.loading import load_scenario  # noqa: E402
from rtgait.sim.contact_model import leg_shapes  # noqa: E402

_CLEARANCE = 0.002  # m: the model's own "touching" (rtgait.sim.contact_model), kept between the thighs by the bend


def _thighs_gap(robot, sim, scenario: str) -> float:
    """Least distance (m; negative: overlap) between the thighs' collision hulls over the planned motion."""
    motion = whole_body_motion(
        robot, planned_walk(load_scenario(scenario), robot), limits=dict.fromkeys(ERROR_FIELDS, np.inf)
    )
    names = {shape.link: shape.geom_name for shape in leg_shapes(robot)}
    left, right = (
        mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, names[f"leg_{s}_3_link"]) for s in ("left", "right")
    )
    data = mujoco.MjData(sim.model)
    gap = np.inf
    for q in motion.q:
        data.qpos[:] = sim.qpos_from_pinocchio(q)
        mujoco.mj_kinematics(sim.model, data)
        gap = min(gap, mujoco.mj_geomDistance(sim.model, data, left, right, 0.1, None))
    return gap


def test_talos_thighs_pass_each_other_down_the_185_stairs_only_with_its_bend(talos, talos_sim) -> None:
    assert talos.description.descent_bend == 0.035
    assert _thighs_gap(talos, talos_sim, "stairs-down-185") >= _CLEARANCE
    straight = dataclasses.replace(talos, description=dataclasses.replace(talos.description, descent_bend=0.0))
    assert _thighs_gap(straight, talos_sim, "stairs-down-185") < 0.0  # the hulls overlap
    # A millimetre less bend no longer keeps the model's clearance: the value is the least that does.
    less = dataclasses.replace(talos, description=dataclasses.replace(talos.description, descent_bend=0.034))
    assert _thighs_gap(less, talos_sim, "stairs-down-185") < _CLEARANCE
