"""Talos climbs the built-in 15 cm stairs kinematically only with its rear heel rolled onto the toe: the IK reaches
every tick of ``stairs-up`` with the toe-off, and refuses the walk at step 2 without it (the reach check of
rtgait.robot.motion); at the lift-off the solved sole is pitched by the toe-off's angle. Down the same stairs it
reaches every tick only with the stance's support height lowered before each step down (support_height.py). G1 climbs
its 10 cm stairs kinematically only with its swing keeping the toe down until it passes the stance foot (its
description's ``walking.toe_release``): with the default share its swing ankle runs out of dorsiflexion at step 2."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.core.geometry import support_height, toe_off  # noqa: E402
from rtgait.robot.motion import UnreachableError, walking_robot, whole_body_motion  # noqa: E402
from tests.robot.conftest import planned_walk  # noqa: E402  (the robot's own COG height, stance and sole)


def test_talos_reaches_the_stairs_with_the_toe_off_and_not_without(talos, monkeypatch) -> None:
    walk = planned_walk(talos, "stairs-up")
    motion = whole_body_motion(talos, walk)
    assert motion.errors[:, 0].max() < 1e-4  # the COG tracked (m)
    # The first lift-off onto the stairs (the left foot leaves the floor for the first tread): the solved sole's
    # pitch, from the full model's forward kinematics, is the toe-off's.
    k = int(np.flatnonzero(walk.support == "right")[0])  # the left foot's lift-off for the first tread
    data = talos.model.createData()
    pin.framesForwardKinematics(talos.model, data, motion.q[k])
    sole = data.oMf[talos.left_sole_id].rotation
    pitch = np.arcsin(-sole[2, 0])  # Ry(pitch): the sole's x axis dips by the pitch
    assert pitch == pytest.approx(toe_off.THETA, abs=1e-3)

    monkeypatch.setattr(toe_off, "THETA", 0.0)
    with pytest.raises(UnreachableError, match=r"step 2 .* out of reach for talos"):
        whole_body_motion(talos, walk)


def test_talos_reaches_down_the_stairs_with_the_stance_lowered_and_not_without(talos, monkeypatch) -> None:
    walk = planned_walk(talos, "stairs-down")
    motion = whole_body_motion(talos, walk)
    assert motion.errors[:, 0].max() < 1e-3  # the COG tracked (m)
    # The landing leg does not reach the lower tread with the COG held over the upper one.
    monkeypatch.setattr(support_height, "DESCENT_SHARE", 0.0)
    with pytest.raises(UnreachableError, match=r"step 2 .* out of reach for talos"):
        whole_body_motion(talos, planned_walk(talos, "stairs-down"))


def test_g1_reaches_its_stairs_with_the_toe_kept_down_past_the_stance_foot(g1) -> None:
    from rtgait.robot.model import RobotModel

    walk = planned_walk(g1, "stairs-up-g1")
    assert g1.description.toe_release > toe_off.RELEASE
    motion = whole_body_motion(g1, walk)
    assert motion.errors[:, 0].max() < 0.01  # the COG tracked within the reach check's limit (m)
    # The sole levelled over the default share, right behind the stance foot: the ankle at its limit, out of reach.
    levelled_early = RobotModel.load(dataclasses.replace(g1.description, toe_release=toe_off.RELEASE))
    with pytest.raises(UnreachableError, match=r"step 2 .* out of reach for g1"):
        whole_body_motion(levelled_early, walk)


def _lowest_ankle_pitch(robot, walk) -> float:
    """The smallest (most dorsiflexed) ankle pitch either foot's solved motion reaches over ``walk`` (rad)."""
    motion = whole_body_motion(robot, walk)
    columns = [robot.model.joints[robot.model.getJointId(f"leg_{side}_5_joint")].idx_q for side in ("left", "right")]
    return float(motion.q[:, columns].min())


def test_up_talos_stairs_the_swing_ankle_stays_off_the_references_clip_with_the_scenarios_toe_release(talos) -> None:
    from rtgait.io.sim_run import planned_walk as scenario_walk
    from rtgait.robot.model import RobotModel
    from rtgait.scenario.loading import load_scenario
    from rtgait.stack.command_limits import POSITION_MARGIN

    scenario = load_scenario("stairs-up")
    robot = walking_robot(talos, scenario)
    assert robot.description.toe_release == 0.5  # the scenario's [walking.talos]
    ankle = talos.model.getJointId("leg_right_5_joint")
    stop = float(talos.model.lowerPositionLimit[talos.model.joints[ankle].idx_q])  # -1.309 rad, the URDF's
    clip = stop + POSITION_MARGIN  # the joint references are kept this far off the stop
    # Levelled over the default share, the swing's ankle is asked past the clip (1.305 rad of dorsiflexion): in closed
    # loop its reference stops there in every swing from step 3.
    levelled_early = RobotModel.load(dataclasses.replace(talos.description, toe_release=toe_off.RELEASE))
    assert _lowest_ankle_pitch(levelled_early, scenario_walk(scenario, levelled_early)) < clip
    # Kept on its toe until it passes the stance foot: well clear of it (1.140 rad).
    assert _lowest_ankle_pitch(robot, scenario_walk(scenario, robot)) > clip + 0.1
