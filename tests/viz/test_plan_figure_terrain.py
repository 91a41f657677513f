"""The plan's zmp_cog off the flat floor: the terrain's side view under the planned feet, drawn again by
``rtgait plot`` from the run's files; a level walk's figure keeps its panels."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from rtgait.cli.main import main
from rtgait.core.analysis.rollout import rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario
from rtgait.viz.figures import draw_zmp_cog
from rtgait.viz.run_data import FigureInfo, PlanRun, read_plan_run


def _figure_parts(name: str, with_terrain: bool = True):
    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    result = rollout(planner, scenario.dt, scenario.sole, scenario.changes)
    terrain = scenario.terrain.terrain if scenario.terrain is not None and with_terrain else None
    return result, FigureInfo(name, scenario.sole, scenario.nominal_footprints(), terrain), scenario


def test_stairs_up_draws_the_planned_feet_over_the_treads() -> None:
    result, info, scenario = _figure_parts("stairs-up")
    figure = draw_zmp_cog(PlanRun.from_rollout(result), info)
    assert len(figure.axes) == 4  # x, y, heights against time; the side view
    side = figure.axes[3]
    lines = {str(line.get_label()): np.asarray(line.get_xydata()) for line in side.get_lines()}
    for side_name, foot in (("left", "lfoot"), ("right", "rfoot")):
        expected = np.column_stack([result.column(f"{foot}_x"), result.column(f"{foot}_z")])
        np.testing.assert_array_equal(lines[f"{side_name} sole (planned)"], expected)
    # Each foothold stands on the tread under it: the planned feet at rest lie on the terrain's profile.
    for foot in scenario.nominal_footprints():
        assert foot.z == pytest.approx(float(info.terrain.height(foot.x, 0.0)), abs=1e-12)
    assert len(draw_zmp_cog(PlanRun.from_rollout(result), _figure_parts("stairs-up", False)[1]).axes) == 3


def test_a_level_walk_keeps_its_two_panels() -> None:
    result, info, _ = _figure_parts("fig4")
    assert len(draw_zmp_cog(PlanRun.from_rollout(result), info).axes) == 2


def test_rtgait_plot_draws_the_side_view_again(tmp_path: Path) -> None:
    out = tmp_path / "stairs"
    assert main(["plan", "stairs-up", "--out", str(out), "--quiet"]) == 0
    run, info, summary = read_plan_run(out)
    assert summary["terrain"]["fields"]["kind"] == "stairs"
    scenario = load_scenario("stairs-up")
    assert info.terrain == scenario.terrain.terrain
    result, _, _ = _figure_parts("stairs-up")
    np.testing.assert_allclose(run.feet_xz, PlanRun.from_rollout(result).feet_xz, atol=1e-9)  # the CSV's digits
    assert len(draw_zmp_cog(run, info).axes) == 4
