"""Whole-body IK near joint limits: the barrier keeps the solution's rate continuous and the limits are never left.

G1's swing foot is carried sideways, away from the stance foot, at a constant rate, one Gauss-Newton step a tick as
the walking stack solves it: its ankle roll (+-0.262 rad) is driven toward its limit. A reference whose velocity
steps in one tick differences into a burst of acceleration (the feed-forward torques' input); with the barrier the
largest change of any coordinate's per-tick step stays a small fraction of the largest step, without it (the joint
pinned at the limit where it would cross) the step changes by more than the step itself.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pinocchio")

from rtgait.interface.task_targets import IKTargets
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.ik_terms import SMOOTH_LIMITS, IKWeights

TICKS = 400
LIFT = 0.05  # m: the swing foot's height
COG_DROP = 0.05  # m: the COG below half-sitting, as when walking


def sweep(robot, weights: IKWeights, reach: float) -> tuple[np.ndarray, int]:
    """Configurations while the right foot moves ``reach`` m outward (from 0.1 m inside its stance place) with the
    COG over the left foot; and the index of the right ankle roll in ``q``."""
    half = 0.5 * robot.step_width
    cog = robot.cog_half_sitting
    over_left = [cog[0], half, cog[2] - COG_DROP]
    ik = WholeBodyIK(robot, weights)
    start = IKTargets(over_left, [0.0, half, 0.0, 0.0], [0.0, -half + 0.1, LIFT, 0.0])
    q, _ = ik.solve(start, robot.q_half_sitting, 200, 1e-9)
    path = []
    for k in range(TICKS):
        right = [0.0, -half + 0.1 - reach * k / TICKS, LIFT, 0.0]
        q, _ = ik.solve(IKTargets(over_left, [0.0, half, 0.0, 0.0], right), q, max_iterations=1, tolerance=0.0)
        path.append(q.copy())
    ankle = robot.model.joints[robot.model.getJointId("right_ankle_roll_joint")].idx_q
    return np.array(path), ankle


def rate_step(path: np.ndarray) -> float:
    """Largest one-tick change of any coordinate's step, relative to the largest step (1: the step doubled)."""
    return float(np.abs(np.diff(path, 2, axis=0)).max() / np.abs(np.diff(path, axis=0)).max())


def test_the_solution_slows_smoothly_into_a_limit(g1):
    # 0.1 m carries the unconstrained ankle roll from 0.07 rad to about 0.02 rad beyond its limit.
    upper = g1.model.upperPositionLimit
    smooth, ankle = sweep(g1, SMOOTH_LIMITS, 0.1)
    assert smooth[0, ankle] < 0.1
    assert smooth[:, ankle].max() > upper[ankle] - SMOOTH_LIMITS.limit_margin  # it did enter the barrier's band
    assert smooth[:, ankle].max() < upper[ankle]
    assert rate_step(smooth) < 0.1
    pinned, _ = sweep(g1, IKWeights(), 0.1)
    assert pinned[:, ankle].max() == pytest.approx(upper[ankle], abs=1e-9)  # the hard stop
    assert rate_step(pinned) > 1.0


def test_limits_are_never_left_far_beyond_reach(g1):
    # 0.3 m asks for about 0.4 rad of ankle roll: the barrier gives way and the pin holds the limit.
    path, ankle = sweep(g1, SMOOTH_LIMITS, 0.3)
    lower, upper = g1.model.lowerPositionLimit[7:], g1.model.upperPositionLimit[7:]
    assert np.all(path[:, 7:] >= lower) and np.all(path[:, 7:] <= upper)
    assert path[-1, ankle] == pytest.approx(g1.model.upperPositionLimit[ankle], abs=1e-9)


def test_the_barrier_is_idle_away_from_the_limits(g1):
    # Both soles flat at half-sitting: every joint farther than the band from its limits, the same solution.
    half = 0.5 * g1.step_width
    cog = g1.cog_half_sitting
    targets = IKTargets([cog[0], cog[1], cog[2] - COG_DROP], [0.0, half, 0.0, 0.0], [0.0, -half, 0.0, 0.0])
    with_barrier, _ = WholeBodyIK(g1, SMOOTH_LIMITS).solve(targets, g1.q_half_sitting, 200, 1e-9)
    without, _ = WholeBodyIK(g1).solve(targets, g1.q_half_sitting, 200, 1e-9)
    lower, upper = g1.model.lowerPositionLimit[7:], g1.model.upperPositionLimit[7:]
    margin = SMOOTH_LIMITS.limit_margin
    assert np.all(with_barrier[7:] > lower + margin) and np.all(with_barrier[7:] < upper - margin)
    np.testing.assert_allclose(with_barrier, without, atol=1e-12)


def test_bad_barrier_settings(g1):
    with pytest.raises(ValueError, match="curvature"):
        WholeBodyIK(g1, IKWeights(limit=-1.0))
    with pytest.raises(ValueError, match="margin"):
        WholeBodyIK(g1, IKWeights(limit_margin=0.0))
