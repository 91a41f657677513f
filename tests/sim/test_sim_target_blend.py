"""The blend of a foot's IK target (rtgait.control.target_blend): it starts with the old target's pose and rate, ends on
the controller's target, and stays within the minimum-jerk bounds."""

from __future__ import annotations

import itertools
import math

import pytest

from rtgait.control.target_blend import FootBlend

T, DT = 0.04, 0.001


def path(blend, target, ticks):
    return [blend.apply(k * DT, target(k * DT)) for k in range(ticks)]


def test_from_a_pose_at_rest_to_a_standing_foot_along_the_minimum_jerk_curve():
    blend = FootBlend("left")
    blend.start(0.0, (0.1, 0.2, 0.05, 0.3), (0.0, 0.0, 0.0), (0.104, 0.197, 0.31), 0.002, T)
    standing = (0.104, 0.197, 0.0, 0.31)
    poses = path(blend, lambda t: standing, 60)
    assert poses[0] == pytest.approx((0.1, 0.2, 0.002, 0.3), abs=1e-15), "where the IK had it"
    assert poses[40] == standing and not blend.active, "on the target from T on"
    # Halfway, the minimum-jerk curve is halfway (b(1/2) = 1/2), in every coordinate.
    assert poses[20] == pytest.approx((0.102, 0.1985, 0.001, 0.305), abs=1e-12)
    jump = math.hypot(0.004, 0.003)
    steps = [math.dist(a[:2], b[:2]) for a, b in itertools.pairwise(poses)]
    assert max(steps) <= 15.0 / 8.0 * jump * DT / T * (1.0 + 1e-9)
    second = [math.dist((c[0] - 2 * b[0] + a[0], c[1] - 2 * b[1] + a[1]), (0.0, 0.0))
              for a, b, c in zip(poses, poses[1:], poses[2:], strict=False)]  # fmt: skip
    assert max(second) <= 10.0 / math.sqrt(3.0) * jump * (DT / T) ** 2 * (1.0 + 1e-3)


def test_it_keeps_the_old_rate_and_takes_a_fast_target_in_slowly():
    # The target ran 5 mm ahead in 3 ms (a swing retargeted just before touch-down); the IK's target was moving at
    # 0.1 m/s. It leaves with that rate, and no tick moves it by more than the blend's own pace allows.
    blend = FootBlend("right")
    blend.start(0.0, (0.0, 0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.005, 0.0, 0.0), 0.0, T)

    def target(t):
        s = min(t / 0.003, 1.0)
        return (0.005 * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s), 0.0, 0.0, 0.0)

    poses = path(blend, target, 60)
    assert (poses[1][0] - poses[0][0]) / DT == pytest.approx(0.1, rel=0.05)
    assert max(b[0] - a[0] for a, b in itertools.pairwise(poses)) < 0.3e-3  # the target's own: 3 mm/tick
    assert poses[45] == pytest.approx((0.005, 0.0, 0.0, 0.0), abs=1e-15)


def test_yaw_across_pi_and_bad_durations():
    blend = FootBlend("left")
    blend.start(0.0, (0.0, 0.0, 0.0, math.pi - 0.01), (0.0, 0.0, 0.0), (0.0, 0.0, -math.pi + 0.01), 0.0, T)
    yaws = [p[3] for p in path(blend, lambda t: (0.0, 0.0, 0.0, -math.pi + 0.01 + 2 * math.tau), 41)]
    assert max(abs(b - a) for a, b in itertools.pairwise(yaws)) < 0.02 * 15 / 8 * DT / T * 1.01
    assert yaws[-1] == -math.pi + 0.01 + 2 * math.tau, "the target's own yaw, unwrapped as it was given"
    with pytest.raises(ValueError, match="duration"):
        blend.start(0.0, (0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.0)
