"""Per-step timing: each step's single support and the double support after it may differ (``Timing.per_step``)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from rtgait.core.analysis.family_key import FamilyKey
from rtgait.core.analysis.walk_family import WalkFamily
from rtgait.core.geometry.footsteps import SoleRect, Stride, Timeline, Timing
from rtgait.core.planner.online import SAMPLE_FIELDS, OnlinePlanner, PlannerConfig, straight_walk
from rtgait.core.walk.walk import VelocityCommand

DT = 1e-3
COL = {name: i for i, name in enumerate(SAMPLE_FIELDS)}
PER_STEP = ((0.8, 0.2), (0.5, 0.35), (1.1, 0.1), (0.6, 0.25), (0.7, 0.15), (0.9, 0.3), (0.8, 0.2))
BASE = Timing(0.8, 0.2, start=0.9, end=0.7, settle=1.5)


def _timing(per_step=PER_STEP) -> Timing:
    return Timing(BASE.single_support, BASE.double_support, BASE.start, BASE.end, BASE.settle, per_step=per_step)


def _expected_durations(n: int, per_step, timing: Timing) -> list[float]:
    """Phase durations of an ``n``-step walk, written out independently of :class:`Timeline`."""
    durations = [timing.start]
    for k in range(1, n + 1):
        single, double = per_step[k - 1] if k <= len(per_step) else (timing.single_support, timing.double_support)
        durations.append(single)
        durations.append(double if k < n else timing.end)
    return [*durations, timing.settle]


@pytest.mark.parametrize("n", [3, 7, 12])
def test_phase_boundaries_are_the_cumulative_sums_of_the_durations(n):
    per_step = PER_STEP[: min(n, len(PER_STEP))]
    timing = _timing(per_step)
    timeline = Timeline(timing, n, per_step)
    durations = _expected_durations(n, per_step, timing)
    starts = np.concatenate(([0.0], np.cumsum(durations)))
    for q in range(2 * n + 2):
        assert timeline.duration(q) == durations[q]
        assert timeline.start_time(q) == pytest.approx(starts[q], abs=1e-12)
        assert timeline.phase_at(timeline.start_time(q)) == q
        assert timeline.phase_at(timeline.start_time(q) + 1e-9) == q
        if q > 0:
            assert timeline.phase_at(timeline.start_time(q) - 1e-9) == q - 1
    assert timeline.end_time == pytest.approx(starts[-1], abs=1e-12)
    assert timeline.phase_at(starts[-1] + 100.0) == 2 * n + 1


def test_an_open_ended_timeline_continues_uniformly_after_the_given_steps():
    per_step = PER_STEP[:3]
    timeline = Timeline(_timing(per_step), None, per_step)
    durations = _expected_durations(30, per_step, BASE)[:-3]  # the walk never ends
    starts = np.concatenate(([0.0], np.cumsum(durations)))
    for q in range(len(durations)):
        assert timeline.start_time(q) == pytest.approx(starts[q], abs=1e-12)
        assert timeline.phase_at(starts[q] + 1e-9) == q


def test_the_planner_walks_the_given_phases():
    """Support labels of a sampled walk change exactly at the cumulative sums of the given durations."""
    timing = _timing()
    config = PlannerConfig(timing=timing, connection="quasi-real-time")
    strides = straight_walk(config, len(PER_STEP) - 1, 0.1)
    planner = OnlinePlanner(config, strides)
    planner.start(0.0)
    expected = np.cumsum(_expected_durations(len(PER_STEP), PER_STEP, timing))
    changes = []
    previous = None
    for k in range(round(planner.end_time / DT) + 1):
        _, _, phase = planner.sample_values(k * DT)
        if previous is not None and phase != previous:
            changes.append(k * DT)
        previous = phase
    assert len(changes) == len(expected) - 1
    assert np.abs(np.array(changes) - expected[:-1]).max() <= DT + 1e-9
    assert planner.end_time == pytest.approx(expected[-1], abs=1e-12)


def _rollout(planner: OnlinePlanner, change_at: float | None = None) -> tuple[np.ndarray, list]:
    planner.start(0.0)
    rows, connections, previous = [], [], None
    for k in range(round(planner.end_time / DT) + 1):
        t = k * DT
        if change_at is not None and abs(t - change_at) < DT / 2:
            planner.change_step(planner.first_open_step() + 1, length=0.16, through=planner.n_steps - 1)
        replans = planner.replan_count
        values, _, _ = planner.sample_values(t)
        rows.append(values)
        if planner.replan_count != replans:
            if previous is not None:
                connections.append((previous, planner.current_plan, planner.plans[-1].t))
            previous = planner.current_plan
    return np.array(rows), connections


@pytest.mark.parametrize("connection", ["real-time", "quasi-real-time"])
def test_pendulum_equation_and_continuity_hold_across_replanning(connection):
    config = PlannerConfig(timing=_timing(), connection=connection)
    planner = OnlinePlanner(config, straight_walk(config, len(PER_STEP) - 1, 0.1))
    x, connections = _rollout(planner, change_at=2.0)
    w2 = planner.w**2
    c, v, a, p = (slice(COL[f"{name}x"], COL[f"{name}y"] + 1) for name in ("cog_", "cog_v", "cog_a", "zmp_"))
    assert np.abs(x[:, p] - (x[:, c] - x[:, a] / w2)).max() < 1e-8
    moving = ~(np.all(x[1:, v] == 0.0, axis=1) & np.all(x[:-1, v] == 0.0, axis=1))
    pos_err = x[1:, c] - x[:-1, c] - 0.5 * (x[1:, v] + x[:-1, v]) * DT
    vel_err = x[1:, v] - x[:-1, v] - 0.5 * (x[1:, a] + x[:-1, a]) * DT
    assert np.abs(pos_err[moving]).max() < 1e-7
    assert np.abs(vel_err[moving]).max() < 1e-5
    assert len(connections) == len(PER_STEP)
    for old, new, t in connections:
        for before, after in zip(old.evaluate(t, side="left")[:2], new.evaluate(t)[:2], strict=True):
            assert np.abs(before - after).max() < 1e-9
        assert np.abs(old.zmp.evaluate(t, side="left") - new.zmp.evaluate(t)).max() < 1e-9
        assert np.abs(old.zmp.evaluate(t, derivative=1, side="left") - new.zmp.evaluate(t, derivative=1)).max() < 1e-7
    assert np.abs(x[-1, v]).max() < 1e-9  # ends at rest


def test_uniform_per_step_timings_give_the_plan_of_the_global_timing():
    steps = 6
    uniform = _timing(((BASE.single_support, BASE.double_support),) * (steps + 1))
    rows = []
    for timing in (BASE, uniform):
        config = PlannerConfig(timing=timing, connection="real-time")
        planner = OnlinePlanner(config, straight_walk(config, steps, 0.12))
        rows.append(_rollout(planner, change_at=3.0)[0])
    assert rows[0].shape == rows[1].shape
    assert np.abs(rows[0] - rows[1]).max() < 1e-12


def test_every_operator_is_built_at_start():
    config = PlannerConfig(timing=_timing(), connection="real-time", horizon_steps=2)
    planner = OnlinePlanner(config, straight_walk(config, len(PER_STEP) - 1, 0.1))
    planner.start(0.0)
    built = dict(planner._layouts)
    shapes = {planner.timeline.durations(q, planner._plan_span(q)) for q in range(0, 2 * planner.n_steps + 1, 2)}
    assert len(built) == len(shapes)  # one per distinct timing, none shared wrongly by shape
    for k in range(round(planner.end_time / DT) + 1):
        planner.sample_values(k * DT)
    assert planner._layouts == built  # no replan had to build one
    for record in planner.plans:
        layout = planner._layout(record.phase, planner._plan_span(record.phase))
        assert tuple(layout.durations) == planner.timeline.durations(record.phase, planner._plan_span(record.phase))


def test_step_changes_keep_each_steps_timing():
    timing = _timing()
    config = PlannerConfig(timing=timing, connection="real-time")
    planner = OnlinePlanner(config, straight_walk(config, len(PER_STEP) - 1, 0.1))
    planner.start(0.0)
    before = [planner.timeline.start_time(q) for q in range(2 * planner.n_steps + 2)]
    planner.change_step(2, length=0.2, through=4)
    assert [planner.timeline.start_time(q) for q in range(2 * planner.n_steps + 2)] == before
    planner.set_strides([Stride(0.1, 0.19)] * 3 + [Stride(0.0, 0.19)], from_step=2)
    assert planner.n_steps == 5
    assert [planner.timeline.duration(q) for q in range(1, 10)] == _expected_durations(5, PER_STEP, timing)[1:10]


def test_a_walk_by_velocity_command_is_uniform():
    planner = OnlinePlanner(PlannerConfig(timing=_timing()), None)
    assert planner.timeline.uniform
    finite = OnlinePlanner(PlannerConfig(timing=_timing()), straight_walk(PlannerConfig(), 6, 0.1))
    finite.start(0.0)
    for k in range(round(2.0 / DT)):
        finite.sample_values(k * DT)
    open_step = finite.first_open_step()
    finite.set_velocity(0.1)
    timeline = finite.timeline
    assert timeline.step_timings == PER_STEP[: open_step - 1]
    assert timeline.duration(2 * open_step - 1) == BASE.single_support


def test_auto_connection_and_batched_evaluation_refuse_per_step_timings():
    sole = SoleRect(0.13, 0.10, 0.07, 0.07)
    config = PlannerConfig(timing=_timing(), connection="auto", sole=sole)
    with pytest.raises(ValueError, match="per-step timings"):
        OnlinePlanner(config, straight_walk(config, 3, 0.1))
    key = FamilyKey(cog_height=0.8, gravity=9.81, timing=_timing(), horizon_steps=3, first_degree=4,
                    first_side="right", sole=sole, dt=0.005, steps=3, changes=())  # fmt: skip
    with pytest.raises(ValueError, match="per-step timings"):
        WalkFamily(key)


@pytest.mark.parametrize(
    ("per_step", "match"),
    [(((0.8, math.nan),), "step 1 double_support"), (((0.8, 0.2), (-1.0, 0.2)), "step 2 single_support"),
     (((0.8, 0.2), (0.8, 100.0)), "step 2 double_support"), ([(0.8, 0.2)], "tuple")],
)  # fmt: skip
def test_bad_per_step_timings_are_refused_naming_the_step(per_step, match):
    with pytest.raises(ValueError, match=match):
        Timing(0.8, 0.2, per_step=per_step)


def test_per_step_phases_too_long_for_the_pendulum_are_refused():
    timing = Timing(0.8, 0.2, per_step=((0.8, 0.2), (30.0, 0.2)))
    with pytest.raises(ValueError, match="step 2 single_support"):
        OnlinePlanner(PlannerConfig(timing=timing), [Stride(0.1, 0.19)] * 3)


def test_uniform_timeline_keeps_its_closed_form():
    timeline = Timeline(BASE, 9)
    assert timeline.uniform and timeline._starts == ()
    for q, r in itertools.pairwise(range(20)):
        assert timeline.phase_at(timeline.start_time(r)) == min(r, 19)
        assert timeline.start_time(q) <= timeline.start_time(r)


def test_a_trial_restores_the_step_timings():
    planner = OnlinePlanner(PlannerConfig(timing=_timing()), straight_walk(PlannerConfig(), 6, 0.1))
    walk = planner.walk
    with walk.trial():
        walk.set_velocity(VelocityCommand(0.1))
        assert walk.timeline.step_timings == ()
    assert walk.timeline.step_timings == PER_STEP and walk.n_steps == 7
