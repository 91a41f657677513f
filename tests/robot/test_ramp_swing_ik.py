"""G1 walks up its 10 degree ramp kinematically only with the swing lifting off the line between its footholds: the
IK reaches every tick of ``slope-up-g1`` with it, and refuses the walk at step 5 with the stair profile (the foot
raised to the landing's height behind the body, its sole pitched toes up with the ramp, beyond G1's ankle
dorsiflexion; rtgait.core.geometry.swing)."""

from __future__ import annotations

import pytest

pytest.importorskip("pinocchio")

from rtgait.core.geometry import swing
from rtgait.core.walk import phases
from rtgait.robot.motion import UnreachableError, whole_body_motion
from tests.robot.conftest import planned_walk


def test_g1_reaches_up_the_ramp_with_the_swing_along_it_and_not_with_the_stair_profile(g1, monkeypatch) -> None:
    motion = whole_body_motion(g1, planned_walk(g1, "slope-up-g1"))
    assert motion.errors[:, 0].max() < 1e-4  # the COG tracked (m)

    def never(start: object, end: object) -> bool:
        return False

    monkeypatch.setattr(swing, "up_ramp", never)
    monkeypatch.setattr(phases, "up_ramp", never)
    with pytest.raises(UnreachableError, match=r"step 5 .* out of reach for g1"):
        whole_body_motion(g1, planned_walk(g1, "slope-up-g1"))
