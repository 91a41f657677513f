"""Scenario files: the built-ins, the TOML schema and its validation, and the paper's outcomes."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path

import pytest

from rtgait.core.analysis.rollout import Rollout, ScheduledChange, rollout
from rtgait.core.limits import (
    MAX_COG_HEIGHT,
    MAX_HORIZON_STEPS,
    MAX_PHASE_W_T,
    MAX_STEPS,
    MIN_COG_HEIGHT,
    MIN_DT,
    MIN_GRAVITY,
)
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import builtin_scenarios, load_scenario
from rtgait.scenario.scenario import Scenario, ScenarioError

BUILTINS = ("fig4", "fig6", "fig7", "fig8", "fig8-real-time", "fig11", "guided", "obstacle", "sidestep", "turn")
TERRAIN_BUILTINS = (
    "slope-down", "slope-up", "stairs-down", "stairs-down-185", "stairs-up", "stairs-up-185", "stepping-stones",
    "unseen-step",
)  # fmt: skip
"""Talos's walks off the flat floor, tested in tests/test_terrain_scenarios.py."""
G1_TERRAIN_BUILTINS = ("slope-down-g1", "slope-up-g1", "stairs-down-g1", "stairs-up-g1", "unseen-step-g1")
"""G1's variants, the terrain placed for its sole (tests/sim/test_sim_terrain_walk.py)."""

VALID = """\
name = "probe"
description = "a short walk for the tests"
connection = "quasi-real-time"

[robot]
cog_height = 0.75
gravity = 9.8

[robot.sole]
front = 0.12
back = 0.09
inner = 0.06
outer = 0.08

[timing]
single_support = 0.7
double_support = 0.1
dt = 0.01
horizon_steps = 2
start = 0.8
end = 0.9
settle = 1.5

[walk]
steps = 4
step_length = 0.1
step_width = 0.2
step_height = 0.04
yaw = 0.05
first_foot = "left"

[[walk.change]]
step = 2
length = 0.12
width = 0.22

[[walk.change]]
step = 3
yaw = -0.1
only = true
"""


def run(scenario: Scenario) -> Rollout:
    """Roll a scenario out as the command line does."""
    return rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole,
                   scenario.changes)  # fmt: skip


def write(tmp_path: Path, text: str, name: str = "probe.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def edited(old: str, new: str) -> str:
    assert old in VALID, old  # a typo in a test case must not silently test the valid file
    return VALID.replace(old, new, 1)


# ----- the built-ins --------------------------------------------------------------------------------------------


def test_builtin_listing_names_every_file_with_a_one_line_description() -> None:
    listing = builtin_scenarios()
    # Natural order: fig4 before fig11.
    assert tuple(listing) == (
        "fig4", "fig6", "fig7", "fig8", "fig8-real-time", "fig11", "guided", "obstacle", "sidestep", "slope-down",
        "slope-down-g1", "slope-up", "slope-up-g1", "stairs-down", "stairs-down-185", "stairs-down-g1", "stairs-up",
        "stairs-up-185", "stairs-up-g1", "stepping-stones", "turn", "unseen-step", "unseen-step-g1",
    )  # fmt: skip
    assert set(listing) == {*BUILTINS, *TERRAIN_BUILTINS, *G1_TERRAIN_BUILTINS}
    for description in listing.values():
        assert description and "\n" not in description


@pytest.mark.parametrize("name", BUILTINS)
def test_builtin_loads_under_its_own_name_with_the_shared_robot(name: str) -> None:
    scenario = load_scenario(name)
    assert scenario.name == name
    assert scenario.source == "builtin"
    # HRP-2-like sole: 0.23 m long with the ankle 0.10 m from the heel, 0.14 m wide.
    assert (scenario.sole.front, scenario.sole.back, scenario.sole.inner, scenario.sole.outer) == (
        0.13, 0.10, 0.07, 0.07,
    )  # fmt: skip
    assert (scenario.cog_height, scenario.step_width, scenario.step_height) == (0.80, 0.19, 0.05)
    if name == "fig11":  # stepping in place: two steps plus the closing one, nothing changes
        assert (scenario.dt, scenario.horizon_steps, scenario.steps, scenario.step_length) == (0.005, 3, 2, 0.0)
        assert scenario.changes == ()
        return
    if name == "guided":  # led by the hand in physics: at most 40 steps, the path in [guide], no changes
        assert (scenario.dt, scenario.horizon_steps, scenario.steps, scenario.connection) == (
            0.005, 3, 40, "quasi-real-time",
        )  # fmt: skip
        assert scenario.changes == () and scenario.guide is not None
        return
    if name == "obstacle":  # the paper's Fig. 1: no scheduled change, a box seen while walking
        assert (scenario.dt, scenario.horizon_steps, scenario.steps, len(scenario.obstacles)) == (0.005, 3, 16, 1)
        assert scenario.changes == ()
        return
    assert (scenario.dt, scenario.horizon_steps, scenario.steps) == (0.005, 3, 10)
    assert len(scenario.changes) == 1 and scenario.changes[0].step == 5


@pytest.mark.parametrize(
    ("name", "connection", "single", "double", "before", "after"),
    [
        ("fig4", "real-time", 0.8, 0.2, 0.05, 0.15),
        ("fig6", "real-time", 0.8, 0.2, 0.11, 0.12),
        ("fig7", "real-time", 0.8, 1.5, 0.05, 0.15),
        ("fig8", "quasi-real-time", 0.7, 0.1, 0.05, 0.15),
        ("fig8-real-time", "real-time", 0.7, 0.1, 0.05, 0.15),
    ],
)
def test_paper_scenarios_have_the_papers_parameters(
    name: str, connection: str, single: float, double: float, before: float, after: float
) -> None:
    scenario = load_scenario(name)
    assert scenario.connection == connection
    assert (scenario.timing.single_support, scenario.timing.double_support) == (single, double)
    assert scenario.step_length == before
    change = scenario.changes[0]
    # The new length holds for every later forward step (the paper's walk keeps the longer steps).
    assert (change.length, change.width, change.turn, change.through) == (after, None, None, 10)


@pytest.mark.parametrize(
    ("name", "outside"),
    [("fig4", True), ("fig6", False), ("fig7", False), ("fig8", False), ("fig8-real-time", True),
     ("fig11", False), ("sidestep", False), ("turn", False)],
)  # fmt: skip
def test_outcome_matches_the_paper_and_the_description(name: str, outside: bool) -> None:
    scenario = load_scenario(name)
    result = run(scenario)
    assert result.zmp_outside is outside
    if outside:
        change_time = result.changes[0][0]
        # The failure is the change being absorbed, not something unrelated before it.
        assert result.times[result.worst_index] > change_time
        assert result.zmp_margin_min < -0.05
    assert ("leaves the sole" in scenario.description) is outside
    assert ("stays inside" in scenario.description) is not outside


def test_fig4_fails_where_the_paper_says() -> None:
    result = run(load_scenario("fig4"))
    # Step 5 lifts off at 5.0 s and lands at 5.8 s; the following 0.2 s double support has to absorb it all.
    assert result.changes == [(pytest.approx(5.0), 5)]
    assert 5.8 <= result.times[result.worst_index] <= 6.0
    assert result.zmp_margin_min == pytest.approx(-0.11, abs=0.02)


# ----- the schema -----------------------------------------------------------------------------------------------


def test_every_field_of_a_file_reaches_the_scenario(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, VALID))
    assert scenario.name == "probe"
    assert scenario.description == "a short walk for the tests"
    assert scenario.connection == "quasi-real-time"
    assert (scenario.cog_height, scenario.gravity) == (0.75, 9.8)
    assert (scenario.sole.front, scenario.sole.back, scenario.sole.inner, scenario.sole.outer) == (
        0.12, 0.09, 0.06, 0.08,
    )  # fmt: skip
    t = scenario.timing
    assert (t.single_support, t.double_support, t.start, t.end, t.settle) == (0.7, 0.1, 0.8, 0.9, 1.5)
    assert (scenario.dt, scenario.horizon_steps) == (0.01, 2)
    assert (scenario.steps, scenario.step_length, scenario.step_width, scenario.step_height) == (4, 0.1, 0.2, 0.04)
    assert (scenario.yaw, scenario.first_foot) == (0.05, "left")
    first, second = scenario.changes
    assert (first.step, first.length, first.width, first.turn, first.through) == (2, 0.12, 0.22, None, 4)
    assert (second.step, second.length, second.width, second.turn, second.through) == (3, None, None, -0.1, None)
    assert scenario.source == str(tmp_path / "probe.toml")


def test_optional_keys_take_their_defaults(tmp_path: Path) -> None:
    text = VALID
    for line in ("gravity = 9.8", 'first_foot = "left"', "yaw = 0.05", "start = 0.8", "end = 0.9", "settle = 1.5",
                 'description = "a short walk for the tests"'):  # fmt: skip
        text = text.replace(line + "\n", "", 1)
    scenario = load_scenario(write(tmp_path, text))
    assert (scenario.gravity, scenario.first_foot, scenario.yaw, scenario.description) == (9.81, "right", 0.0, "")
    assert (scenario.timing.start, scenario.timing.end, scenario.timing.settle) == (1.0, 1.0, 2.0)


def test_planner_config_and_strides_follow_the_scenario(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, VALID))
    config = scenario.planner_config()
    assert config.cog_height == 0.75 and config.gravity == 9.8
    assert config.timing == scenario.timing and config.horizon_steps == 2
    assert config.connection == "quasi-real-time" and config.first_side == "left"
    assert (config.step_width, config.step_height) == (0.2, 0.04)
    strides = scenario.strides()
    assert len(strides) == 5  # four forward steps and the closing one
    assert all((s.length, s.width, s.turn) == (0.1, 0.2, 0.05) for s in strides[:4])
    assert (strides[4].length, strides[4].width, strides[4].turn) == (0.0, 0.2, 0.0)
    prints = scenario.nominal_footprints()
    assert len(prints) == 7 and prints[0].side == "left"


def test_duration_is_the_walk_the_planner_makes(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, VALID))
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    planner.start(0.0)
    assert scenario.duration == pytest.approx(planner.end_time)


def test_a_change_without_through_changes_only_that_step(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, VALID))
    result = run(scenario)
    # Step 3 turns by -0.1 rad on its own; steps 2 and 4 keep the walk's 0.05 rad (step 2's change leaves yaw).
    yaws = [print_.yaw for print_ in result.footprints]
    turns = [b - a for a, b in itertools.pairwise(yaws[1:])]
    assert turns[:4] == pytest.approx([0.05, 0.05, -0.1, 0.05])


def test_a_path_and_a_path_object_load_the_same(tmp_path: Path) -> None:
    path = write(tmp_path, VALID)
    assert load_scenario(str(path)) == load_scenario(path)


def test_builtin_file_copied_elsewhere_loads_identically(tmp_path: Path) -> None:
    from importlib import resources

    text = resources.files("rtgait").joinpath("scenarios", "fig8.toml").read_text(encoding="utf-8")
    assert load_scenario(write(tmp_path, text, "copy.toml")) == load_scenario("fig8")


# ----- validation -----------------------------------------------------------------------------------------------

CHANGES = VALID[VALID.index("[[walk.change]]") :]

BAD = [
    ("unknown scenario", None, "unknown scenario 'nope'"),
    ("durations", ("double_support = 0.1", "double_support = -0.2"), "timing.double_support must be a number > 0 s"),
    ("zero duration", ("single_support = 0.7", "single_support = 0"), "timing.single_support"),
    ("settle", ("settle = 1.5", "settle = -1"), "timing.settle"),
    ("nan", ("cog_height = 0.75", "cog_height = nan"), "robot.cog_height"),
    ("inf", ("step_length = 0.1", "step_length = inf"), "walk.step_length must be a finite number (in m)"),
    ("missing", ("step_height = 0.04\n", ""), "missing required key walk.step_height"),
    ("missing table", ("[robot.sole]\nfront = 0.12\nback = 0.09\ninner = 0.06\nouter = 0.08\n", ""), "robot.sole"),
    ("unknown key", ("single_support = 0.7", "singel_support = 0.7"), "unknown key timing.singel_support"),
    ("unknown top key", ('name = "probe"', 'name = "probe"\nspeed = 3'), "unknown top-level key speed"),
    ("unknown change key", ("step = 2\n", "step = 2\nlenght = 0.3\n"), "walk.change[0].lenght"),
    ("change past the walk", ("step = 3\n", "step = 5\n"), "walk.change[1].step must be a step of the walk (1..4)"),
    ("change zero", ("step = 2\n", "step = 0\n"), "walk.change[0].step"),
    ("change empty", ("step = 3\nyaw = -0.1\n", "step = 3\n"), "walk.change[1] changes nothing"),
    ("change only", ("only = true", 'only = "yes"'), "walk.change[1].only"),
    ("change yaw", ("yaw = -0.1", "yaw = 2.0"), "walk.change[1].yaw"),
    ("change width", ("width = 0.22", "width = 0"), "walk.change[0].width"),
    ("connection", ('connection = "quasi-real-time"', 'connection = "fast"'), "connection must be one of"),
    ("invalid toml", ("steps = 4", "steps = = 4"), "invalid TOML"),
    ("steps float", ("steps = 4", "steps = 4.5"), "walk.steps must be an integer >= 1"),
    ("steps zero", ("steps = 4", "steps = 0"), "walk.steps"),
    ("horizon", ("horizon_steps = 2", "horizon_steps = true"), "timing.horizon_steps"),
    ("string number", ("step_width = 0.2", 'step_width = "0.2"'), "walk.step_width"),
    ("sole", ("back = 0.09", "back = -0.01"), "robot.sole.back"),
    ("gravity", ("gravity = 9.8", "gravity = 0"), "robot.gravity"),
    ("dt", ("dt = 0.01", "dt = 0.5"), "timing.dt must not exceed the shortest phase"),
    ("first foot", ('first_foot = "left"', 'first_foot = "middle"'), "walk.first_foot"),
    ("name", ('name = "probe"', 'name = "../escape"'), "name must be"),
    ("change table", (CHANGES, "[walk.change]\nstep = 3\nlength = 0.1\n"), "walk.change must be an array of tables"),
    ("missing file", "no-such-file.toml", "cannot read scenario file"),
    # The limits of rtgait.core.limits, each named by its field and stated.
    ("steps limit", ("steps = 4", "steps = 10000"), "walk.steps must be at most 9999 (one closing step is added"),
    ("horizon limit", ("horizon_steps = 2", "horizon_steps = 21"), "timing.horizon_steps must be at most 20"),
    ("phase too long", ("settle = 1.5", "settle = 61"), "timing.settle must be within [0.001, 60] s"),
    ("phase too short", ("double_support = 0.1", "double_support = 5e-4"), "timing.double_support must be within"),
    ("dt limit", ("dt = 0.01", "dt = 1e-6"), "timing.dt must be within [1e-05, 60] s"),
    ("cog height limit", ("cog_height = 0.75", "cog_height = 11"), "robot.cog_height must be within [0.05, 10] m"),
    ("gravity limit", ("gravity = 9.8", "gravity = 0.05"), "robot.gravity must be within [0.1, 100] m/s^2"),
    # w = sqrt(9.8 / 0.75) = 3.61 1/s: a 5.8 s phase is w*T = 21.
    ("w T limit", ("settle = 1.5", "settle = 5.8"), "timing.settle = 5.8 s is too long for a COG 0.75 m high: w*T"),
    ("stride limit", ("step_length = 0.1", "step_length = -2.1"), "walk.step_length must be within [-2, 2] m"),
    ("change stride limit", ("width = 0.22", "width = 2.5"), "walk.change[0].width must be within [0, 2] m"),
    # Two entries for one step: the last one used to win silently.
    ("two changes of a step", ("step = 3\n", "step = 2\n"), "walk.change[0] and walk.change[1] both change step 2"),
]
"""(case, edit of VALID or a scenario argument, text the one-line error must contain)."""


@pytest.mark.parametrize(("case", "edit", "expected"), BAD, ids=[case for case, _, _ in BAD])
def test_bad_input_raises_one_line_naming_the_field(tmp_path: Path, case: str, edit, expected: str) -> None:
    if edit is None:
        argument: str | Path = "nope"
    elif isinstance(edit, str):
        argument = str(tmp_path / edit)
    else:
        argument = write(tmp_path, edited(*edit))
    with pytest.raises(ScenarioError) as caught:
        load_scenario(argument)
    message = str(caught.value)
    assert expected in message
    assert "\n" not in message
    assert isinstance(caught.value, ValueError)


def test_unknown_scenario_lists_the_builtins() -> None:
    with pytest.raises(
        ScenarioError, match="fig4, fig6, fig7, fig8, fig8-real-time, fig11, guided, obstacle, sidestep, slope-down"
    ):
        load_scenario("fig5")


def test_scenario_built_in_code_is_validated_too() -> None:
    scenario = load_scenario("fig4")
    with pytest.raises(ScenarioError, match="dt must be a number > 0 s"):
        replace(scenario, dt=math.nan)
    with pytest.raises(ScenarioError, match="shortest phase"):
        replace(scenario, dt=0.3)
    with pytest.raises(ScenarioError, match=r"walk.change\[0\].step"):
        replace(scenario, steps=4)
    with pytest.raises(ScenarioError, match="connection"):
        replace(scenario, connection="fast")


@pytest.mark.parametrize(
    ("changes", "expected"),
    [
        ({"cog_height": 1e-6}, r"cog_height must be within \[0.05, 10\] m"),
        ({"gravity": 1e9}, r"gravity must be within \[0.1, 100\] m/s\^2"),
        ({"dt": 1e-7}, r"dt must be at least 1e-05 s"),
        ({"steps": MAX_STEPS}, r"steps must be at most 9999"),
        ({"horizon_steps": MAX_HORIZON_STEPS + 1}, r"horizon_steps must be at most 20"),
        # w = sqrt(9.81 / 0.05) = 14 1/s: fig4's 2 s settling phase is w*T = 28 (a robot this small settles faster).
        ({"cog_height": 0.05}, r"timing.settle = 2 s is too long for a COG 0.05 m high"),
        # fig4 walks 14.8 s (148001 samples every 0.1 ms); with 210 steps it walks 214.8 s: 2148001 samples.
        ({"steps": 210, "dt": 1e-4}, r"dt 0.0001 s is too short for a walk of .* at most 1000000"),
        ({"changes": (ScheduledChange(3, length=0.1), ScheduledChange(3, width=0.2))}, r"both change step 3"),
    ],
)
def test_limits_hold_for_scenarios_built_in_code(changes: dict[str, object], expected: str) -> None:
    # The CLI's --dt and a robot's COG height reach the scenario this way, not through a file.
    with pytest.raises(ScenarioError, match=expected):
        replace(load_scenario("fig4"), **changes)


def test_values_at_the_limits_are_accepted(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, VALID))  # 7.1 s long
    assert replace(scenario, steps=MAX_STEPS - 1).steps == MAX_STEPS - 1
    assert replace(scenario, horizon_steps=MAX_HORIZON_STEPS).horizon_steps == MAX_HORIZON_STEPS
    assert replace(scenario, dt=MIN_DT).dt == MIN_DT  # 710001 samples
    assert replace(scenario, cog_height=MAX_COG_HEIGHT, gravity=MIN_GRAVITY).cog_height == MAX_COG_HEIGHT
    w = math.sqrt(scenario.gravity / scenario.cog_height)
    longest = replace(scenario.timing, settle=MAX_PHASE_W_T / w * (1.0 - 1e-12))
    assert replace(scenario, timing=longest).timing.settle == longest.settle
    low = replace(scenario, cog_height=MIN_COG_HEIGHT, timing=replace(scenario.timing, settle=1.0))
    assert low.cog_height == MIN_COG_HEIGHT


def test_robot_mass_is_optional_and_bounded(write_scenario) -> None:
    path = write_scenario(name="massive")
    base = path.read_text(encoding="utf-8")
    assert load_scenario(path).mass is None
    path.write_text(base.replace("cog_height = 0.8\n", "cog_height = 0.8\nmass = 57.0\n"), encoding="utf-8")
    assert load_scenario(path).mass == 57.0
    path.write_text(base.replace("cog_height = 0.8\n", "cog_height = 0.8\nmass = 5000.0\n"), encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"mass must be within \[1, 500\] kg"):
        load_scenario(path)
