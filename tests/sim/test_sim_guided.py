"""Hand-guided walking in physics (the paper's Section 6): a person pulls the hand along a path."""

from __future__ import annotations

import math

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.robot.motion import robot_scenario
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import GuidePath
from rtgait.sim.guided import Leash, simulate_guided
from rtgait.sim.loop import LoopOptions


def test_the_robot_follows_the_hand_along_a_short_path(talos, talos_sim):
    """Straight 0.4 m, a 0.6 rad turn to the left, 0.2 m, stop: the robot walks after the hand without falling,
    stops once the person has stopped, and its base ends where the person's end point minus the arm's offset
    puts it."""
    walk = robot_scenario(load_scenario("guided"), talos)
    path = GuidePath(forward=0.4, turn=0.6, radius=0.6, after=0.2, speed=0.15)
    result, led = simulate_guided(talos_sim, walk, LoopOptions(), path=path)
    assert not result.fell
    assert led.stop_time is not None and led.stop_time >= result.walk_start + path.duration
    assert result.steps_completed == result.steps_planned >= 6
    # Its base ends 34 mm from there (31 mm at half the physics step, 0.5 ms): within 8 cm, some 2.4 times that.
    assert led.base_error < 0.08
    assert 0.0 < led.max_force <= led.force_limit == pytest.approx(0.045 * talos.mass * 9.81)
    assert led.max_twist > 0.0, "the person twisted the hand"
    # It walked after the hand, not dragged: the stance feet stood still, the ZMP followed the plan.
    assert result.foot_slip_max < 0.02
    assert result.zmp_errors()["vs_plan"]["rms"] < 0.04
    # It turned with the path (to the left), and came to rest: 0.1 mrad off the path's heading (2.8 mrad at half
    # the physics step), within a centiradian.
    qx, qy, qz, qw = result.base_quaternion[-1]
    yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    assert yaw == pytest.approx(0.6, abs=0.01)


def test_the_leash_is_scaled_to_the_robot():
    talos, g1 = Leash.for_robot(90.0), Leash.for_robot(33.0)
    assert talos.max_force == pytest.approx(0.045 * 90.0 * 9.81) and g1.max_force == pytest.approx(0.045 * 33.0 * 9.81)
    ratio = 33.0 / 90.0
    for name in ("stiffness", "damping", "max_force", "twist_gain", "max_twist"):
        assert getattr(g1, name) == pytest.approx(ratio * getattr(talos, name)), name
    with pytest.raises(ValueError, match="mass"):
        Leash.for_robot(0.0)


def test_guide_path_geometry():
    path = GuidePath(forward=1.0, turn=math.pi / 2, radius=1.0, after=0.5, speed=0.25)
    assert path.length == pytest.approx(1.5 + math.pi / 2)
    assert path.duration == pytest.approx(path.length / 0.25)
    assert path.at(0.5) == pytest.approx((0.5, 0.0, 0.0))
    assert path.at(1.0 + math.pi / 2) == pytest.approx((2.0, 1.0, math.pi / 2))
    assert path.at(100.0) == pytest.approx((2.0, 1.5, math.pi / 2))
    right = GuidePath(forward=0.0, turn=-math.pi / 2, radius=1.0, after=0.0)
    assert right.at(right.length) == pytest.approx((1.0, -1.0, -math.pi / 2))
