"""The stack's feed-forward torques: off by default (the commands unchanged), and when on, the static torques that
hold the robot on the wrenches the split asks for, clipped to the joints' limits (no physics)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.control.settings import ControlTargets  # noqa: E402
from rtgait.interface.task_targets import FootOffsets, IKTargets  # noqa: E402
from rtgait.robot.joint_inertia import damping_gains  # noqa: E402
from rtgait.robot.joint_limits import joint_limits  # noqa: E402
from rtgait.robot.model import RobotModel  # noqa: E402
from rtgait.robot.motion import robot_scenario  # noqa: E402
from rtgait.scenario import load_scenario  # noqa: E402
from rtgait.stack.feedforward import FeedForward  # noqa: E402
from rtgait.stack.safety import SafetyLayer  # noqa: E402
from rtgait.stack.setup import walking_stack  # noqa: E402

DT = 0.001


@pytest.fixture(scope="module")
def talos() -> RobotModel:
    return RobotModel.load("talos")


@pytest.fixture(scope="module")
def walk(talos):
    return robot_scenario(load_scenario("fig8"), talos)


def _standing(talos, dy: float = 0.0) -> IKTargets:
    half = 0.5 * talos.step_width
    return IKTargets((0.01, dy, talos.description.cog_height), (0.0, half, 0.0, 0.0), (0.0, -half, 0.0, 0.0))


def _static_torques(talos, q: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """Gravity's joint torques less the soles' wrenches', each Jacobian computed on its own."""
    model = talos.model
    data = model.createData()
    tau = pin.computeGeneralizedGravity(model, data, q).copy()
    for frame, wrench in zip((talos.left_sole_id, talos.right_sole_id), wrenches, strict=True):
        tau -= pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL).T @ wrench
    return tau


def test_the_feed_forward_leaves_the_positions_and_velocities_as_they_are(talos, walk):
    # Off (the default), no torques; on, the same position and velocity references, with torques.
    plain = walking_stack(talos, walk, dt=DT)
    fed = walking_stack(talos, walk, dt=DT, feedforward=True)
    assert plain.feedforward is None and isinstance(fed.feedforward, FeedForward)
    for k in range(50):
        targets = _standing(talos, 0.02 * k / 50)
        a, b = plain.hold(targets).command, fed.hold(targets).command
        assert a.torques is None and b.torques is not None and b.torques.shape == a.positions.shape
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.velocities, b.velocities)


def test_standing_still_the_torques_hold_the_robot_on_the_split_of_its_zmp(talos, walk):
    stack = walking_stack(talos, walk, dt=DT, feedforward=True)
    targets = _standing(talos, 0.03)
    for _ in range(200):  # the motion's rates settle to rest
        out = stack.hold(targets)
    feedforward = stack.feedforward
    wrenches = feedforward.last.wrenches
    weight = talos.mass * 9.81
    assert feedforward.last.method == "closed-form"
    np.testing.assert_allclose(wrenches[:, 2].sum(), weight, rtol=1e-6)
    # Without a controller the split is the motion's own ZMP's: the COM 3 cm toward the left foot.
    half = 0.5 * talos.step_width
    com = pin.centerOfMass(talos.model, talos.model.createData(), out.q)
    np.testing.assert_allclose(wrenches[0, 2] / weight, 0.5 + com[1] / (2.0 * half), atol=1e-3)
    np.testing.assert_allclose(out.command.torques, _static_torques(talos, out.q, wrenches)[6:], atol=1e-3)


@pytest.mark.parametrize("support", ["left", "right", "double"])
def test_the_controller_s_support_and_zmp_choose_the_wrenches(talos, walk, support):
    stack = walking_stack(talos, walk, dt=DT, feedforward=True)
    targets = _standing(talos)
    for _ in range(3):
        q = stack.hold(targets).q
    feedforward = FeedForward(talos, walk.sole, DT)
    zmp = (0.02, 0.04)
    out = ControlTargets(0.0, targets.cog, targets.left_foot, targets.right_foot, FootOffsets(), zmp, zmp, (0.0, 0.0),
                         support, 0, ())  # fmt: skip
    feedforward.torques(q, targets, out)
    wrenches = feedforward.last.wrenches
    if support == "double":
        # The wrenches sum to the motion's (its ZMP under the COM, not the commanded one), their split pulled from
        # the motion's even loads toward the commanded ZMP's (the left foot's share 0.74 on the segment's projection).
        assert feedforward.last.method == "closed-form"
        com = pin.centerOfMass(talos.model, talos.model.createData(), q)
        total = wrenches.sum(axis=0)  # level, unturned soles at the same height: the sum of the local wrenches
        np.testing.assert_allclose(total[2], talos.mass * 9.81, rtol=1e-9)
        assert 0.55 < wrenches[0, 2] / total[2] < 0.74
        np.testing.assert_allclose(feedforward.dynamics.required.zmp(), com[:2], atol=1e-6)
    else:
        np.testing.assert_array_equal(wrenches[1 if support == "left" else 0], 0.0)
        assert feedforward.last.method == "qp"  # the COM between the feet is off either sole


def test_the_torques_are_clipped_to_the_limits_and_counted(talos, walk):
    limits = dataclasses.replace(joint_limits(talos), torque=np.full(len(talos.joint_names), 5.0))
    stack = walking_stack(talos, walk, dt=DT, feedforward=True)
    stack.safety = SafetyLayer(limits, damping_gains(talos), walk.planner_config().cog_height)
    torques = stack.hold(_standing(talos)).command.torques
    assert np.abs(torques).max() == 5.0
    knee = talos.joint_names.index("leg_left_4_joint")
    assert stack.safety.clip.counts.torque[knee] == 1


def test_commanded_wrench_moves_the_zmp_and_keeps_the_moment_about_the_com():
    # The DCM law's correction moves the wrench's ZMP by exactly the shift, with the line of action through the COM:
    # the rate of angular momentum N - c x F is unchanged (independent of how the shift is computed).
    from rtgait.robot.inverse_dynamics import RequiredWrench
    from rtgait.stack.feedforward import commanded_wrench

    weight = 35.0 * 9.81
    com = (0.02, -0.01, 0.70)
    required = RequiredWrench(np.array([3.0, -2.0, weight]), np.array([4.0, -6.0, 0.5]))
    floor = 0.01
    moved = commanded_wrench(required, (0.015, -0.02), com, floor)
    before, after = required.zmp(floor), moved.zmp(floor)
    assert after[0] - before[0] == pytest.approx(0.015, abs=1e-12)
    assert after[1] - before[1] == pytest.approx(-0.02, abs=1e-12)
    c = np.array(com)
    np.testing.assert_allclose(moved.moment - np.cross(c, moved.force), required.moment - np.cross(c, required.force))
    assert moved.force[2] == required.force[2]


def test_the_friction_compensation_adds_its_torques_at_the_motion_s_joint_velocities(talos, walk):
    # Two feed-forwards on the same moving configurations, one with friction compensation: they differ by
    # alpha (F_c tanh(dq / v_s) + b dq) at the joint velocities of the IK's motion (its rates), computed here apart.
    from rtgait.stack.friction_compensation import STICTION_SPEED, FrictionCompensation

    coulomb = np.linspace(0.5, 2.0, len(talos.joint_names))
    viscous = np.full(len(talos.joint_names), 0.3)
    plain = FeedForward(talos, walk.sole, DT)
    compensated = FeedForward(talos, walk.sole, DT, friction_compensation=FrictionCompensation(coulomb, viscous, 0.6))
    stack = walking_stack(talos, walk, dt=DT, feedforward=True)
    q = stack.hold(_standing(talos)).q
    for k in range(50):
        targets = _standing(talos, dy=5.0 * (k * DT) ** 2)  # the COM accelerating sideways at 10 m/s^2: the legs move
        q = stack.hold(targets).q
        difference = compensated.torques(q, targets, None) - plain.torques(q, targets, None)
    dq = plain.rates.velocity[6:]
    assert np.abs(dq).max() > 0.01, "the joints move"
    expected = 0.6 * (coulomb * np.tanh(dq / STICTION_SPEED) + viscous * dq)
    np.testing.assert_allclose(difference, expected, atol=1e-9)
