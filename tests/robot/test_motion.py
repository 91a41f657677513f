"""Whole-body motion of planned walks: tracking by independent kinematics, limits, unreachable plans, offsets."""

from __future__ import annotations

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.core.analysis.rollout import ScheduledChange  # noqa: E402
from rtgait.core.planner.sample import SampleColumns  # noqa: E402
from rtgait.robot.model import BASE_COLUMNS, RobotModel  # noqa: E402
from rtgait.robot.motion import ERROR_FIELDS, UnreachableError, whole_body_motion  # noqa: E402


def tracking_errors(robot: RobotModel, q: np.ndarray, walk, cog_offset=None) -> dict[str, np.ndarray]:
    """Per-tick distances of the COG and both soles from the plan, by forward kinematics of the full model."""
    model = robot.full_model
    data = model.createData()
    planned_cog = walk.values[:, SampleColumns.cog].copy()
    if cog_offset is not None:
        planned_cog[:, :2] += cog_offset
    out = {name: np.empty(len(q)) for name in ("cog", "feet", "tilt", "yaw")}
    for k, q_full in enumerate(robot.full_configuration(q)):
        pin.framesForwardKinematics(model, data, q_full)
        out["cog"][k] = np.linalg.norm(pin.centerOfMass(model, data, q_full) - planned_cog[k])
        feet, tilt, yaw = [], [], []
        for frame, columns in (
            (robot.full_left_sole_id, SampleColumns.left_foot),
            (robot.full_right_sole_id, SampleColumns.right_foot),
        ):
            x, y, z, heading = walk.values[k, columns]
            placement = data.oMf[frame]
            feet.append(np.linalg.norm(placement.translation - [x, y, z]))
            tilt.append(np.arccos(min(1.0, placement.rotation[2, 2])))
            turn = np.arctan2(placement.rotation[1, 0], placement.rotation[0, 0]) - heading
            yaw.append(abs(np.angle(np.exp(1j * turn))))
        out["feet"][k], out["tilt"][k], out["yaw"][k] = max(feet), max(tilt), max(yaw)
    return out


def assert_within_limits(model, q: np.ndarray) -> None:
    lower, upper = model.lowerPositionLimit[7:], model.upperPositionLimit[7:]
    assert np.all(q[:, 7:] >= lower) and np.all(q[:, 7:] <= upper)


def test_talos_follows_fig8(talos, talos_fig8, talos_fig8_motion):
    motion, walk = talos_fig8_motion, talos_fig8
    np.testing.assert_array_equal(motion.times, walk.times)
    measured = tracking_errors(talos, motion.q, walk)
    assert measured["cog"].max() < 1e-3
    assert measured["feet"].max() < 1e-3
    assert measured["tilt"].max() < 1e-3 and measured["yaw"].max() < 1e-3
    # In fact micrometres; and the motion's own error record agrees with the measurement.
    assert measured["cog"].max() < 1e-5 and measured["feet"].max() < 1e-5
    np.testing.assert_allclose(motion.error("cog"), measured["cog"], atol=1e-9)
    assert max(motion.max_errors[name] for name in ERROR_FIELDS[:6]) < 1e-5
    assert_within_limits(talos.model, motion.q)
    assert_within_limits(talos.full_model, motion.q_full)
    # The swing feet really travel: the walk is 10 steps, the last ones 0.15 m.
    assert walk.column("lfoot_x")[-1] > 1.0


def test_table_names_joints_by_urdf_name(talos, talos_fig8_motion):
    header, rows = talos_fig8_motion.table()
    assert header[:8] == ("t", *BASE_COLUMNS)
    assert header[8:] == talos.full_joint_names
    assert "arm_left_1_joint" in header and "leg_right_4_joint" in header
    assert rows.shape == (len(talos_fig8_motion.times), len(header))
    # Locked joints stay at half-sitting; quaternions stay unit.
    column = header.index("arm_left_4_joint")
    np.testing.assert_allclose(rows[:, column], -0.525366)
    np.testing.assert_allclose(np.linalg.norm(rows[:, 4:8], axis=1), 1.0, atol=1e-12)
    small_header, small_rows = talos_fig8_motion.table(full=False)
    assert small_header[8:] == talos.joint_names and small_rows.shape[1] == 8 + 14


def test_cog_offset_moves_the_cog(talos, plan_walk):
    walk = plan_walk(talos, dt=0.02)
    n = len(walk.times)
    ramp = np.linspace(0.0, 1.0, n)
    offset = np.column_stack([0.01 * np.sin(2 * np.pi * ramp), -0.005 * ramp])
    motion = whole_body_motion(talos, walk, cog_offset=offset)
    measured = tracking_errors(talos, motion.q, walk, cog_offset=offset)
    assert measured["cog"].max() < 1e-5 and measured["feet"].max() < 1e-5
    planned = np.column_stack([walk.column("cog_x"), walk.column("cog_y")])
    np.testing.assert_allclose(motion.cog_target[:, :2], planned + offset)
    with pytest.raises(ValueError, match=r"cog_offset must have shape \(\d+, 2\)"):
        whole_body_motion(talos, walk, cog_offset=np.zeros((n, 3)))
    with pytest.raises(ValueError, match="cog_offset must be finite"):
        whole_body_motion(talos, walk, cog_offset=np.full((n, 2), np.nan))


def test_a_step_too_long_for_the_legs_is_refused(talos, plan_walk):
    walk = plan_walk(talos, dt=0.01, changes=(ScheduledChange(5, length=0.7, through=10),))
    with pytest.raises(UnreachableError) as caught:
        whole_body_motion(talos, walk)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith("step 5 at t=") and "out of reach for talos" in message
    assert "foot error" in message


def test_a_cog_above_the_legs_reach_is_refused(talos, plan_walk):
    walk = plan_walk(talos, dt=0.01, cog_height=0.95)
    with pytest.raises(UnreachableError, match=r"the start of the walk at t=0\.000 s .* COG error 0\.\d+ m"):
        whole_body_motion(talos, walk)


def test_the_same_walk_is_fine_within_reach(talos, plan_walk):
    # Longer steps than fig8's, still within Talos's legs: no error, the limits hold.
    walk = plan_walk(talos, dt=0.01, changes=(ScheduledChange(5, length=0.3, through=10),))
    motion = whole_body_motion(talos, walk)
    assert tracking_errors(talos, motion.q, walk)["feet"].max() < 1e-5
    assert_within_limits(talos.model, motion.q)


def test_second_robot_walks_from_its_description(g1, plan_walk):
    walk = plan_walk(g1, dt=0.01)
    motion = whole_body_motion(g1, walk)
    measured = tracking_errors(g1, motion.q, walk)
    assert measured["cog"].max() < 1e-3 and measured["feet"].max() < 1e-3
    assert measured["tilt"].max() < 1e-3 and measured["yaw"].max() < 1e-3
    assert_within_limits(g1.model, motion.q)
    header, _ = motion.table()
    assert "left_knee_joint" in header and "waist_yaw_joint" in header


def test_unknown_error_limit(talos, talos_fig8):
    with pytest.raises(ValueError, match="unknown error limit 'feet'"):
        whole_body_motion(talos, talos_fig8, limits={"feet": 0.01})
