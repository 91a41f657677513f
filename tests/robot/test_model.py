"""The loaded models: half-sitting on the ground, reduced vs full model, sole frames with an offset."""

from __future__ import annotations

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.robot.model import RobotModel  # noqa: E402


def full_kinematics(robot: RobotModel, q_full: np.ndarray) -> tuple[np.ndarray, pin.SE3, pin.SE3]:
    """COG and both sole placements by forward kinematics of the FULL model (independent of the reduced one)."""
    data = robot.full_model.createData()
    pin.framesForwardKinematics(robot.full_model, data, q_full)
    com = pin.centerOfMass(robot.full_model, data, q_full).copy()
    return com, data.oMf[robot.full_left_sole_id].copy(), data.oMf[robot.full_right_sole_id].copy()


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_half_sitting_stands_on_the_ground(name, request):
    robot = request.getfixturevalue(name)
    com, left, right = full_kinematics(robot, robot.q_full_half_sitting)
    for sole in (left, right):
        assert abs(sole.translation[2]) < 5e-4, "sole on the ground (z = 0)"
        assert sole.rotation[2, 2] > np.cos(0.005), "sole level"
        assert abs(np.arctan2(sole.rotation[1, 0], sole.rotation[0, 0])) < 1e-3, "heading +x"
    middle = 0.5 * (left.translation + right.translation)
    np.testing.assert_allclose(middle[:2], 0.0, atol=1e-9)
    assert left.translation[1] > 0.0 > right.translation[1]
    assert robot.step_width == pytest.approx(left.translation[1] - right.translation[1], abs=1e-6)
    # Standing: the COG above the support polygon, above the walking height (knees stay bent when walking).
    sole = robot.description.sole
    assert -sole.back < com[0] < sole.front
    assert abs(com[1]) < 0.5 * robot.step_width
    assert com[2] > robot.description.cog_height
    np.testing.assert_allclose(robot.cog_half_sitting, com, atol=1e-12)


def test_talos_numbers(talos):
    assert talos.mass == pytest.approx(90.272, abs=1e-3)
    assert talos.mass == pytest.approx(pin.computeTotalMass(talos.full_model), abs=1e-9)
    assert talos.step_width == pytest.approx(0.17, abs=1e-3)
    assert talos.cog_half_sitting[2] == pytest.approx(0.8767, abs=1e-3)
    # The SRDF's half_sitting puts the base at 1.01927 m; ours differs only by where the soles are.
    assert talos.q_half_sitting[2] == pytest.approx(1.01927, abs=1e-3)
    assert set(talos.joint_names) == set(talos.description.moving_joints)
    assert len(talos.full_joint_names) == talos.full_model.nq - 7
    assert talos.model.nq == 7 + 14


@pytest.mark.parametrize("name", ["talos", "g1"])
def test_reduced_and_full_models_agree(name, request):
    # Moving joints anywhere in their range: the reduced model (locked joints merged into their parents) must
    # put the COG and the soles exactly where the full model with the locked joints at half-sitting does.
    robot = request.getfixturevalue(name)
    rng = np.random.default_rng(3)
    model = robot.model
    for _ in range(5):
        q = robot.q_half_sitting.copy()
        lower, upper = model.lowerPositionLimit[7:], model.upperPositionLimit[7:]
        q[7:] = lower + rng.random(model.nq - 7) * (upper - lower)
        q[:7] = pin.SE3ToXYZQUAT(pin.SE3.Random())
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        com = pin.centerOfMass(model, data, q)
        full_com, full_left, full_right = full_kinematics(robot, robot.full_configuration(q))
        np.testing.assert_allclose(com, full_com, atol=1e-12)
        assert (data.oMf[robot.left_sole_id].inverse() * full_left).isIdentity(1e-12)
        assert (data.oMf[robot.right_sole_id].inverse() * full_right).isIdentity(1e-12)
    batch = robot.full_configuration(np.tile(robot.q_half_sitting, (3, 1)))
    np.testing.assert_array_equal(batch, np.tile(robot.q_full_half_sitting, (3, 1)))
    with pytest.raises(ValueError, match="coordinates per row"):
        robot.full_configuration(np.zeros(5))


def test_sole_offset_frames_are_below_the_ankles(g1):
    # G1's description puts the sole point 0.035 m below each ankle roll link.
    data = g1.full_model.createData()
    pin.framesForwardKinematics(g1.full_model, data, g1.q_full_half_sitting)
    for side, sole_id in (("left", g1.full_left_sole_id), ("right", g1.full_right_sole_id)):
        ankle = data.oMf[g1.full_model.getFrameId(f"{side}_ankle_roll_link")]
        local = ankle.inverse() * data.oMf[sole_id]
        np.testing.assert_allclose(local.translation, [0.0, 0.0, -0.035], atol=1e-12)
        assert ankle.translation[2] == pytest.approx(0.035, abs=5e-4)
