"""Batched evaluation of whole walks (rtgait.core.analysis.batch) against the rollout `rtgait plan` makes, case by
case."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rtgait.core import OnlinePlanner, PlannerConfig, ScheduledChange, SoleRect, Stride, Timing, rollout
from rtgait.core.analysis.batch import StraightWalk, evaluate_parameters, evaluate_walks, walk_family
from rtgait.core.analysis.family_key import family_key
from rtgait.core.analysis.walk_family import TIE
from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.hull import PointChain, outside_margin, sole_extents, two_box_hull, two_box_vertices
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.geometry.support_height import support_heights
from rtgait.io.plan_summary import summarize
from rtgait.scenario.loading import load_scenario
from rtgait.viz.margin_marker import MARGIN_TIE_TOLERANCE, margin_marker

PAPER = ("fig4", "fig6", "fig7", "fig8", "fig8-real-time", "sidestep")


def as_walk(scenario) -> StraightWalk:
    return StraightWalk(
        scenario.planner_config(), scenario.sole, scenario.dt, scenario.steps, scenario.step_length, scenario.changes
    )


def reference(config: PlannerConfig, sole: SoleRect, dt: float, steps: int, length: float, changes) -> dict:
    """What `rtgait plan` reports, from the rollout itself (report.summarize's definitions)."""
    strides = [Stride(length, config.step_width)] * steps + [Stride(0.0, config.step_width)]
    run = rollout(OnlinePlanner(config, strides), dt, sole, changes)
    zmp = np.stack([run.column("zmp_x"), run.column("zmp_y")], axis=1)
    ref = np.stack([run.column("zmp_ref_x"), run.column("zmp_ref_y")], axis=1)
    free = run.free_segment_mask()
    deviation = np.abs((zmp - ref)[free]).max(axis=0) if free.any() else np.zeros(2)
    worst = margin_marker(run.times, run.margin, [t for t, _ in run.changes]).index  # as summary.json reports it
    return {"margin": run.zmp_margin_min, "time": float(run.times[worst]), "deviation": deviation}


def assert_same(got, index: int, want: dict) -> None:
    assert got.zmp_margin_min[index] == pytest.approx(want["margin"], abs=1e-9)
    np.testing.assert_allclose(got.zmp_deviation_max[index], want["deviation"], rtol=0, atol=1e-9)
    assert got.zmp_margin_min_time[index] == want["time"]


@pytest.mark.parametrize("name", PAPER)
def test_paper_cases_match_rtgait_plan(name):
    scenario = load_scenario(name)
    strides = scenario.strides()
    run = rollout(OnlinePlanner(scenario.planner_config(), strides), scenario.dt, scenario.sole, scenario.changes)
    summary = summarize(run, scenario)
    got = evaluate_walks([as_walk(scenario)])
    assert got.zmp_margin_min[0] == pytest.approx(summary["zmp_margin_min"], abs=1e-9)
    assert got.zmp_margin_min_time[0] == summary["zmp_margin_min_time"]
    np.testing.assert_allclose(got.zmp_deviation_max[0], summary["zmp_deviation_max"], rtol=0, atol=1e-9)
    assert bool(got.zmp_outside[0]) == summary["zmp_outside"]


def random_case(rng: np.random.Generator):
    timing = Timing(
        float(rng.choice([0.5, 0.7, 0.8])), float(rng.choice([0.05, 0.1, 0.2, 0.4])),
        start=float(rng.choice([0.5, 1.0])), end=1.0, settle=float(rng.choice([1.0, 2.0])),
    )  # fmt: skip
    config = PlannerConfig(
        cog_height=float(rng.uniform(0.6, 1.0)), timing=timing, step_width=float(rng.uniform(0.15, 0.25)),
        horizon_steps=int(rng.integers(1, 5)), connection=str(rng.choice(["real-time", "quasi-real-time"])),
        first_degree=int(rng.choice([4, 4, 2])), first_side=str(rng.choice(["left", "right"])),
    )  # fmt: skip
    sole = SoleRect(*(float(v) for v in rng.uniform(0.05, 0.15, 4)))
    steps = int(rng.integers(2, 8))
    changes = []
    for step in sorted(rng.choice(np.arange(1, steps + 1), size=int(rng.integers(0, 3)), replace=False)):
        length = float(rng.uniform(-0.2, 0.4)) if rng.integers(3) else None
        width = float(rng.uniform(0.12, 0.3)) if rng.integers(2) or length is None else None
        changes.append(ScheduledChange(int(step), length=length, width=width,
                                       through=int(step) if rng.integers(2) else steps))  # fmt: skip
    dt = float(rng.choice([0.005, 0.01, 0.0025]))
    return config, sole, dt, steps, float(rng.uniform(-0.1, 0.3)), tuple(changes)


def test_random_walks_match_the_rollout():
    """Seeded random walks: timings, both modes, lengths and widths, one-step and lasting changes, both feet first,
    the quadratic connection, several changes, other sampling periods."""
    rng = np.random.default_rng(20260601)
    cases = [random_case(rng) for _ in range(24)]
    got = evaluate_walks([StraightWalk(c, s, dt, n, length, ch) for c, s, dt, n, length, ch in cases])
    for i, case in enumerate(cases):
        assert_same(got, i, reference(*case))


def test_one_family_many_rows_equals_one_by_one():
    scenario = load_scenario("fig4")
    walk = as_walk(scenario)
    theta = np.repeat(walk.parameters()[None], 9, axis=0)
    theta[:, 3] = np.linspace(-0.1, 0.4, 9)  # the changed step length
    many = evaluate_parameters(walk, theta)
    for i, length in enumerate(theta[:, 3]):
        one = replace(scenario, changes=(replace(scenario.changes[0], length=float(length)),))
        want = reference(one.planner_config(), one.sole, one.dt, one.steps, one.step_length, one.changes)
        assert_same(many, i, want)
    assert many.zmp_outside.any() and not many.zmp_outside.all()


def test_random_rises_give_the_planner_s_cog_height_at_every_tick():
    """Seeded random walks whose steps go up, down a stair (the stance before it holds a lower support height) or by
    less than a stair's rise: the batch's COG height at every tick is the rollout's, from the footholds' heights and
    the stances' support heights alone."""
    rng = np.random.default_rng(20261205)
    lowered = 0
    for _ in range(8):
        config, sole, dt, steps, length, changes = random_case(rng)
        rises = rng.choice([-0.15, -0.06, -0.004, 0.0, 0.004, 0.1], size=steps).tolist()
        strides = [Stride(length, config.step_width, rise=r) for r in rises] + [Stride(0.0, config.step_width)]
        run = rollout(OnlinePlanner(config, strides), dt, sole, changes)
        heights = np.array([foot.z for foot in run.footprints])
        support = np.array(support_heights(run.footprints))
        lowered += int(np.sum(support < heights - 1e-9))
        walk = StraightWalk(config, sole, dt, steps, length, changes, tuple(heights), tuple(support))
        family = walk_family(family_key(config, sole, dt, steps, walk.shapes()))
        np.testing.assert_allclose(family.cog_heights(heights, support)[0], run.column("cog_z"), rtol=0, atol=1e-9)
        got = evaluate_walks([walk])
        assert got.cog_z_min[0] == pytest.approx(run.column("cog_z").min(), abs=1e-9)
        assert got.cog_z_max[0] == pytest.approx(run.column("cog_z").max(), abs=1e-9)
    assert lowered >= 5  # the stances' own support heights were exercised, not only the footholds'


def test_support_heights_need_the_footholds_heights_and_their_shape():
    scenario = load_scenario("stairs-down")
    walk = as_walk(scenario)
    with pytest.raises(ValueError, match="footholds' heights"):
        evaluate_parameters(walk, walk.parameters(), support=np.zeros((1, scenario.steps + 3)))
    with pytest.raises(ValueError, match="support heights must be finite"):
        evaluate_parameters(walk, walk.parameters(), np.zeros((1, scenario.steps + 3)), support=np.zeros((1, 3)))


def test_ties_are_broken_as_rtgait_plan_does():
    assert MARGIN_TIE_TOLERANCE == TIE


def test_turning_walks_are_refused():
    scenario = load_scenario("fig4")
    walk = replace(as_walk(scenario), changes=(ScheduledChange(5, turn=0.1, through=10),))
    with pytest.raises(ValueError, match="straight walks"):
        evaluate_walks([walk])


def test_two_box_hull_is_the_support_polygon():
    rng = np.random.default_rng(3)
    for _ in range(50):
        sole = SoleRect(*(float(v) for v in rng.uniform(0.02, 0.2, 4)))
        left = Footstep(*(float(v) for v in rng.uniform(-0.3, 0.3, 2)), 0.0, "left")
        right = Footstep(*(float(v) for v in rng.uniform(-0.3, 0.3, 2)), 0.0, "right")
        a = (np.array(sole_extents(sole, True)) + np.array([left.x, left.x, left.y, left.y]))[None]
        b = (np.array(sole_extents(sole, False)) + np.array([right.x, right.x, right.y, right.y]))[None]
        nx, ny, c = two_box_hull(a, b)
        points = rng.uniform(-0.6, 0.6, (100, 2))
        inside = np.min(c - points[:, :1] * nx - points[:, 1:] * ny, axis=1)
        outside = outside_margin(points[None, :, 0], points[None, :, 1], two_box_vertices(a, b))[0]
        mine = np.where(inside >= 0.0, inside, outside)
        np.testing.assert_allclose(mine, signed_margin(points, support_polygon([left, right], sole)), atol=1e-12)


def test_point_chain_finds_the_maximum():
    rng = np.random.default_rng(4)
    u = np.linspace(0.0, 1.0, 41)
    for points in (rng.normal(size=(30, 2)), np.stack([3 * u**2 - 2 * u**3, (u * (1 - u)) ** 2], 1),
                   np.stack([np.zeros(41), u], 1), np.ones((3, 2))):  # fmt: skip
        chain = PointChain(points)
        v = rng.normal(size=(200, 2))
        value, index = chain.maximum(v[:, 0], v[:, 1])
        np.testing.assert_allclose(value, (v @ points.T).max(axis=1), atol=1e-12)
        np.testing.assert_allclose(value, np.einsum("kd,kd->k", v, points[index]), atol=1e-12)
