"""A scenario's ``[walking.<robot>]`` tables: what a walk asks of a named robot (its COG height, its toe release) in
place of the robot description's, read, checked and kept by a footstep plan's export."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtgait.scenario.footholds import footstep_plan_text
from rtgait.scenario.loading import builtin_scenarios, load_scenario
from rtgait.scenario.scenario import ScenarioError
from rtgait.scenario.walking_table import RobotWalking, walking_for
from tests.test_scenario import VALID, write


def test_the_185_staircase_asks_talos_for_its_own_cog_height_and_toe_release() -> None:
    walking = load_scenario("stairs-up-185").walking
    assert walking_for(walking, "talos") == RobotWalking("talos", cog_height=0.81, toe_release=0.5)
    assert walking_for(walking, "g1") is None  # G1 walks it with its own values
    # Up the 15 cm stairs Talos keeps only its swing's toe down longer (its COG height is its own); the other
    # built-ins ask nothing of any robot: their walks are unchanged.
    assert walking_for(load_scenario("stairs-up").walking, "talos") == RobotWalking("talos", toe_release=0.5)
    assert [name for name in builtin_scenarios() if load_scenario(name).walking] == ["stairs-up", "stairs-up-185"]


def test_a_table_per_robot_reaches_the_scenario(tmp_path: Path) -> None:
    text = VALID.replace("[walk]", "[walking.talos]\ncog_height = 0.78\n\n[walking.g1]\ntoe_release = 0.4\n\n[walk]")
    scenario = load_scenario(write(tmp_path, text))
    assert scenario.walking == (RobotWalking("talos", cog_height=0.78), RobotWalking("g1", toe_release=0.4))
    assert scenario.cog_height == 0.75  # the scenario's own, for runs without a robot, is untouched


@pytest.mark.parametrize(
    ("table", "expected"),
    [
        ("[walking.talos]\ncog_height = 50.0", r"walking\.talos\.cog_height must be"),
        ("[walking.talos]\ncog_height = -0.8", r"walking\.talos\.cog_height must be a number > 0 m, got -0.8"),
        ("[walking.talos]\ntoe_release = 1.5", r"walking\.talos\.toe_release must be a share of the swing in \(0, 1\]"),
        ("[walking.talos]\nheight = 0.8", r"walking\.talos.*height"),
        ("[walking.talos]", r"walking\.talos must set cog_height or toe_release"),
        ("[walking]\ntalos = 0.8", r"walking\.talos must be a table"),
    ],
)
def test_bad_tables_are_refused_in_one_line_naming_the_field(tmp_path: Path, table: str, expected: str) -> None:
    text = VALID.replace("[walk]", f"{table}\n\n[walk]")
    with pytest.raises(ScenarioError, match=expected) as caught:
        load_scenario(write(tmp_path, text))
    assert "\n" not in str(caught.value)


def test_a_footstep_plan_export_keeps_what_the_walk_asks_of_a_robot(tmp_path: Path) -> None:
    from rtgait.core.analysis.rollout import rollout
    from rtgait.core.planner.online import OnlinePlanner

    scenario = load_scenario("stairs-up-185")
    walk = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole)
    again = load_scenario(write(tmp_path, footstep_plan_text(scenario, walk.footprints)))
    assert again.walking == scenario.walking
