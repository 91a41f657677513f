"""Whole-body IK: tracking a planned walk, joint limits, warm starts; errors checked by independent kinematics."""

from __future__ import annotations

import math

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.core.planner.sample import SampleColumns  # noqa: E402
from rtgait.interface.task_targets import IKTargets  # noqa: E402
from rtgait.robot.ik import WholeBodyIK  # noqa: E402
from rtgait.robot.model import RobotModel  # noqa: E402
from rtgait.robot.rotation_errors import _yaw_error  # noqa: E402


def yaw_matrix(yaw: float) -> np.ndarray:
    return pin.utils.rotate("z", yaw)


def fk_errors(robot: RobotModel, q: np.ndarray, targets: IKTargets) -> dict[str, float]:
    """Task errors of ``q`` by forward kinematics of the full model (not the solver's own evaluation)."""
    model = robot.full_model
    q_full = robot.full_configuration(q)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q_full)
    com = pin.centerOfMass(model, data, q_full)
    result = {"cog": float(np.linalg.norm(com - np.asarray(targets.cog)))}
    for side, frame, target in (
        ("left", robot.full_left_sole_id, targets.left_foot),
        ("right", robot.full_right_sole_id, targets.right_foot),
    ):
        placement = data.oMf[frame]
        result[f"{side}_position"] = float(np.linalg.norm(placement.translation - np.asarray(target[:3])))
        rotation_error = yaw_matrix(target[3]).T @ placement.rotation
        result[f"{side}_orientation"] = float(np.linalg.norm(pin.log3(rotation_error)))
    return result


def walk_targets(walk) -> list[IKTargets]:
    columns = (SampleColumns.cog, SampleColumns.left_foot, SampleColumns.right_foot)
    return [IKTargets(*targets) for targets in zip(*(walk.values[:, c] for c in columns), strict=True)]


def test_rotation_error_matches_pinocchio_log():
    rng = np.random.default_rng(7)
    for _ in range(200):
        rotation = pin.SE3.Random().rotation
        yaw = rng.uniform(-math.pi, math.pi)
        homogeneous = np.eye(4)
        homogeneous[:3, :3] = rotation
        expected = pin.log3(yaw_matrix(yaw) @ rotation.T)
        np.testing.assert_allclose(_yaw_error(homogeneous.tolist(), math.cos(yaw), math.sin(yaw)), expected, atol=1e-9)
    # Small errors, the case that matters while tracking, to full precision.
    small = pin.exp3(np.array([1e-7, -2e-7, 3e-8])) @ yaw_matrix(0.3)
    error = _yaw_error(small.tolist(), math.cos(0.3), math.sin(0.3))
    np.testing.assert_allclose(error, [-1e-7, 2e-7, -3e-8], rtol=1e-6)


def test_tracks_a_planned_walk_tick_by_tick(talos, plan_walk):
    # The solver as a control loop uses it: default settings, warm-started from the previous tick.
    walk = plan_walk(talos, dt=0.01)
    ik = WholeBodyIK(talos)
    targets = walk_targets(walk)
    q, _ = ik.solve(targets[0], talos.q_half_sitting, max_iterations=100)
    lower, upper = talos.model.lowerPositionLimit[7:], talos.model.upperPositionLimit[7:]
    worst = dict.fromkeys(("cog", "left_position", "right_position", "left_orientation", "right_orientation"), 0.0)
    for k, target in enumerate(targets[1:], start=1):
        q_previous, kept = q, q.copy()
        q, reported = ik.solve(target, q_previous)
        assert q is not q_previous
        np.testing.assert_array_equal(q_previous, kept)  # the previous solution is not touched
        assert np.all(q[7:] >= lower) and np.all(q[7:] <= upper), f"joint limit left at tick {k}"
        if k % 10 == 0:
            measured = fk_errors(talos, q, target)
            for name, value in measured.items():
                worst[name] = max(worst[name], value)
                # The solver reports what forward kinematics measures.
                assert getattr(reported, name) == pytest.approx(value, abs=1e-9)
    assert worst["cog"] < 1e-4, worst
    assert max(worst["left_position"], worst["right_position"]) < 1e-4, worst
    assert max(worst["left_orientation"], worst["right_orientation"]) < 1e-4, worst


def test_joint_limits_hold_when_the_target_is_out_of_reach(talos):
    # The COG 0.3 m above half-sitting: the legs stretch until a knee reaches its limit (0 rad) and stays
    # there; the solver reports the COG error instead of leaving the limits.
    ik = WholeBodyIK(talos)
    half = talos.cog_half_sitting
    targets = IKTargets(
        [half[0], half[1], half[2] + 0.3], [0.0, 0.5 * talos.step_width, 0.0, 0.0],
        [0.0, -0.5 * talos.step_width, 0.0, 0.0],
    )  # fmt: skip
    q, errors = ik.solve(targets, talos.q_half_sitting, max_iterations=200)
    lower, upper = talos.model.lowerPositionLimit[7:], talos.model.upperPositionLimit[7:]
    assert np.all(q[7:] >= lower) and np.all(q[7:] <= upper)
    knees = [talos.model.joints[talos.model.getJointId(f"leg_{s}_4_joint")].idx_q for s in ("left", "right")]
    assert min(q[knees]) == pytest.approx(0.0, abs=1e-9)
    assert errors.cog > 0.1
    assert errors.cog == pytest.approx(fk_errors(talos, q, targets)["cog"], abs=1e-9)


def test_any_previous_configuration_is_honoured(talos):
    # Warm start from configurations the solver has not seen (not its cached last solution).
    ik = WholeBodyIK(talos, max_iterations=50)
    stand = IKTargets(
        [0.0, 0.0, 0.84], [0.0, 0.5 * talos.step_width, 0.0, 0.0], [0.0, -0.5 * talos.step_width, 0.0, 0.0]
    )
    q_stand, _ = ik.solve(stand, talos.q_half_sitting)
    shifted = IKTargets([0.02, 0.01, 0.83], [0.05, 0.1, 0.02, 0.1], [0.0, -0.085, 0.0, -0.05])
    q_a, errors_a = ik.solve(shifted, q_stand)
    # Same problem from half-sitting after the cache holds q_a: the answer must not depend on the cache.
    q_b, errors_b = ik.solve(shifted, talos.q_half_sitting)
    for q, errors in ((q_a, errors_a), (q_b, errors_b)):
        measured = fk_errors(talos, q, shifted)
        assert measured["cog"] < 1e-6 and measured["left_position"] < 1e-6
        assert measured["left_orientation"] < 1e-5
        assert errors.cog == pytest.approx(measured["cog"], abs=1e-12)
    # Editing the returned array in place and passing it back is noticed too: the step is the one a fresh
    # solver makes from the edited configuration.
    ik.solve(shifted, q_b)
    q_b[9] += 0.05
    q_c, errors_c = ik.solve(shifted, q_b, max_iterations=1, tolerance=0.0)
    q_fresh, errors_fresh = WholeBodyIK(talos).solve(shifted, q_b, max_iterations=1, tolerance=0.0)
    np.testing.assert_array_equal(q_c, q_fresh)
    assert errors_c == errors_fresh
    assert ik.errors(shifted, q_b).left_position == pytest.approx(fk_errors(talos, q_b, shifted)["left_position"])


def test_bad_arguments(talos):
    with pytest.raises(ValueError, match="max_iterations"):
        WholeBodyIK(talos, max_iterations=0)
    with pytest.raises(ValueError, match="tolerance"):
        WholeBodyIK(talos, tolerance=-1.0)
    with pytest.raises(ValueError, match="q_previous must have shape"):
        WholeBodyIK(talos).solve(IKTargets([0, 0, 0.8], [0, 0.1, 0, 0], [0, -0.1, 0, 0]), np.zeros(5))
