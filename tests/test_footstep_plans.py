"""Footstep plan files (:mod:`rtgait.scenario.footholds`): loading, walking, exporting and refusing bad steps."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rtgait.cli.main import main
from rtgait.core.geometry.footsteps import Footstep, place_footsteps, standing_feet
from rtgait.scenario.footholds import footstep_plan_text
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import ScenarioError

HEADER = """name = "free-path"
connection = "quasi-real-time"

[robot]
cog_height = 0.80

[robot.sole]
front = 0.13
back = 0.10
inner = 0.07
outer = 0.07

[timing]
single_support = 0.8
double_support = 0.2
dt = 0.005
horizon_steps = 3

[walk]
step_width = 0.19
step_height = 0.05
"""

STEPS = [
    {"side": "right", "x": 0.10, "y": -0.095},
    {"side": "left", "x": 0.22, "y": 0.10, "single_support": 0.6, "double_support": 0.35},
    {"side": "right", "x": 0.33, "y": -0.08, "yaw": 0.15, "single_support": 1.0},
    {"side": "left", "x": 0.36, "y": 0.13, "yaw": 0.15, "double_support": 0.1},
    {"side": "right", "x": 0.40, "y": -0.06, "yaw": 0.15},
]


def _text(steps: list[dict]) -> str:
    blocks = []
    for step in steps:
        lines = ["[[footstep]]"]
        for key, value in step.items():
            lines.append(f"{key} = {json.dumps(value) if isinstance(value, str) else repr(value)}")
        blocks.append("\n".join(lines))
    return HEADER + "\n" + "\n\n".join(blocks) + "\n"


def _write(tmp_path: Path, steps: list[dict], name: str = "plan.toml") -> Path:
    path = tmp_path / name
    path.write_text(_text(steps), encoding="utf-8")
    return path


def _footprints(folder: Path) -> list[tuple]:
    data = json.loads((folder / "summary.json").read_text())
    return [(f["x"], f["y"], f["yaw"], f["side"]) for f in data["footprints"]]


def test_a_footstep_plan_loads_as_a_scenario(tmp_path):
    scenario = load_scenario(_write(tmp_path, STEPS))
    assert scenario.steps == len(STEPS) - 1 and scenario.first_foot == "right"
    prints = scenario.nominal_footprints()
    assert len(prints) == len(STEPS) + 2
    for foot, step in zip(prints[2:], STEPS, strict=True):
        assert (foot.x, foot.y, foot.yaw, foot.side) == (step["x"], step["y"], step.get("yaw", 0.0), step["side"])
    assert scenario.timing.per_step == ((0.8, 0.2), (0.6, 0.35), (1.0, 0.2), (0.8, 0.1), (0.8, 0.2))
    durations = [1.0, 0.8, 0.2, 0.6, 0.35, 1.0, 0.2, 0.8, 0.1, 0.8, 1.0, 2.0]
    assert scenario.duration == pytest.approx(sum(durations), abs=1e-12)


def test_rtgait_plan_walks_the_footholds_and_the_export_round_trips(tmp_path, capsys):
    path = _write(tmp_path, STEPS)
    exported = tmp_path / "exported.toml"
    assert main(["plan", str(path), "--out", str(tmp_path / "a"), "--no-figures", "--quiet",
                 "--export-footsteps", str(exported)]) == 0  # fmt: skip
    walked = _footprints(tmp_path / "a")
    for foot, step in zip(walked[2:], STEPS, strict=True):
        assert foot[:2] == pytest.approx((step["x"], step["y"]), abs=1e-12)
        assert foot[3] == step["side"]
    # The phases walked are the file's: the support label changes at the cumulative sums of its durations.
    with open(tmp_path / "a" / "trajectory.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    t = np.array([float(r["t"]) for r in rows])
    phase = np.array([int(r["phase"]) for r in rows])
    switches = t[1:][np.diff(phase) != 0]
    expected = np.cumsum([1.0, 0.8, 0.2, 0.6, 0.35, 1.0, 0.2, 0.8, 0.1, 0.8, 1.0])
    assert switches == pytest.approx(expected, abs=1e-9)

    again = load_scenario(exported)
    assert again.timing.per_step == load_scenario(path).timing.per_step
    assert main(["plan", str(exported), "--out", str(tmp_path / "b"), "--no-figures", "--quiet"]) == 0
    replanned = _footprints(tmp_path / "b")
    assert len(replanned) == len(walked)
    for a, b in zip(walked, replanned, strict=True):
        assert a[3] == b[3]
        assert a[:3] == pytest.approx(b[:3], abs=1e-12)
    assert capsys.readouterr().err == ""


def test_export_of_a_scenario_gives_its_footholds_as_walked_after_its_changes(tmp_path):
    exported = tmp_path / "fig8.toml"
    assert main(["plan", "fig8", "--out", str(tmp_path / "a"), "--no-figures", "--quiet",
                 "--export-footsteps", str(exported)]) == 0  # fmt: skip
    plan = load_scenario(exported)
    assert plan.timing.per_step == ()  # a uniform walk stays uniform
    walked = _footprints(tmp_path / "a")
    _assert_same([(f.x, f.y, f.yaw, f.side) for f in plan.nominal_footprints()], walked)
    assert walked != _footprints_nominal(tmp_path / "a")  # fig8's change is in the export
    assert main(["plan", str(exported), "--out", str(tmp_path / "b"), "--no-figures", "--quiet"]) == 0
    _assert_same(_footprints(tmp_path / "b"), walked)


def _assert_same(a: list[tuple], b: list[tuple], tol: float = 1e-12) -> None:
    assert [f[3] for f in a] == [f[3] for f in b]
    assert np.abs(np.array([f[:3] for f in a]) - np.array([f[:3] for f in b])).max() <= tol


def _footprints_nominal(folder: Path) -> list[tuple]:
    data = json.loads((folder / "summary.json").read_text())
    return [(f["x"], f["y"], f["yaw"], f["side"]) for f in data["nominal_footprints"]]


def _bad(steps_change) -> list[dict]:
    steps = [dict(step) for step in STEPS]
    steps_change(steps)
    return steps


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda s: s[2].update(side="left"), r"footstep\[2\] \(step 3\) is a left foot again"),
        (lambda s: s[1].update(x=2.5), r"footstep\[1\] \(step 2\) lands 2.\d+ m from the stance foot: out of reach"),
        (lambda s: s[3].update(y=-0.2), r"footstep\[3\] \(step 4\) is out of reach: the feet cross"),
        (lambda s: s[2].update(x=math.nan), r"footstep\[2\]\.x"),
        (lambda s: s[0].update(side="right", y=float("inf")), r"footstep\[0\]\.y"),
        (lambda s: s[1].update(single_support=-0.5), r"footstep\[1\]\.single_support"),
        (lambda s: s[4].update(double_support=0.2), r"footstep\[4\]\.double_support: the last step"),
        (lambda s: s[2].update(yaw=1.8), r"footstep\[2\] \(step 3\) is out of reach: it turns"),
        (lambda s: s[2].update(height=0.1), r"footstep\[2\]"),
        (lambda s: s[0].update(side="up"), r"footstep\[0\]\.side"),
    ],
)
def test_bad_steps_are_refused_naming_the_step(tmp_path, capsys, change, message):
    path = _write(tmp_path, _bad(change))
    with pytest.raises(ScenarioError, match=message):
        load_scenario(path)
    assert main(["plan", str(path), "--out", str(tmp_path / "o"), "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("rtgait: error: ")
    assert not (tmp_path / "o").exists()


def test_too_few_steps_and_a_dt_longer_than_a_steps_phase_are_refused(tmp_path):
    with pytest.raises(ScenarioError, match=r"2\.\.10000"):
        load_scenario(_write(tmp_path, STEPS[:1]))
    steps = _bad(lambda s: s[1].update(double_support=0.002))
    with pytest.raises(ScenarioError, match=r"timing\.dt must not exceed the shortest phase"):
        load_scenario(_write(tmp_path, steps))


def test_a_left_first_plan_and_a_last_step_that_leaves_the_feet_apart(tmp_path):
    steps = [
        {"side": "left", "x": 0.1, "y": 0.095},
        {"side": "right", "x": 0.2, "y": -0.095},
        {"side": "left", "x": 0.2, "y": 0.3},  # the walk ends standing 0.395 m wide
    ]
    scenario = load_scenario(_write(tmp_path, steps))
    assert scenario.first_foot == "left" and scenario.timing.per_step == ()
    assert main(["plan", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "o"), "--no-figures", "--quiet"]) == 0
    with open(tmp_path / "o" / "trajectory.csv", newline="") as stream:
        last = list(csv.DictReader(stream))[-1]
    assert (float(last["cog_x"]), float(last["cog_y"])) == pytest.approx((0.2, 0.1025), abs=1e-6)


def test_footstep_plan_text_writes_every_digit():
    scenario = load_scenario("fig4")
    prints = [*scenario.nominal_footprints()[:2], Footstep(0.1 + 1e-15, -0.095, 0.0, "right"),
              Footstep(0.2, 0.095, 1e-3 / 3, "left")]  # fmt: skip
    text = footstep_plan_text(scenario, prints, name="x")
    assert repr(0.1 + 1e-15) in text and repr(1e-3 / 3) in text and 'name = "x"' in text


def test_export_to_a_folder_is_refused_before_the_run(tmp_path, capsys):
    assert main(["plan", "fig4", "--out", str(tmp_path / "o"), "--no-figures", "--export-footsteps",
                 str(tmp_path)]) == 2  # fmt: skip
    assert "--export-footsteps" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rtgait_simulate_takes_a_footstep_plan(tmp_path):
    path = _write(tmp_path, STEPS)
    assert main(["simulate", str(path), "--model", "lipm", "--no-figures", "--quiet", "--out",
                 str(tmp_path / "s")]) == 0  # fmt: skip
    summary = json.loads((tmp_path / "s" / "summary.json").read_text())
    assert summary["fell"] is False


def test_a_wider_stance_moves_the_first_stride_not_the_footholds(tmp_path):
    """A robot's step width (``dataclasses.replace``, as ``--robot`` does) changes the standing feet only."""
    scenario = load_scenario(_write(tmp_path, STEPS))
    wider = replace(scenario, step_width=0.25)
    prints = place_footsteps(standing_feet(0.25, wider.first_foot), wider.strides())
    assert prints[:2] == list(standing_feet(0.25, "right"))
    _assert_same([(f.x, f.y, f.yaw, f.side) for f in prints[2:]],
                 [(f.x, f.y, f.yaw, f.side) for f in scenario.footholds])  # fmt: skip


def test_a_per_step_phase_too_long_for_the_pendulum_names_the_step(tmp_path):
    steps = _bad(lambda s: s[1].update(single_support=30.0))
    with pytest.raises(ScenarioError, match="step 2 single_support must be at most"):
        load_scenario(_write(tmp_path, steps))


def test_the_auto_connection_refuses_a_per_step_timed_plan(tmp_path):
    path = _write(tmp_path, STEPS)
    path.write_text(path.read_text().replace('"quasi-real-time"', '"auto"'))
    with pytest.raises(ScenarioError, match="per-step timings are unsupported"):
        load_scenario(path)
    uniform = [{k: v for k, v in step.items() if not k.endswith("_support")} for step in STEPS]
    path = _write(tmp_path, uniform, "uniform.toml")
    path.write_text(path.read_text().replace('"quasi-real-time"', '"auto"'))
    assert load_scenario(path).connection == "auto"
