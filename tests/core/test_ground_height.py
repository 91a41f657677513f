"""The planned ground height under a foot target, against footholds at known heights."""

from __future__ import annotations

import pytest

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.ground_height import changes_ground_height, ground_height, ground_rise


def stairs() -> list[Footstep]:
    # Left and right alternately up 0.15 m treads, 0.25 m apart.
    return [
        Footstep(0.0, 0.1, 0.0, "left"),
        Footstep(0.0, -0.1, 0.0, "right"),
        Footstep(0.25, 0.1, 0.0, "left", z=0.15),
        Footstep(0.5, -0.1, 0.0, "right", z=0.30),
    ]


def test_a_stance_foot_stands_at_its_foothold_and_a_swing_reaches_the_landing_height() -> None:
    prints = stairs()
    assert ground_height(prints, "left", 0.0, 0.1) == 0.0
    assert ground_height(prints, "left", 0.25, 0.1) == pytest.approx(0.15)
    assert ground_height(prints, "left", 0.125, 0.1) == pytest.approx(0.075)  # halfway along its swing
    assert ground_height(prints, "right", 0.5, -0.1) == pytest.approx(0.30)
    assert ground_rise(prints, (0.25, 0.1), (0.0, -0.1)) == pytest.approx(0.15)
    assert changes_ground_height(prints) and not changes_ground_height(prints[:2])
