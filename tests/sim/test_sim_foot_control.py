"""Foot force control on synthetic inputs: the ZMP split, the signs of the ankle and height laws, leaks and clamps."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

pytest.importorskip("mujoco")  # the measured feet's type lives with the MuJoCo measurement

from rtgait.control.foot_control import (
    FootControlGains,
    FootForceControl,
    FootOffsets,
    ZmpSplit,
    split_zmp,
)
from rtgait.core.geometry.footsteps import SoleRect
from rtgait.estimation.state import FootState
from rtgait.robot.ankles import add_ankle_offsets, find_ankle_joints

SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.05)
LEFT = (0.0, 0.1, 0.0)
RIGHT = (0.05, -0.1, 0.0)
DT = 0.001


def foot(cop_local=(0.0, 0.0), fz=400.0, pose=(0.0, 0.0, 0.0, 0.0), loaded=True) -> FootState:
    """A measured foot with the given load (N) and CoP in its sole frame (m)."""
    return FootState((0.0, 0.0, fz), (0.0, 0.0, 0.0), fz, cop_local, cop_local, pose, 0.0, 0.0, 0.0, loaded, 4)


def world_to_local(point, pose):
    x, y, yaw = pose[0], pose[1], pose[-1]
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = point[0] - x, point[1] - y
    return (c * dx + s * dy, -s * dx + c * dy)


# ----- the split ---------------------------------------------------------------------------------------------------


def test_single_support_takes_the_zmp_on_the_stance_sole():
    split = split_zmp((0.03, 0.12), LEFT, RIGHT, SOLE, "left")
    assert split.left_ratio == 1.0 and split.left_cop == (0.03, 0.12) and not split.saturated
    split = split_zmp((0.2, 0.12), LEFT, RIGHT, SOLE, "left")  # beyond the toe: clamped to the front edge
    assert split.saturated and split.left_cop == pytest.approx((0.13, 0.12))
    split = split_zmp((0.05, -0.1), LEFT, RIGHT, SOLE, "right")
    assert split.left_ratio == 0.0 and split.right_cop == (0.05, -0.1)
    with pytest.raises(ValueError, match="support"):
        split_zmp((0.0, 0.0), LEFT, RIGHT, SOLE, "none")


def test_double_support_split_reproduces_the_zmp_and_follows_it():
    rng = np.random.default_rng(3)
    ratios = []
    for s in np.linspace(0.0, 1.0, 11):
        # Points along the segment from the right sole point to the left one, a few cm off it.
        point = (RIGHT[0] + s * (LEFT[0] - RIGHT[0]) + rng.uniform(-0.03, 0.03), RIGHT[1] + s * (LEFT[1] - RIGHT[1]))
        split = split_zmp(point, LEFT, RIGHT, SOLE, "double")
        assert not split.saturated
        a = split.left_ratio
        ratios.append(a)
        # The shares add up to the total, and their moments to the ZMP: a c_L + (1 - a) c_R = p.
        combined = np.multiply(a, split.left_cop) + np.multiply(1.0 - a, split.right_cop)
        np.testing.assert_allclose(combined, point, atol=1e-12)
    assert ratios[0] == pytest.approx(0.0, abs=0.05) and ratios[-1] == pytest.approx(1.0, abs=0.05)
    assert all(b >= a for a, b in itertools.pairwise(ratios)), "more load on the foot the ZMP nears"
    middle = ((LEFT[0] + RIGHT[0]) / 2, (LEFT[1] + RIGHT[1]) / 2)
    split = split_zmp(middle, LEFT, RIGHT, SOLE, "double")
    assert split.left_ratio == pytest.approx(0.5)
    assert split.left_cop == pytest.approx(LEFT[:2]) and split.right_cop == pytest.approx(RIGHT[:2])


def test_double_support_split_beyond_a_foot_and_outside():
    split = split_zmp((0.0, 0.15), LEFT, RIGHT, SOLE, "double")  # past the left sole point, on the left sole
    assert split.left_ratio == 1.0 and split.left_cop == pytest.approx((0.0, 0.15)) and not split.saturated
    assert split.right_cop == RIGHT[:2], "no share, no CoP to servo: the sole point"
    split = split_zmp((0.4, 0.0), LEFT, RIGHT, SOLE, "double")  # far in front of both feet
    assert split.saturated
    for cop, pose in ((split.left_cop, LEFT), (split.right_cop, RIGHT)):
        assert world_to_local(cop, pose)[0] == pytest.approx(SOLE.front)


def test_split_respects_a_turned_foot():
    turned = (0.0, 0.1, math.pi / 2)  # the left foot heading +y: its front is +y, its inner side +x
    split = split_zmp((0.09, 0.1), turned, RIGHT, SOLE, "left")  # 9 cm to its inner side, which is 7 cm wide
    assert split.saturated and world_to_local(split.left_cop, turned) == pytest.approx((0.0, -SOLE.inner))


# ----- ankle damping -----------------------------------------------------------------------------------------------


def ankle_step(control, left, right, desired_left=(0.0, 0.1), desired_right=RIGHT[:2], support="double", ratio=0.5):
    """One tick of `control` with the desired CoPs given directly."""
    return control.update(ZmpSplit(ratio, desired_left, desired_right, False), left, right, support)


def test_a_cop_in_front_pitches_the_toe_up_and_one_on_the_left_rolls_onto_the_right_edge():
    control = FootForceControl(dt=DT)
    pose = (0.0, 0.1, 0.0, 0.0)
    out = ankle_step(control, foot((0.02, 0.0), pose=pose), foot(pose=(*RIGHT[:2], 0.0, 0.0)))
    # A positive pitch (about +y) turns the toe down; the CoP in front must raise it, so the pitch decreases.
    assert out.left_pitch < 0.0 and out.left_roll == 0.0
    expected = FootControlGains().cop_admittance * 400.0 * 0.02 * DT  # K * |dtau| * dt, below the rate limit
    assert out.left_pitch == pytest.approx(-expected, rel=1e-3)
    control.reset()
    out = ankle_step(control, foot((0.0, 0.01), pose=pose), foot(pose=(*RIGHT[:2], 0.0, 0.0)))
    # A positive roll (about +x) lifts the left edge and presses the right one: the CoP moves right.
    assert out.left_roll > 0.0 and out.left_pitch == 0.0
    assert out.right_roll == 0.0 and out.right_pitch == 0.0, "the right foot's CoP is where it is wanted"


def test_the_ankle_law_works_in_the_sole_frame():
    # The left foot turned a quarter left: its CoP ahead of the desired one along the foot is along +y in the world.
    pose = (0.0, 0.1, 0.0, math.pi / 2)
    control = FootForceControl(dt=DT)
    out = ankle_step(control, foot((0.02, 0.0), pose=pose), foot(pose=(*RIGHT[:2], 0.0, 0.0)))
    assert out.left_pitch < 0.0 and out.left_roll == pytest.approx(0.0, abs=1e-12)
    # A desired CoP 2 cm along world +y (the foot's front) from a CoP at the sole point: the CoP is behind, toe down.
    control.reset()
    out = ankle_step(control, foot((0.0, 0.0), pose=pose), foot(pose=(*RIGHT[:2], 0.0, 0.0)), desired_left=(0.0, 0.12))
    assert out.left_pitch > 0.0 and out.left_roll == pytest.approx(0.0, abs=1e-12)


def test_ankle_rate_and_angle_clamps_and_the_leak():
    gains = FootControlGains()
    control = FootForceControl(gains, dt=DT)
    big = foot((0.1, 0.0), fz=900.0, pose=(0.0, 0.1, 0.0, 0.0))  # K dtau = 0.9 rad/s, beyond 0.2 rad/s
    right = foot(pose=(*RIGHT[:2], 0.0, 0.0))
    previous = 0.0
    for _ in range(50):
        out = ankle_step(control, big, right)
        assert previous - out.left_pitch == pytest.approx(gains.max_tilt_rate * DT)
        previous = out.left_pitch
    for _ in range(2000):
        out = ankle_step(control, big, right)
    assert out.left_pitch == pytest.approx(-gains.max_tilt)
    # No error: the offset leaks back as exp(-t / T).
    start = out.left_pitch
    level = foot((0.0, 0.0), fz=900.0, pose=(0.0, 0.1, 0.0, 0.0))
    for _ in range(round(gains.cop_time_constant / DT)):
        out = ankle_step(control, level, right)
    assert out.left_pitch == pytest.approx(start * math.exp(-1.0), rel=1e-6)


def test_a_foot_in_the_air_or_not_meant_to_stand_returns_level_quickly():
    gains = FootControlGains()
    control = FootForceControl(gains, dt=DT)
    right = foot(pose=(*RIGHT[:2], 0.0, 0.0))
    for _ in range(100):
        ankle_step(control, foot((0.03, 0.0), pose=(0.0, 0.1, 0.0, 0.0)), right)
    start = control.offsets.left_pitch
    assert start < -0.005
    air = foot((math.nan, math.nan), fz=0.0, pose=(0.0, 0.1, 0.05, 0.0), loaded=False)
    steps = round(gains.swing_time_constant / DT)
    for _ in range(steps):
        out = ankle_step(control, air, right, support="right", ratio=0.0)
    assert out.left_pitch == pytest.approx(start * math.exp(-1.0), rel=1e-6)
    # On the ground but with the plan on the other foot (about to lift off): no torque input either.
    control.reset()
    out = ankle_step(control, foot((0.03, 0.0), pose=(0.0, 0.1, 0.0, 0.0)), right, support="right", ratio=0.0)
    assert out.left_pitch == 0.0


# ----- force difference --------------------------------------------------------------------------------------------


def test_force_difference_lowers_the_underloaded_foot():
    gains = FootControlGains()
    control = FootForceControl(gains, dt=DT)
    # Wanted: 90 % on the left; measured: 50/50 of 800 N. (f_L - f_R)_d - (f_L - f_R) = 640 N.
    left, right = foot(fz=400.0, pose=(0.0, 0.1, 0.0, 0.0)), foot(fz=400.0, pose=(*RIGHT[:2], 0.0, 0.0))
    out = ankle_step(control, left, right, ratio=0.9)
    assert out.left_height < 0.0 < out.right_height and out.left_height == pytest.approx(-out.right_height)
    rate = gains.force_difference_admittance * 640.0  # dz' at the start (m/s)
    assert out.right_height - out.left_height == pytest.approx(rate * DT, rel=1e-3)
    # Held, the error would settle dz at K_f T_f 640 N = 0.096 m: the clamp holds each foot at 0.025 m.
    for _ in range(20000):
        out = ankle_step(control, left, right, ratio=0.9)
    assert out.left_height == pytest.approx(-gains.max_height) and out.right_height == pytest.approx(gains.max_height)
    # No error: the difference leaks back with T_f.
    even = foot(fz=720.0, pose=(0.0, 0.1, 0.0, 0.0)), foot(fz=80.0, pose=(*RIGHT[:2], 0.0, 0.0))
    start = out.right_height
    for _ in range(round(gains.force_difference_time_constant / DT)):
        out = ankle_step(control, *even, ratio=0.9)
    assert out.right_height == pytest.approx(start * math.exp(-1.0), rel=1e-6)


def test_force_difference_acts_only_in_double_support():
    control = FootForceControl(dt=DT)
    left, right = foot(fz=400.0, pose=(0.0, 0.1, 0.0, 0.0)), foot(fz=400.0, pose=(*RIGHT[:2], 0.0, 0.0))
    out = ankle_step(control, left, right, support="left", ratio=1.0)
    assert out.left_height == 0.0 and out.right_height == 0.0
    lifted = foot((math.nan, math.nan), fz=0.0, pose=(*RIGHT[:2], 0.0, 0.0), loaded=False)
    out = ankle_step(control, left, lifted, ratio=0.7)  # planned double support, one foot not down yet
    assert out.left_height == 0.0 and out.right_height == 0.0


def test_gains_are_checked_and_dt_is_needed():
    with pytest.raises(ValueError, match="cop_admittance"):
        FootControlGains(cop_admittance=1.0)
    with pytest.raises(ValueError, match="dt"):
        FootForceControl().update(split_zmp((0.0, 0.1), LEFT, RIGHT, SOLE, "left"), foot(), foot(), "left")


# ----- onto the robot's ankles -------------------------------------------------------------------------------------


def test_ankle_offsets_turn_the_soles_as_asked(talos):
    pin = pytest.importorskip("pinocchio")
    ankles = find_ankle_joints(talos)
    names = [talos.joint_names[i] for i in ankles[:4]]
    assert names == ["leg_left_6_joint", "leg_left_5_joint", "leg_right_6_joint", "leg_right_5_joint"]
    q = talos.q_half_sitting.copy()
    add_ankle_offsets(q[7:], ankles, FootOffsets(left_roll=0.02, left_pitch=-0.03, right_pitch=0.01))
    data = talos.model.createData()
    pin.framesForwardKinematics(talos.model, data, q)
    for frame, roll, pitch in ((talos.left_sole_id, 0.02, -0.03), (talos.right_sole_id, 0.0, 0.01)):
        rotation = data.oMf[frame].rotation
        assert math.atan2(rotation[2, 1], rotation[2, 2]) == pytest.approx(roll, abs=1e-3)
        assert -math.asin(rotation[2, 0]) == pytest.approx(pitch, abs=1e-3)
