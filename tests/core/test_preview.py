"""The ZMP preview control baseline (Kajita et al. 2003): its gains, its loop, and its batched evaluation."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rtgait.core import rollout
from rtgait.core.analysis.batch import StraightWalk
from rtgait.core.analysis.preview import PREVIEW_PERIOD, PreviewPlanner, evaluate_preview, preview_gains
from rtgait.core.planner.sample import SAMPLE_FIELDS
from rtgait.scenario.loading import load_scenario
from rtgait.viz.margin_marker import margin_marker


def test_gains_track_a_step_of_the_reference():
    """With the step 2 s ahead (more than the preview), the ZMP follows it; the error then vanishes (integral)."""
    g = preview_gains(0.8, 9.81)
    assert g.steps == round(1.6 / PREVIEW_PERIOD) and g.Gd[0] == pytest.approx(-g.Gi)
    assert g.Gx[0] == pytest.approx(-g.Gd.sum(), rel=0.01)  # standing on a constant reference needs no jerk
    ticks = 1200
    ref = np.where(np.arange(ticks + g.steps + 1) * g.period >= 2.0, 0.1, 0.0)
    x, error, zmp = np.zeros(3), 0.0, np.empty(ticks)
    for k in range(ticks):
        zmp[k] = g.C @ x
        error += zmp[k] - ref[k]
        u = -g.Gi * error - g.Gx @ x - g.Gd @ ref[k + 1 : k + 1 + g.steps]
        x = g.A @ x + g.B * u
    assert np.sqrt(np.mean((zmp - ref[:ticks]) ** 2)) < 0.003
    assert abs(zmp[-1] - 0.1) < 1e-6 and zmp.max() < 0.11


def scenario_walk(name: str):
    scenario = load_scenario(name)
    config = replace(scenario.planner_config(), connection="real-time")
    walk = StraightWalk(config, scenario.sole, scenario.dt, scenario.steps, scenario.step_length, scenario.changes)
    return scenario, config, walk


@pytest.mark.parametrize("name", ["fig4", "fig6", "fig8"])
def test_batched_preview_equals_its_rollout(name):
    scenario, config, walk = scenario_walk(name)
    planner = PreviewPlanner(config, scenario.strides())
    run = rollout(planner, PREVIEW_PERIOD, scenario.sole, scenario.changes)
    margin, time, deviation = evaluate_preview(walk, walk.parameters()[None])
    assert margin[0] == pytest.approx(run.zmp_margin_min, abs=1e-9)
    assert time[0] == run.times[margin_marker(run.times, run.margin, [t for t, _ in run.changes]).index]
    zmp = np.stack([run.column("zmp_x"), run.column("zmp_y")], axis=1)
    ref = np.stack([run.column("zmp_ref_x"), run.column("zmp_ref_y")], axis=1)
    np.testing.assert_allclose(deviation[0], np.abs(zmp - ref).max(axis=0), atol=1e-9)
    assert deviation[0][0] > 0.005  # the realised ZMP is not the reference: it is what is measured
    # The realised ZMP is the cart-table's: c - zc / g c''.
    acc = run.values[:, [SAMPLE_FIELDS.index("cog_ax"), SAMPLE_FIELDS.index("cog_ay")]]
    cog = run.values[:, [SAMPLE_FIELDS.index("cog_x"), SAMPLE_FIELDS.index("cog_y")]]
    np.testing.assert_allclose(zmp, cog - config.cog_height / config.gravity * acc, atol=1e-12)


def test_preview_sees_a_change_only_once_decided():
    scenario, config, _ = scenario_walk("fig4")
    changed = rollout(PreviewPlanner(config, scenario.strides()), PREVIEW_PERIOD, scenario.sole, scenario.changes)
    plain = rollout(PreviewPlanner(config, scenario.strides()), PREVIEW_PERIOD, scenario.sole, ())
    decided = changed.changes[0][0]
    before, after = changed.times <= decided, changed.times > decided + 0.05
    zmp = slice(SAMPLE_FIELDS.index("zmp_x"), SAMPLE_FIELDS.index("zmp_y") + 1)
    np.testing.assert_array_equal(changed.values[before, zmp], plain.values[before, zmp])
    assert np.abs(changed.values[after, zmp] - plain.values[after, zmp]).max() > 0.05


def test_many_cases_at_once_equal_one_at_a_time():
    _, _, walk = scenario_walk("fig4")
    theta = np.repeat(walk.parameters()[None], 4, axis=0)
    theta[:, 3] = [0.05, 0.1, 0.15, 0.3]
    margins, times, deviations = evaluate_preview(walk, theta)
    for i, length in enumerate(theta[:, 3]):
        one = replace(walk, changes=(replace(walk.changes[0], length=float(length)),))
        m, t, d = evaluate_preview(one, one.parameters()[None])
        assert (margins[i], times[i]) == pytest.approx((m[0], t[0]), abs=1e-12)
        np.testing.assert_allclose(deviations[i], d[0], atol=1e-12)
    assert margins[0] > margins[-1]  # a larger late change is harder for the preview too
