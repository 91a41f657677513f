"""Contact in physics: feet that do not creep under static friction, legs that collide with each other, and
outcomes that do not depend on the physics step."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.core.analysis.rollout import ScheduledChange  # noqa: E402
from rtgait.core.geometry.footsteps import Stride  # noqa: E402
from rtgait.core.planner.online import OnlinePlanner  # noqa: E402
from rtgait.io.sim_run import simulate  # noqa: E402
from rtgait.robot.motion import robot_scenario  # noqa: E402
from rtgait.sim.loop import LoopOptions  # noqa: E402
from rtgait.sim.model import SimConfig, build_sim_model  # noqa: E402
from rtgait.sim.run_loop import run_sim_loop  # noqa: E402


def feet_drift(sim, force: tuple[float, float, float], seconds: float) -> np.ndarray:
    """How far each sole point moves horizontally (m) while the robot stands, pushed at the base by ``force`` (N)."""
    data = sim.new_data()
    sites = [sim.left_sole_site, sim.right_sole_site]
    start = data.site_xpos[sites, :2].copy()
    data.xfrc_applied[sim.base_body, 0:3] = force
    for _ in range(round(seconds / sim.timestep)):
        mujoco.mj_step(sim.model, data)
    return np.linalg.norm(data.site_xpos[sites, :2] - start, axis=1)


def test_feet_do_not_creep_under_a_push_below_the_friction_limit(talos, talos_sim):
    # 50 N sideways and forward on a 90 kg robot standing on friction 1: a twentieth of what the soles can hold.
    force = (30.0, 40.0, 0.0)
    assert np.hypot(*force[:2]) < 0.1 * talos_sim.config.friction * talos.mass * 9.81
    drift = feet_drift(talos_sim, force, 3.0)
    assert drift.max() < 1e-3, f"the feet moved {drift * 1000} mm in 3 s"
    # The same push without MuJoCo's no-slip solver: the soft contact lets the loaded feet creep.
    creeping = build_sim_model(talos, SimConfig(meshes=False, noslip_iterations=0))
    assert feet_drift(creeping, force, 3.0).max() > 1e-3


def test_a_step_onto_the_other_foot_makes_the_legs_collide(talos, talos_sim, shorten):
    """A stride 0.10 m wide puts the swing sole (0.13 m wide) 3 cm over the stance one: the leg boxes meet, which
    they never do in a walk at the robot's step width."""
    config = robot_scenario(shorten("fig8", 1), talos).planner_config()
    options = LoopOptions(start_ramp=0.5, start_hold=0.2)

    def walk(width: float):
        planner = OnlinePlanner(config, [Stride(0.0, width), Stride(0.0, config.step_width)])
        return run_sim_loop(talos_sim, planner, options)

    normal = walk(config.step_width)
    assert not normal.legs_touched and not normal.fell
    crossing = walk(0.10)
    assert crossing.legs_touched
    touched = crossing.times[np.argmax(crossing.legs_touch)]
    # During the first step's swing: after its lift-off (walk start + start phase), before the next one.
    lift_off = crossing.walk_start + config.timing.start
    assert lift_off < touched < lift_off + config.timing.single_support + config.timing.double_support
    assert crossing.fell or crossing.tipped, "the feet in each other's way: the robot cannot walk on"


@pytest.mark.parametrize(
    ("name", "steps", "changes"),
    [
        ("fig8", 4, (ScheduledChange(4, length=0.15),)),  # a feasible walk (the short_walk fixture's)
        ("fig4", 3, (ScheduledChange(2, length=0.15, through=3),)),  # its ZMP leaves the support polygon
    ],
)
def test_the_outcome_does_not_flip_when_the_physics_step_is_halved(talos, talos_sim, shorten, name, steps, changes):
    scenario = shorten(name, steps, changes)
    fine = build_sim_model(talos, SimConfig(meshes=False, physics_dt=0.0005))
    assert fine.substeps == 2 and talos_sim.substeps == 1
    # The paper's outcome, of the plan alone: open loop.
    results = [simulate(scenario, talos, sim=sim, controller="open-loop") for sim in (talos_sim, fine)]
    walked = [not r.fell and not r.tipped and r.steps_completed == r.steps_planned for r in results]
    lost = [r.fell or r.tipped for r in results]
    assert walked[0] == walked[1] and lost[0] == lost[1]
    assert walked[0] == (name == "fig8")


def test_the_leg_shapes_are_the_links_convex_hulls(talos, talos_sim):
    """Each leg shape is the convex hull of its link's geometry (the same volume as the hull of all its points), and
    the hulls leave the thighs apart where their bounding boxes met: each of Talos's hips rolled 0.15 rad outward (the
    feet 0.39 m apart, wider than a 0.1 m/s sideways walk's widest stance), its thighs are still 5 mm apart; their
    boxes, reaching 79 mm inward of the hip axis, met once the thighs rolled 0.15 rad apart in all."""
    import xml.etree.ElementTree as ElementTree

    import mujoco
    from scipy.spatial import ConvexHull

    from rtgait.sim.contact_model import _link_points, leg_shapes

    description = talos.description
    root = ElementTree.parse(description.urdf).getroot()
    shapes = leg_shapes(talos)
    assert len(shapes) == 12
    for shape in shapes:
        points = _link_points(root, shape.link, description.urdf, description.package_dirs)
        assert ConvexHull(shape.vertices).volume == pytest.approx(ConvexHull(points).volume, rel=1e-9)
        assert len(shape.vertices) < len(points)
    model, data = talos_sim.model, talos_sim.new_data()
    for side, sign in (("left", 1.0), ("right", -1.0)):
        joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"leg_{side}_2_joint")  # hip roll
        data.qpos[model.jnt_qposadr[joint]] += sign * 0.15
    mujoco.mj_kinematics(model, data)
    thighs = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"leg_{s}_3_link_shape") for s in ("left", "right")]
    assert mujoco.mj_geomDistance(model, data, thighs[0], thighs[1], 0.5, None) > 0.005
