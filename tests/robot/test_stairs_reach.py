"""Why Talos's reach check refuses BaselineWalkingController's 0.185 m stairs at its own COG height, against the
leg's geometry read from the URDF's joint placements (independent of the IK), and that the COG height the scenario
asks of Talos (``[walking.talos]``) gives the trailing leg the knee bend it has on the 15 cm stairs it climbs. Down
the same stairs Talos reaches every tick at its own height with the swing forward first (swing.py), not without."""

from __future__ import annotations

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.io.sim_run import planned_walk  # noqa: E402
from rtgait.robot.motion import (  # noqa: E402
    ERROR_FIELDS,
    UnreachableError,
    robot_scenario,
    walking_robot,
    whole_body_motion,
)
from rtgait.scenario.loading import load_scenario  # noqa: E402
from tests.robot.conftest import planned_walk as own_walk  # noqa: E402  (the robot's values, as given)
from tests.test_scenario import VALID, write  # noqa: E402

_NO_LIMITS = dict.fromkeys(ERROR_FIELDS, np.inf)
_HIP, _KNEE, _ANKLE = "leg_{}_3_joint", "leg_{}_4_joint", "leg_{}_5_joint"  # Talos's pitch joints


def _leg_length(robot) -> float:
    """Hip pitch to ankle pitch axis with the knee straight: thigh + shank, from the URDF's joint placements."""
    model = robot.model
    thigh = model.jointPlacements[model.getJointId(_KNEE.format("right"))].translation
    shank = model.jointPlacements[model.getJointId(_ANKLE.format("right"))].translation
    return float(np.linalg.norm(thigh) + np.linalg.norm(shank))


def _hip_to_ankle(robot, q: np.ndarray, side: str) -> float:
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    hip = data.oMi[robot.model.getJointId(_HIP.format(side))].translation
    ankle = data.oMi[robot.model.getJointId(_ANKLE.format(side))].translation
    return float(np.linalg.norm(hip - ankle))


def _longest_leg(robot, motion) -> float:
    return max(_hip_to_ankle(robot, q, side) for q in motion.q for side in ("left", "right"))


def test_the_scenario_asks_talos_alone_for_its_height_and_toe_release(talos, g1) -> None:
    scenario = load_scenario("stairs-up-185")
    walking = walking_robot(talos, scenario)
    assert (walking.description.cog_height, walking.description.toe_release) == (0.81, 0.5)
    assert robot_scenario(scenario, talos).cog_height == 0.81
    assert walking_robot(walking, scenario) is walking  # applied twice: the same robot (its MuJoCo scene too)
    assert walking_robot(g1, scenario) is g1  # asked nothing: its own
    assert walking_robot(talos, load_scenario("stairs-down")) is talos


def test_at_its_own_height_talos_trailing_leg_runs_out_of_length_at_step_3(talos) -> None:
    own = talos  # at 0.84 m, as its description gives it: the scenario's [walking.talos] replaced
    walk = own_walk(own, "stairs-up-185", cog_height=own.description.cog_height)
    with pytest.raises(UnreachableError, match=r"step 3 at t=3\.690 s is out of reach for talos: COG error"):
        whole_body_motion(own, walk)
    motion = whole_body_motion(own, walk, limits=_NO_LIMITS)
    k = int(np.argmax(motion.error("cog") > 0.01))  # the refused tick
    knee = own.model.joints[own.model.getJointId(_KNEE.format("right"))].idx_q
    # The trailing (right) foot, lifting off the floor behind the first tread: the knee at its straight limit and the
    # hip as far from the ankle as thigh + shank reach.
    assert motion.q[k, knee] == pytest.approx(own.model.lowerPositionLimit[knee], abs=1e-6)
    assert _hip_to_ankle(own, motion.q[k], "right") == pytest.approx(_leg_length(own), abs=1e-4)
    assert _leg_length(own) == pytest.approx(0.705, abs=1e-3)  # 0.38 m thigh + 0.325 m shank


def test_at_the_scenarios_height_the_legs_reach_as_far_as_on_the_walked_15_cm_stairs(talos) -> None:
    scenario = load_scenario("stairs-up-185")
    robot = walking_robot(talos, scenario)
    motion = whole_body_motion(robot, planned_walk(scenario, robot))
    assert motion.error("cog").max() < 0.01
    reference = whole_body_motion(talos, planned_walk(load_scenario("stairs-up"), talos))
    assert _longest_leg(robot, motion) <= _longest_leg(talos, reference)


def test_a_height_talos_cannot_reach_is_refused_naming_the_scenarios_setting(tmp_path, capsys) -> None:
    from rtgait.cli.main import main

    # With straight legs Talos's COG stands about 0.9 m high: 0.95 m is out of reach from the start.
    path = write(tmp_path, VALID.replace("[walk]", "[walking.talos]\ncog_height = 0.95\n\n[walk]"))
    code = main(["plan", str(path), "--robot", "talos", "--no-figures", "--quiet", "--out", str(tmp_path / "out")])
    error = capsys.readouterr().err.strip()
    assert code != 0
    assert error.startswith("rtgait: error: the start of the walk at t=0.000 s is out of reach for talos: COG error")
    assert error.endswith("with the COG at the scenario's walking.talos.cog_height = 0.95 m")
    assert "\n" not in error


def test_talos_reaches_down_the_stairs_with_the_swing_forward_first_and_not_without(talos, monkeypatch) -> None:
    # The swing down a stair over its landing by mid-swing, then straight down: every tick reached at Talos's own
    # 0.84 m. With the former stair profile (the foot held over the tread below until 65 % of the swing) the swing
    # leg folds under the hip and step 3 is refused; its hip-to-ankle distance there is under half thigh + shank.
    from rtgait.core.geometry import swing

    walk = own_walk(talos, "stairs-down-185")
    motion = whole_body_motion(talos, walk)
    assert motion.errors[:, 0].max() < 0.01  # within the reach check's COG limit (m)
    monkeypatch.setattr(swing, "down_stair", lambda start, end: False)
    former = own_walk(talos, "stairs-down-185")
    with pytest.raises(UnreachableError, match=r"^step 3 .* out of reach for talos"):
        whole_body_motion(talos, former)
    lifted = whole_body_motion(talos, former, limits=_NO_LIMITS)
    worst = int(np.argmax(lifted.errors[:, 0]))
    folded = min(_hip_to_ankle(talos, lifted.q[worst], side) for side in ("left", "right"))
    assert folded < 0.5 * _leg_length(talos)
