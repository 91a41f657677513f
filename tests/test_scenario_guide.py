"""The optional [guide] table of a scenario: the hand-guided walk's path."""

from __future__ import annotations

import pytest

from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import GuidePath, ScenarioError
from rtgait.scenario.scenario_file import parse_scenario


def _document(guide: dict) -> dict:
    return {
        "name": "g",
        "connection": "quasi-real-time",
        "robot": {"cog_height": 0.8, "sole": {"front": 0.13, "back": 0.1, "inner": 0.07, "outer": 0.07}},
        "timing": {"single_support": 0.7, "double_support": 0.1, "dt": 0.005, "horizon_steps": 3},
        "walk": {"steps": 4, "step_length": 0.1, "step_width": 0.19, "step_height": 0.05},
        "guide": guide,
    }


def test_builtin_guided_scenario_has_a_path():
    scenario = load_scenario("guided")
    assert scenario.connection == "quasi-real-time"
    assert scenario.guide == GuidePath(forward=1.0, turn=1.5708, radius=1.0, after=0.5, speed=0.15)
    assert load_scenario("fig8").guide is None


def test_guide_defaults_and_values():
    assert parse_scenario(_document({})).guide == GuidePath()
    assert parse_scenario(_document({"speed": 0.2, "turn": -0.5})).guide == GuidePath(speed=0.2, turn=-0.5)


@pytest.mark.parametrize(
    ("guide", "words"),
    [
        ({"speed": 0.0}, "guide.speed"),
        ({"radius": -1.0}, "guide.radius"),
        ({"turn": 4.0}, "guide.turn"),
        ({"forward": "far"}, "guide.forward"),
        ({"pace": 1.0}, "pace"),
    ],
)
def test_bad_guide(guide, words):
    with pytest.raises(ScenarioError, match=words):
        parse_scenario(_document(guide))


def test_guide_needs_quasi_real_time():
    document = _document({})
    document["connection"] = "real-time"
    with pytest.raises(ScenarioError, match="quasi-real-time"):
        parse_scenario(document)
