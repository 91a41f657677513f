"""Measurement of the simulated robot against statics: weight, ZMP under the COM, a push's moment, landings."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.sim.measure import DEFAULT_LANDING_FRACTION, SimMeasurer  # noqa: E402

G = 9.81

# A rigid "table" robot: a base on two feet, sole sites on the soles' bottom faces (z up, x forward). The base
# carries an off-centre mass so that the COM is not over the feet's middle. The feet are boxes on a floor plane, or
# (`spheres`) four corner spheres each on a floor box: MuJoCo puts the geom of lower type first in a contact, so the
# spheres are then geom1 and the force on them is minus the contact force, and each foot has several geoms.
TABLE = """
<mujoco>
  <option timestep="0.001" integrator="implicitfast" gravity="0 0 -{g}"/>
  <worldbody>
    {floor}
    <body name="base" pos="0 0 {height}">
      <freejoint/>
      <geom type="box" size="0.1 0.15 0.05" mass="30" contype="0" conaffinity="0"/>
      <geom type="sphere" size="0.03" pos="{dx} {dy} 0.2" mass="{extra}" contype="0" conaffinity="0"/>
      <body name="left_foot" pos="0 0.1 -0.5">
        {left}
        <site name="left_sole" pos="0 0 0"/>
      </body>
      <body name="right_foot" pos="0 -0.1 -0.5">
        {right}
        <site name="right_sole" pos="0 0 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
PLANE = '<geom name="floor" type="plane" size="0 0 0.05"/>'
BOX = '<geom name="floor" type="box" size="2 2 0.05" pos="0 0 -0.05"/>'
SOLE = '<geom type="box" size="0.1 0.05 0.005" pos="0 0 0.005" mass="1"/>'
CORNERS = "".join(
    f'<geom type="sphere" size="0.005" pos="{x} {y} 0.005" mass="0.25"/>'
    for x in (-0.095, 0.095)
    for y in (-0.045, 0.045)
)


def table(dx=0.04, dy=-0.03, extra=5.0, height=0.5, spheres=False):
    feet = CORNERS if spheres else SOLE
    xml = TABLE.format(g=G, height=height, dx=dx, dy=dy, extra=extra, floor=BOX if spheres else PLANE, left=feet,
                       right=feet)  # fmt: skip
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    ident = lambda kind, name: mujoco.mj_name2id(model, kind, name)  # noqa: E731
    measurer = SimMeasurer(
        model,
        base_body=ident(mujoco.mjtObj.mjOBJ_BODY, "base"),
        left_site=ident(mujoco.mjtObj.mjOBJ_SITE, "left_sole"),
        right_site=ident(mujoco.mjtObj.mjOBJ_SITE, "right_sole"),
        omega=math.sqrt(G / 0.5),
    )
    return model, data, measurer


def run(model, data, seconds):
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)


@pytest.mark.parametrize("spheres", [False, True])
def test_table_at_rest_carries_its_weight_with_the_zmp_under_the_com(spheres):
    model, data, measurer = table(spheres=spheres)
    run(model, data, 0.5)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert all(int(data.contact.geom[i][1 if spheres else 0]) == floor for i in range(data.ncon)), "the case tested"
    m = measurer.measure(data)
    weight = 37.0 * G
    assert m.normal_force == pytest.approx(weight, rel=1e-3)
    assert m.left.normal_force > 0.0 and m.right.normal_force > 0.0
    assert m.left.force[2] + m.right.force[2] == pytest.approx(m.normal_force)
    # Statics: at rest the ZMP is the COM's ground projection (the extra mass puts it 5 mm forward, 4 mm right).
    np.testing.assert_allclose(m.zmp, m.com[:2], atol=5e-4)
    assert m.com[0] > 0.004 and m.com[1] < -0.003
    np.testing.assert_allclose(m.dcm, m.com[:2], atol=1e-4)
    # Each foot's CoP is the force-weighted mean of its contact points (independent of the wrench algebra), and
    # lies on its sole.
    for foot, name in ((m.left, "left_foot"), (m.right, "right_foot")):
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        rows = [i for i in range(data.ncon) if body in model.geom_bodyid[data.contact.geom[i]]]
        force = np.zeros(6)
        weights = []
        for i in rows:
            mujoco.mj_contactForce(model, data, i, force)
            weights.append((data.contact.frame[i].reshape(3, 3).T @ force[:3])[2])  # sign: which geom is the foot
        weights = np.abs(weights)
        mean = (data.contact.pos[rows, :2] * weights[:, None]).sum(axis=0) / weights.sum()
        np.testing.assert_allclose(foot.cop, mean, atol=2e-4)
        assert abs(foot.cop_local[0]) <= 0.1 and abs(foot.cop_local[1]) <= 0.05
        assert foot.contacts == 4 and foot.loaded and foot.tilt < 1e-3
    assert m.support == "double" and m.landings == () and m.other_contacts == 0


def test_a_push_moves_the_zmp_by_its_moment():
    # Statics about the ZMP p: m g (c_x - p_x) + a_z F_x = 0 for a horizontal push F_x at height a_z, so
    # p_x = c_x + a_z F_x / (m g); the normal force stays m g.
    model, data, measurer = table(dx=0.0, dy=0.0, extra=0.0)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base")
    weight = 32.0 * G
    push = (0.08 * weight, -0.05 * weight)
    data.xfrc_applied[base, 0:2] = push
    run(model, data, 0.6)
    m = measurer.measure(data)
    height = data.xipos[base, 2]  # xfrc_applied acts at the body's centre of mass
    assert m.normal_force == pytest.approx(weight, rel=1e-3)
    expected = (m.com[0] + height * push[0] / weight, m.com[1] + height * push[1] / weight)
    np.testing.assert_allclose(m.zmp, expected, atol=1e-3)
    assert m.zmp[0] - m.com[0] > 0.035, "a real shift, not the rest position"


def test_landing_is_detected_once_per_foot_with_its_pose():
    model, data, measurer = table(dx=0.0, dy=0.0, height=0.53)  # 3 cm above the floor: 78 ms of fall
    landings = []
    states = []
    for k in range(300):
        mujoco.mj_step(model, data)
        m = measurer.measure(data, t=k * 0.001)
        landings.extend(m.landings)
        states.append(m.support)
    assert states[0] == "none" and states[-1] == "double"
    assert sorted(landing.side for landing in landings) == ["left", "right"]
    for landing in landings:
        assert 0.07 <= landing.t <= 0.09
        assert abs(landing.z) < 2e-3 and abs(landing.yaw) < 1e-6 and abs(landing.roll) < 1e-3
        assert landing.normal_force >= measurer.landing_force
        assert landing.y == pytest.approx(0.1 if landing.side == "left" else -0.1, abs=1e-3)
        assert landing.footstep().side == landing.side


def test_load_hysteresis_and_the_flight_time_of_a_landing():
    model, data, measurer = table(dx=0.0, dy=0.0, extra=0.0)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base")
    weight = 32.0 * G
    assert measurer.landing_force == pytest.approx(DEFAULT_LANDING_FRACTION * weight)
    assert measurer.release_force == pytest.approx(0.5 * measurer.landing_force)
    t = [0.0]

    def hold(load_per_foot, seconds, ramp=0.1):
        """Lift the table so that each foot carries `load_per_foot` (fraction of the weight), reached over `ramp`
        seconds (a sudden change would make the table bounce on its soft contacts)."""
        before = data.xfrc_applied[base, 2]
        after = weight * (1.0 - 2.0 * load_per_foot)
        found = []
        n = round(seconds / 0.001)
        for k in range(n):
            data.xfrc_applied[base, 2] = before + (after - before) * min(1.0, (k + 1) * 0.001 / ramp if ramp else 1.0)
            mujoco.mj_step(model, data)
            t[0] += 0.001
            m = measurer.measure(data, t[0])
            found.extend(m.landings)
        return m, found

    m, found = hold(0.5, 0.3)
    assert m.left.loaded and m.right.loaded and not found  # loaded from the first measurement: no landing
    m, _ = hold(0.02, 0.15)  # between the release (1.4 %) and landing (2.8 %) thresholds: stays loaded
    assert m.left.loaded and m.right.loaded
    m, _ = hold(0.005, 0.15)  # below the release threshold: unloaded
    assert not m.left.loaded and not m.right.loaded
    m, found = hold(0.02, 0.15)  # between the thresholds again: stays unloaded
    assert not m.left.loaded and not found
    m, found = hold(0.5, 0.1)  # loaded after more than min_unloaded_time "in the air": a landing per foot
    assert m.left.loaded and sorted(f.side for f in found) == ["left", "right"]
    # A scuff: lifted off for 15 ms (an upward push of 1.3 times the weight), then down again, bouncing; no flight
    # lasts min_unloaded_time, so no landing.
    states, found = [], []
    for k in range(100):
        data.xfrc_applied[base, 2] = 1.3 * weight if k < 15 else 0.0
        mujoco.mj_step(model, data)
        m = measurer.measure(data, t[0] + 0.001 * (k + 1))
        states.append(m.left.loaded)
        found.extend(m.landings)
    assert not all(states) and states[-1] and not found


def test_talos_standing_weight_zmp_and_com(talos, talos_sim):
    data = talos_sim.new_data()
    measurer = SimMeasurer.for_sim(talos_sim)
    run(talos_sim.model, data, 0.5)
    mujoco.mj_forward(talos_sim.model, data)  # everything at data.time, for the comparison with Pinocchio
    m = measurer.measure(data)
    weight = talos.mass * 9.81
    assert m.normal_force == pytest.approx(weight, rel=0.01)
    np.testing.assert_allclose(m.zmp, m.com[:2], atol=2e-3)
    for foot, y in ((m.left, 0.5 * talos.step_width), (m.right, -0.5 * talos.step_width)):
        assert foot.loaded and foot.contacts >= 2 and foot.tilt < 0.01  # a box on a plane: its lowest corners
        np.testing.assert_allclose(foot.pose, (0.0, y, 0.0, 0.0), atol=3e-3)
    # MuJoCo's COM and COM velocity are Pinocchio's for the same state (same URDF inertias).
    pin = pytest.importorskip("pinocchio")
    q = talos_sim.pinocchio_from_qpos(data.qpos)
    v = np.empty(talos.model.nv)
    rotation = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
    v[0:3] = rotation.T @ data.qvel[0:3]  # MuJoCo: world linear velocity; Pinocchio: in the base frame
    v[3:6] = data.qvel[3:6]
    v[6:] = data.qvel[talos_sim.dof_index]
    pdata = talos.model.createData()
    pin.centerOfMass(talos.model, pdata, q, v)
    np.testing.assert_allclose(m.com, pdata.com[0], atol=1e-9)
    np.testing.assert_allclose(m.com_vel, pdata.vcom[0], atol=1e-9)


def test_talos_pushed_zmp_follows_statics(talos, talos_sim):
    data = talos_sim.new_data()
    measurer = SimMeasurer.for_sim(talos_sim)
    force = 40.0  # N forward on the pelvis
    data.xfrc_applied[talos_sim.base_body, 0] = force
    run(talos_sim.model, data, 1.2)
    m = measurer.measure(data)
    height = data.xipos[talos_sim.base_body, 2]
    weight = talos.mass * 9.81
    assert m.normal_force == pytest.approx(weight, rel=0.01)
    assert m.zmp[0] == pytest.approx(m.com[0] + height * force / weight, abs=2e-3)
    assert m.zmp[1] == pytest.approx(m.com[1], abs=2e-3)
    assert m.zmp[0] - m.com[0] > 0.03
