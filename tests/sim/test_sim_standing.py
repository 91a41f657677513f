"""Standing still in physics: a stable robot, and a measured ZMP that obeys static equilibrium."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.interface.task_targets import IKTargets  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.sim.contact_reading import ContactReader  # noqa: E402
from rtgait.sim.step_snapshot import read_snapshot  # noqa: E402


def stand(sim, seconds: float, q=None):
    """Hold the start posture for ``seconds`` of physics; returns the state and the base positions per tick."""
    data = sim.new_data(q=q)
    n = round(seconds / sim.timestep)
    base = np.empty((n, 7))
    for k in range(n):
        mujoco.mj_step(sim.model, data)
        base[k] = data.qpos[:7]
    return data, base


def test_standing_still_is_stable(talos_sim):
    data, base = stand(talos_sim, 2.0)
    drift = np.linalg.norm(base[:, :3] - talos_sim.qpos_half_sitting[:3], axis=1)
    assert drift.max() < 0.01, "the base stays within 1 cm of half-sitting"
    tilt = np.arccos(np.clip(1.0 - 2.0 * (base[:, 4] ** 2 + base[:, 5] ** 2), -1.0, 1.0))
    assert tilt.max() < 0.01, "the base stays upright (rad)"
    assert np.abs(data.qvel).max() < 1e-3, "at rest after 2 s"


@pytest.mark.parametrize("cog_xy", [(0.0, 0.0), (0.04, -0.05), (-0.05, 0.06)])
def test_measured_cop_is_the_cog_projection(talos, talos_sim, cog_xy):
    # Static equilibrium (independent of any model of walking): at rest, the contact forces carry the weight and
    # their centre of pressure lies under the COG. The COG is moved off-centre by the IK to make it a real test.
    ik = WholeBodyIK(talos)
    half = 0.5 * talos.step_width
    target = IKTargets((*cog_xy, talos.description.cog_height), (0.0, half, 0.0, 0.0), (0.0, -half, 0.0, 0.0))
    q, errors = ik.solve(target, talos.q_half_sitting, max_iterations=100, tolerance=1e-9)
    assert errors.cog < 1e-6
    data, _ = stand(talos_sim, 1.5, q)
    sx, sy, f_left, f_right, corners_left, corners_right = _sole_record(talos_sim, data)
    weight = talos.mass * 9.81
    total = f_left + f_right
    assert total == pytest.approx(weight, rel=2e-3)
    cog = data.subtree_com[talos_sim.base_body]
    np.testing.assert_allclose((sx / total, sy / total), cog[:2], atol=1e-3)
    np.testing.assert_allclose(cog[:2], cog_xy, atol=3e-3)
    assert min(corners_left, corners_right) >= 3 and min(f_left, f_right) > 0.05 * weight, "standing on both feet"


def test_contact_measurement_matches_mj_contact_force(talos_sim):
    # The loop reads the pyramidal edge forces directly; MuJoCo's own mj_contactForce, rotated to the world, must
    # give the same vertical forces and centre of pressure.
    data, _ = stand(talos_sim, 0.3)
    force = np.zeros(6)
    sums = np.zeros(3)
    per_foot = {talos_sim.left_sole_geom: 0.0, talos_sim.right_sole_geom: 0.0}
    for i in range(data.ncon):
        contact = data.contact[i]
        mujoco.mj_contactForce(talos_sim.model, data, i, force)
        world = contact.frame.reshape(3, 3).T @ force[:3]
        sums += (contact.pos[0] * world[2], contact.pos[1] * world[2], world[2])
        per_foot[int(contact.geom2 if contact.geom1 == talos_sim.floor_geom else contact.geom1)] += world[2]
    sx, sy, f_left, f_right, _, _ = _sole_record(talos_sim, data)
    np.testing.assert_allclose((sx, sy, f_left + f_right), sums, rtol=1e-9, atol=1e-9)
    # The truth's full contact force on each foot: the same vertical forces.
    decoded = ContactReader.for_sim(talos_sim).read(data, read_snapshot(data))
    assert decoded.left_force[2] == pytest.approx(per_foot[talos_sim.left_sole_geom], rel=1e-9)
    assert decoded.right_force[2] == pytest.approx(per_foot[talos_sim.right_sole_geom], rel=1e-9)
    assert f_left == pytest.approx(per_foot[talos_sim.left_sole_geom], rel=1e-9)
    assert f_right == pytest.approx(per_foot[talos_sim.right_sole_geom], rel=1e-9)


def _sole_record(sim, data) -> tuple[float, float, float, float, int, int]:
    """The contact record's sums of ``data``'s last step: ``sum p_x f_n``, ``sum p_y f_n`` (N m), the normal force
    on each sole (N) and how many corners of each sole box touch."""
    sums = ContactReader.for_sim(sim).read(data, read_snapshot(data))
    return (
        sums.sole_moment_x, sums.sole_moment_y, sums.left_normal, sums.right_normal, sums.left_corners,
        sums.right_corners,
    )  # fmt: skip
