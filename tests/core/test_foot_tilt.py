"""A foot target's tilt from the footholds: a stance foot takes its foothold's, a swing blends from the lift-off's to
the landing's by its progress, level footholds give none."""

from __future__ import annotations

import pytest

from rtgait.core.geometry.foot_tilt import foot_tilt, is_tilted, tilted_feet
from rtgait.core.geometry.footsteps import Footstep

PRINTS = [
    Footstep(0.0, -0.1, 0.0, "right"),
    Footstep(0.0, 0.1, 0.0, "left"),
    Footstep(0.2, -0.1, 0.0, "right", z=0.0, pitch=0.0),
    Footstep(0.4, 0.1, 0.0, "left", z=0.02, pitch=-0.1, roll=0.02),
    Footstep(0.6, -0.1, 0.0, "right", z=0.05, pitch=-0.2),
]


def test_a_stance_foot_takes_its_foothold_s_tilt_and_a_swing_blends() -> None:
    assert foot_tilt(PRINTS, "left", 0.4, 0.1) == pytest.approx((-0.1, 0.02))
    assert foot_tilt(PRINTS, "left", 0.0, 0.1) == pytest.approx((0.0, 0.0))
    assert foot_tilt(PRINTS, "left", 0.1, 0.1) == pytest.approx((-0.025, 0.005))  # a quarter of the way
    assert foot_tilt(PRINTS, "right", 0.4, -0.1) == pytest.approx((-0.1, 0.0))  # halfway from 0.2 to 0.6
    assert foot_tilt(PRINTS, "right", 0.9, -0.1) == pytest.approx((-0.2, 0.0))  # beyond the last: the last's
    assert foot_tilt([], "left", 0.0, 0.0) == (0.0, 0.0)


def test_level_footholds_add_nothing_and_tilted_feet_append_the_tilt() -> None:
    assert not is_tilted(PRINTS[:3])
    assert is_tilted(PRINTS)
    left, right = tilted_feet(PRINTS, (0.4, 0.1, 0.02, 0.0), (0.6, -0.1, 0.05, 0.0))
    assert left == pytest.approx((0.4, 0.1, 0.02, 0.0, -0.1, 0.02))
    assert right == pytest.approx((0.6, -0.1, 0.05, 0.0, -0.2, 0.0))
