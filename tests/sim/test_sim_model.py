"""The MuJoCo model built from the robot description: structure, and kinematics identical to Pinocchio's."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pin = pytest.importorskip("pinocchio")

from rtgait.sim.model import SimConfig, build_sim_model  # noqa: E402


def test_structure(talos, talos_sim):
    model = talos_sim.model
    # A free joint plus the 14 moving joints; every other URDF joint is locked.
    assert model.nq == 7 + 14 and model.nv == 6 + 14
    assert model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert model.opt.timestep == 0.001
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert float(model.body_mass.sum()) == pytest.approx(talos.mass, rel=1e-9)
    # Actuator i drives joint i of the IK's order, found by name.
    assert model.nu == len(talos.joint_names)
    for i, name in enumerate(talos.joint_names):
        joint = model.actuator_trnid[i, 0]
        assert mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) == name
        assert model.jnt_qposadr[joint] == talos_sim.qpos_index[i]
    # PD servos: force = kp * (ctrl - q) - kd * qdot, clipped to the URDF's effort limit; armature on each joint.
    np.testing.assert_allclose(model.actuator_gainprm[:, 0], talos_sim.kp)
    np.testing.assert_allclose(model.actuator_biasprm[:, 1], -talos_sim.kp)
    np.testing.assert_allclose(model.actuator_biasprm[:, 2], -talos_sim.kd)
    efforts = [talos.model.effortLimit[talos.model.joints[talos.model.getJointId(n)].idx_v] for n in talos.joint_names]
    assert model.actuator_forcelimited.all()
    np.testing.assert_allclose(model.actuator_forcerange[:, 1], efforts)
    np.testing.assert_allclose(model.actuator_forcerange[:, 0], -np.array(efforts))
    np.testing.assert_allclose(model.dof_armature[talos_sim.dof_index], talos_sim.actuation.armature)
    assert model.opt.noslip_iterations > 0


def test_only_the_soles_touch_the_floor_and_the_legs_each_other(talos, talos_sim):
    model = talos_sim.model
    sole = talos.description.sole
    colliding = []
    for a in range(model.ngeom):
        for b in range(a + 1, model.ngeom):
            ok = (model.geom_contype[a] & model.geom_conaffinity[b]) or (
                model.geom_contype[b] & model.geom_conaffinity[a]
            )
            if ok:
                colliding.append({a, b})
    floor = talos_sim.floor_geom
    legs = talos_sim.leg_geoms
    # One convex hull per leg link (6 per leg), on the link's body; the left leg's against the right leg's only.
    assert len(legs) == 12
    bodies = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.geom_bodyid[g]) for g in legs]
    assert bodies == [f"leg_{side}_{i}_link" for side in ("left", "right") for i in range(1, 7)]
    left, right = legs[:6], legs[6:]
    expected = [sorted({floor, talos_sim.left_sole_geom}), sorted({floor, talos_sim.right_sole_geom})]
    expected += [sorted({a, b}) for a in left for b in right]
    assert sorted(sorted(pair) for pair in colliding) == sorted(expected)
    # At half-sitting no pair of leg shapes touches (none had to be excluded), nor the soles anything but the floor.
    assert all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH for g in legs)
    assert talos_sim.excluded_leg_pairs == ()
    data = talos_sim.new_data()
    assert data.ncon > 0 and all(talos_sim.floor_geom in data.contact.geom[i] for i in range(data.ncon))
    for geom in (talos_sim.left_sole_geom, talos_sim.right_sole_geom):
        assert model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_BOX
        half = model.geom_size[geom]
        assert half[0] == pytest.approx(0.5 * (sole.front + sole.back))
        assert half[1] == pytest.approx(0.5 * (sole.inner + sole.outer))


def test_soles_at_half_sitting(talos, talos_sim):
    # The sole boxes' bottom faces lie on the floor, centred on the described sole rectangle.
    data = mujoco.MjData(talos_sim.model)
    data.qpos[:] = talos_sim.qpos_half_sitting
    mujoco.mj_forward(talos_sim.model, data)
    sole = talos.description.sole
    for geom, site, inward in (
        (talos_sim.left_sole_geom, talos_sim.left_sole_site, -1.0),
        (talos_sim.right_sole_geom, talos_sim.right_sole_site, 1.0),
    ):
        rotation = data.geom_xmat[geom].reshape(3, 3)
        half = talos_sim.model.geom_size[geom]
        bottom = data.geom_xpos[geom] - rotation[:, 2] * half[2]
        assert bottom[2] == pytest.approx(0.0, abs=5e-4)
        offset = bottom - data.site_xpos[site]
        assert offset[0] == pytest.approx(0.5 * (sole.front - sole.back), abs=5e-4)
        assert offset[1] == pytest.approx(inward * 0.5 * (sole.inner - sole.outer), abs=5e-4)


def test_kinematics_match_pinocchio(talos, talos_sim):
    # Random base poses and joint angles: MuJoCo's COG and sole frames must equal Pinocchio's (independent model
    # of the same URDF), which checks the joint mapping by name, the quaternion order and the locked joints.
    rng = np.random.default_rng(7)
    model = talos.model
    pdata = model.createData()
    data = mujoco.MjData(talos_sim.model)
    for _ in range(5):
        q = pin.randomConfiguration(
            model, np.maximum(model.lowerPositionLimit, -1.0), np.minimum(model.upperPositionLimit, 1.0)
        )
        q[:3] = rng.uniform(-1.0, 1.0, 3)
        talos_sim.qpos_from_pinocchio(q, out=data.qpos)
        mujoco.mj_kinematics(talos_sim.model, data)
        mujoco.mj_comPos(talos_sim.model, data)
        pin.framesForwardKinematics(model, pdata, q)
        np.testing.assert_allclose(data.subtree_com[talos_sim.base_body], pin.centerOfMass(model, pdata, q), atol=1e-9)
        for site, frame in (
            (talos_sim.left_sole_site, talos.left_sole_id),
            (talos_sim.right_sole_site, talos.right_sole_id),
        ):
            np.testing.assert_allclose(data.site_xpos[site], pdata.oMf[frame].translation, atol=1e-9)
            np.testing.assert_allclose(data.site_xmat[site].reshape(3, 3), pdata.oMf[frame].rotation, atol=1e-9)
        np.testing.assert_allclose(talos_sim.pinocchio_from_qpos(data.qpos), q, atol=1e-12)


def test_meshes_are_visual_only(talos):
    sim = build_sim_model(talos)  # with the visual meshes
    model = sim.model
    legs = set(sim.leg_geoms)  # the legs' collision shapes are convex meshes too: the hulls of their links
    meshes = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and g not in legs]
    assert len(meshes) > 20
    assert all(model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0 for g in meshes)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("physics_dt", 0.0),
        ("friction", -1.0),
        ("contact_timeconst", 0.001),
        ("contact_dampratio", 0.0),
        ("gain_scale", 0.0),
        ("armature_scale", -0.1),
        ("noslip_iterations", -1),
        ("control_dt", 0.0),
    ],
)
def test_bad_config(field, value):
    extra = {"physics_dt": 0.001} if field == "contact_timeconst" else {}  # two steps of a step given
    with pytest.raises(ValueError, match=field):
        SimConfig(**{field: value}, **extra)


def test_the_physics_step_is_the_descriptions_unless_given():
    from rtgait.robot.model import RobotModel

    g1 = RobotModel.load("g1")
    assert SimConfig().resolved(g1).physics_dt == g1.description.actuation.physics_dt == 0.0005
    assert SimConfig(physics_dt=0.001).resolved(g1).physics_dt == 0.001
    with pytest.raises(ValueError, match="contact_timeconst"):
        SimConfig(contact_timeconst=0.0008).resolved(g1)  # fewer than two of G1's 0.5 ms steps


ROMEO = """name = "romeo"
[model]
urdf = "example-robot-data:romeo_description/urdf/romeo.urdf"
[feet]
left_sole_frame = "l_sole"
right_sole_frame = "r_sole"
[feet.sole]
front = 0.11
back = 0.07
inner = 0.045
outer = 0.045
[walking]
cog_height = 0.60
moving_joints = ["LHipYaw", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll",
                 "RHipYaw", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll", "TrunkYaw"]
torso_frame = "torso"
[posture]
LHipPitch = -0.3490658
LKneePitch = 0.6981317
LAnklePitch = -0.3490658
RHipPitch = -0.3490658
RKneePitch = 0.6981317
RAnklePitch = -0.3490658
"""


def test_a_robot_with_meshes_mujoco_cannot_decode_still_builds_with_one_note(tmp_path):
    """Romeo's visual meshes are COLLADA (.dae), which MuJoCo does not read, and its fingers are coupled by <mimic>
    joints: the model builds without them (one warning), with the same mass as Pinocchio's."""
    from rtgait.robot.model import RobotModel
    from rtgait.sim.model import MeshSkippedWarning

    path = tmp_path / "romeo.toml"
    path.write_text(ROMEO, encoding="utf-8")
    robot = RobotModel.load(str(path))
    with pytest.warns(MeshSkippedWarning, match=r"romeo: visual meshes MuJoCo cannot decode \(\d+ \.dae\)") as caught:
        sim = build_sim_model(robot)
    assert len(caught) == 1 and "\n" not in str(caught[0].message)
    assert sim.model.body_subtreemass[sim.base_body] == pytest.approx(robot.mass)
