"""The "auto" connection: per change, real-time if it keeps the ZMP inside, else quasi-real-time, else later."""

from __future__ import annotations

import ast
import inspect
from dataclasses import replace

import numpy as np
import pytest

from rtgait.core import (
    OnlinePlanner,
    PlannerConfig,
    ScheduledChange,
    SoleRect,
    StepChangeTooLateError,
    Timing,
    rollout,
    straight_walk,
)
from rtgait.core.analysis.batch import StraightWalk, evaluate_parameters, evaluate_walks
from rtgait.core.planner import auto
from rtgait.core.planner.auto import auto_options, window
from rtgait.io.plan_report import plan_report
from rtgait.io.plan_summary import summarize
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import ScenarioError
from rtgait.scenario.scenario_file import parse_scenario

SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)


def auto_planner(single: float, double: float, length: float = 0.05, margin: float = 0.01) -> OnlinePlanner:
    config = PlannerConfig(timing=Timing(single, double), step_width=0.19, connection="auto", sole=SOLE,
                           auto_margin=margin)  # fmt: skip
    planner = OnlinePlanner(config, straight_walk(config, 10, length))
    planner.start(0.0)
    return planner


def walk_to(planner: OnlinePlanner, t_end: float, dt: float = 0.005) -> None:
    t = max(planner.latest_time, 0.0)
    while t < t_end - 1e-12:
        planner.sample(t)
        t += dt
    planner.sample(t_end)


def lift_off(planner: OnlinePlanner, step: int) -> float:
    return planner.phase_start(2 * step - 1)


def test_small_change_is_held_for_the_real_time_connection():
    """fig6-like: 0.11 -> 0.12 m, T_dbl 0.2 s. Known early, it is still committed only at step 5's lift-off."""
    planner = auto_planner(0.8, 0.2, length=0.11)
    walk_to(planner, 3.0)
    before = planner.footprints()[6].x
    planner.change_step(5, length=0.12, through=10)
    record = planner.change_log[-1]
    assert (record.connection, record.committed_step) == ("real-time", 5)
    assert record.commit_time == pytest.approx(lift_off(planner, 5))
    assert record.predicted[0][0] == "real-time" and record.predicted[0][2] >= 0.01
    walk_to(planner, lift_off(planner, 5) - 0.01)
    assert planner.footprints()[6].x == before  # held: the plans made until then do not see it
    walk_to(planner, lift_off(planner, 5) + 0.01)
    assert planner.footprints()[6].x == pytest.approx(before + 0.01)


@pytest.mark.parametrize(("single", "double"), [(0.8, 0.2), (0.7, 0.1)])
def test_large_change_takes_the_quasi_real_time_connection(single, double):
    """fig4 / fig8-like: 0.05 -> 0.15 m, which the real-time connection cannot absorb."""
    planner = auto_planner(single, double)
    walk_to(planner, planner.phase_start(8) - 0.05)  # before the double support that precedes step 5's lift-off
    planner.change_step(5, length=0.15, through=10)
    record = planner.change_log[-1]
    assert record.connection == "quasi-real-time" and record.committed_step == 5
    kinds = [kind for kind, _, _ in record.predicted]
    assert kinds == ["real-time", "quasi-real-time"]
    assert record.predicted[0][2] < 0.0 <= 0.01 <= record.predicted[1][2]
    assert planner.footprints()[6].x == pytest.approx(0.05 * 4 + 0.15)  # applied at once


def test_defers_when_neither_deadline_allows():
    """The same large change arriving in the double support before step 5's lift-off: the quasi-real-time deadline
    has passed and the real-time connection topples, so step 6 takes the new length instead."""
    planner = auto_planner(0.8, 0.2)
    walk_to(planner, planner.phase_start(8) + 0.05)
    planner.change_step(5, length=0.15, through=10)
    record = planner.change_log[-1]
    assert record.connection == "deferred" and record.committed_step == 6 and record.through == 10
    prints = planner.footprints()
    assert prints[6].x - prints[5].x == pytest.approx(0.05)  # step 5 keeps its length
    assert prints[7].x - prints[6].x == pytest.approx(0.15)
    # And the walk it makes keeps the ZMP inside.
    times = np.arange(planner.latest_time + 0.005, planner.end_time, 0.005)
    margins = np.array([planner.zmp_margin(planner.sample(t), SOLE) for t in times])
    assert margins.min() > 0.0


def test_a_newer_wish_for_a_held_step_replaces_it():
    """A small change held for step 5's lift-off, then a large one for the same step before the quasi-real-time
    deadline: the large one is applied at once and the held one never is."""
    planner = auto_planner(0.8, 0.2, length=0.11)
    walk_to(planner, 3.0)
    planner.change_step(5, length=0.12, through=10)
    assert planner.change_log[-1].connection == "real-time"
    planner.change_step(5, length=0.2, through=10)
    assert planner.change_log[-1].connection == "quasi-real-time"
    expected = planner.footprints()[6].x
    walk_to(planner, lift_off(planner, 5) + 0.01)
    assert planner.footprints()[6].x == pytest.approx(expected) == pytest.approx(0.11 * 4 + 0.2)


def test_the_auto_connection_touches_nothing_private_of_its_planner():
    """It reads its planner through :class:`AutoPlanner` and changes only the walk, through the walk's methods."""
    tree = ast.parse(inspect.getsource(auto))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
            owner = node.value
            assert isinstance(owner, ast.Name) and owner.id == "self", ast.unparse(node)
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Attribute):
                    assert ast.unparse(target.value) == "self", ast.unparse(target)


def test_too_late_after_lift_off():
    planner = auto_planner(0.8, 0.2)
    walk_to(planner, lift_off(planner, 5) + 0.01)
    with pytest.raises(StepChangeTooLateError, match="step 5"):
        planner.change_step(5, length=0.15)


def test_auto_needs_a_sole_and_a_sane_margin():
    with pytest.raises(ValueError, match="needs sole"):
        PlannerConfig(connection="auto")
    with pytest.raises(ValueError, match="auto_margin"):
        PlannerConfig(connection="auto", sole=SOLE, auto_margin=2.0)


def test_options_and_windows():
    options = auto_options(5, 10, next_replan=8, n_steps=11, horizon_steps=3)
    assert [(o.kind, o.step, o.commit_phase) for o in options] == [
        ("real-time", 5, 9), ("quasi-real-time", 5, None), ("deferred", 6, None), ("deferred", 7, None),
        ("deferred", 8, None),
    ]  # fmt: skip
    assert options[0].window == (10, 18) and options[1].window == (8, 16)
    late = auto_options(5, 5, next_replan=10, n_steps=11, horizon_steps=3)  # a one-step change, quasi past
    assert [(o.kind, o.step, o.through) for o in late] == [("real-time", 5, 5), ("deferred", 6, 6),
                                                            ("deferred", 7, 7), ("deferred", 8, 8)]  # fmt: skip
    assert window(18, 3, 11) == (18, 22)


@pytest.mark.parametrize(("name", "kind"), [("fig4", "quasi-real-time"), ("fig6", "real-time"),
                                             ("fig7", "real-time"), ("fig8", "quasi-real-time")])  # fmt: skip
def test_paper_cases_in_auto_mode(name, kind):
    scenario = replace(load_scenario(name), connection="auto")
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    run = rollout(planner, scenario.dt, scenario.sole, scenario.changes)
    assert planner.change_log[-1].connection == kind
    assert not run.zmp_outside
    summary = summarize(run, scenario)
    (decision,) = summary["auto_decisions"]
    assert decision["connection"] == kind and decision["arrived_at"] == summary["changes"][0]["decided_at"]
    assert f"-> {kind}" in plan_report({**summary, "files": [], "rows": 0}, __import__("pathlib").Path("x"), 0.0)
    # The batched evaluation makes the same choice and the same walk.
    batch = evaluate_walks([StraightWalk(scenario.planner_config(), scenario.sole, scenario.dt, scenario.steps,
                                         scenario.step_length, scenario.changes)])  # fmt: skip
    assert batch.decisions[0] == kind
    assert batch.zmp_margin_min[0] == pytest.approx(run.zmp_margin_min, abs=1e-9)


def test_batched_auto_matches_the_planner_on_random_changes():
    rng = np.random.default_rng(11)
    base = replace(load_scenario("fig4"), connection="auto")
    for _ in range(8):
        timing = Timing(float(rng.choice([0.7, 0.8])), float(rng.choice([0.05, 0.1, 0.2, 0.5])))
        step = int(rng.integers(2, 9))
        change = ScheduledChange(step, length=float(rng.uniform(-0.1, 0.45)), through=10 if rng.integers(2) else step)
        scenario = replace(base, timing=timing, changes=(change,), auto_margin=float(rng.choice([0.0, 0.01, 0.03])))
        planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
        run = rollout(planner, scenario.dt, scenario.sole, scenario.changes)
        batch = evaluate_walks([StraightWalk(scenario.planner_config(), scenario.sole, scenario.dt, scenario.steps,
                                             scenario.step_length, scenario.changes)])  # fmt: skip
        assert batch.decisions[0] == planner.change_log[-1].connection
        assert batch.zmp_margin_min[0] == pytest.approx(run.zmp_margin_min, abs=1e-9)


def test_auto_region_contains_both_others():
    """On a grid of changes x double-support times, wherever real-time or quasi-real-time keeps the ZMP inside,
    so does auto."""
    base = load_scenario("fig4")
    lengths = np.linspace(-0.1, 0.45, 23)
    real_time_outside = 0
    for double in (0.05, 0.1, 0.2, 0.4, 0.8, 1.5):
        inside = {}
        for mode in ("real-time", "quasi-real-time", "auto"):
            s = replace(base, connection=mode, timing=Timing(0.8, double))
            walk = StraightWalk(s.planner_config(), s.sole, s.dt, s.steps, s.step_length, s.changes)
            theta = np.repeat(walk.parameters()[None], len(lengths), axis=0)
            theta[:, 3] = lengths
            inside[mode] = ~evaluate_parameters(walk, theta).zmp_outside
        assert not np.any((inside["real-time"] | inside["quasi-real-time"]) & ~inside["auto"]), double
        real_time_outside += int(np.sum(~inside["real-time"]))
    assert real_time_outside > 10  # the grid does reach well outside the real-time region


def test_scenario_files_take_auto():
    text = load_scenario("fig4")
    document = {
        "name": "a", "connection": "auto", "auto_margin": 0.02,
        "robot": {"cog_height": 0.8, "sole": {"front": 0.13, "back": 0.1, "inner": 0.07, "outer": 0.07}},
        "timing": {"single_support": 0.8, "double_support": 0.2, "dt": 0.005, "horizon_steps": 3},
        "walk": {"steps": 4, "step_length": 0.05, "step_width": 0.19, "step_height": 0.05},
    }  # fmt: skip
    scenario = parse_scenario(document)
    assert scenario.connection == "auto" and scenario.auto_margin == 0.02
    config = scenario.planner_config()
    assert config.sole == text.sole and config.auto_margin == 0.02
    with pytest.raises(ScenarioError, match="auto_margin is for"):
        parse_scenario({**document, "connection": "real-time"})
    with pytest.raises(ScenarioError, match="auto_margin"):
        parse_scenario({**document, "auto_margin": 3.0})
