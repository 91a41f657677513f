"""Sole levelling on synthetic feet: a leg whose joint zeros tilt its sole by a known angle, learnt while the foot
stands flat and taken out of its commands, on the ground and in the air."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.control.sole_level import SoleLevel, SoleLevelSettings
from rtgait.core.geometry.footsteps import SoleRect
from rtgait.estimation.state import FootState

SOLE = SoleRect(front=0.13, back=0.06, inner=0.03, outer=0.03)  # G1's: 6 cm wide
WEIGHT = 330.0  # N
DT = 0.002


def foot(roll: float, pitch: float, fz: float = WEIGHT, cop=(0.03, 0.0), loaded: bool = True) -> FootState:
    """A measured foot whose estimated sole is rolled and pitched by ``roll``, ``pitch`` (rad)."""
    tilt = math.hypot(roll, pitch)
    return FootState((0.0, 0.0, fz), (0.0, 0.0, 0.0), fz, cop, cop, (0.0, 0.1, 0.0, 0.0), roll, pitch, tilt, loaded, 4)


def test_a_flat_loaded_foot_teaches_its_tilt_and_its_command_follows():
    """A sole standing flat reads the leg's kinematic error ``delta``: after a few time constants of stance the
    learnt tilt and the command (a second low-pass after it) are ``delta``; the other foot, in the air and level,
    learns nothing."""
    delta = (math.radians(0.4), math.radians(-0.6))
    rng = np.random.default_rng(0)
    level = SoleLevel(SOLE, WEIGHT, DT)
    for _ in range(int(5.0 / DT)):  # ten time constants (the command lags the learnt tilt)
        noise = 2e-4 * rng.standard_normal(2)  # rad, the estimate's tilt noise
        standing = foot(delta[0] + noise[0], delta[1] + noise[1])
        level.update(standing, foot(0.0, 0.0, fz=0.0, cop=(math.nan, math.nan), loaded=False), "left")
    lr, lp, rr, rp = level.tilts
    assert abs(lr - delta[0]) < 1e-4 and abs(lp - delta[1]) < 1e-4
    assert rr == 0.0 and rp == 0.0
    command = level.command
    assert abs(command[0] - delta[0]) < 1e-4 and abs(command[1] - delta[1]) < 1e-4


@pytest.mark.parametrize(
    "case",
    [
        {"cop": (0.125, 0.0)},  # the CoP 5 mm from the toe: the foot may be rolling onto it
        {"cop": (0.0, 0.025)},  # 5 mm from the outer edge
        {"fz": 0.2 * WEIGHT},  # lightly loaded: the sole need not lie flat
        {"cop": (math.nan, math.nan)},
    ],
)
def test_a_foot_that_may_not_lie_flat_teaches_nothing(case):
    level = SoleLevel(SOLE, WEIGHT, DT)
    for _ in range(500):
        level.update(foot(0.01, 0.01, **case), foot(0.01, 0.01, **case), "double")
    assert level.tilts == (0.0, 0.0, 0.0, 0.0)
    # Nor does a loaded foot the plan has swinging.
    for _ in range(500):
        level.update(foot(0.01, 0.01), foot(0.01, 0.01), "right")
    assert level.tilts[:2] == (0.0, 0.0) and level.tilts[2] != 0.0


def test_a_swinging_sole_is_steered_level():
    """The leg's joint zeros tilt its sole by ``-delta`` in the real world for a command of 0; the stance leg's
    compliance rolls the body, and the swing sole with it, by ``beta``. The estimate reads the real tilt plus
    ``delta``. Learnt on the ground, then steered in the air, the real swing sole ends level."""
    delta, beta = math.radians(0.5), math.radians(0.3)
    level = SoleLevel(SOLE, WEIGHT, DT)
    air = foot(0.0, 0.0, fz=0.0, cop=(math.nan, math.nan), loaded=False)
    for _ in range(int(3.0 / DT)):  # standing flat: the real sole is level, the estimate reads delta
        level.update(foot(delta, -delta), air, "left")
    real = (0.0, 0.0)
    for _ in range(int(0.5 / DT)):  # lifted: the real tilt is the command less delta, plus the body's roll
        command = level.command
        real = (command[0] - delta + beta, command[1] + delta)
        level.update(foot(real[0] + delta, real[1] - delta, fz=0.0, cop=(math.nan, math.nan), loaded=False), air,
                     "right")  # fmt: skip
    command = level.command
    real = (command[0] - delta + beta, command[1] + delta)
    assert abs(real[0]) < 1e-4 and abs(real[1]) < 1e-4  # held at the learnt tilt, it would be beta off


def test_clamps_and_settings():
    level = SoleLevel(SOLE, WEIGHT, DT)
    for _ in range(int(3.0 / DT)):
        level.update(foot(0.2, -0.2), foot(0.0, 0.0), "double")
    limit = SoleLevelSettings().max_tilt
    assert level.tilts[:2] == pytest.approx((limit, -limit))
    with pytest.raises(ValueError, match="time_constant"):
        SoleLevelSettings(time_constant=0.0)
    with pytest.raises(ValueError, match="max_tilt"):
        SoleLevelSettings(max_tilt=1.0)
    with pytest.raises(ValueError, match="weight"):
        SoleLevel(SOLE, 0.0, DT)
