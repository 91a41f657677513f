"""The built-in walks off the flat floor at the pendulum level: ``rtgait plan NAME`` works and draws the
heights, and each walk's expected outcome holds against independent truths (the terrain, the full ZMP equation)."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from rtgait.cli.main import main
from rtgait.core.analysis.height_error import zmp_error
from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.swing_terrain import swing_gaps
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario

TEN_DEGREES = math.radians(10.0)
# name: (height of the last foothold (m), largest full-ZMP error allowed (m)): stairs 6 x 15 cm, slopes 10 deg x 2 m.
# Down the stairs each stance before a step down holds its support height half a riser lower (support_height.py): the
# full ZMP then errs by (r/2) |c''| / g in those single supports, 0.075 m x 0.13 = 10 mm at most (0.0925 m x 0.13 =
# 12 mm down BaselineWalkingController's 18.5 cm staircase).
OUTCOMES = {
    "stairs-up": (0.9, 0.005),
    "stairs-down": (-0.9, 0.012),
    "stairs-up-185": (6 * 0.185, 0.005),
    "stairs-down-185": (-6 * 0.185, 0.0145),
    "slope-up": (2.0 * math.tan(TEN_DEGREES), 0.001),
    "slope-down": (-2.0 * math.tan(TEN_DEGREES), 0.001),
    "stepping-stones": (0.0, 1e-9),
}


def _roll(name: str):
    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    return scenario, rollout(planner, scenario.dt, scenario.sole, scenario.changes)


@pytest.mark.parametrize("name", sorted(OUTCOMES))
def test_walk_off_the_floor_keeps_the_zmp_inside_and_ends_at_rest_on_the_top(name):
    scenario, result = _roll(name)
    top, max_error = OUTCOMES[name]
    assert result.zmp_margin_min > 0.03  # m: the ZMP stays well inside every support polygon
    assert result.footprints[-1].z == pytest.approx(top, abs=1e-9)
    # At rest zc above the last footholds: the terrain's height there, not the plan's bookkeeping.
    last = result.footprints[-1]
    assert result.column("cog_z")[-1] == pytest.approx(
        scenario.cog_height + scenario.terrain.terrain.height(last.x, last.y), abs=1e-6
    )
    assert np.max(zmp_error(result, scenario.terrain.terrain, scenario.gravity)) <= max_error


def test_stepping_stones_put_every_foot_on_a_stone():
    scenario, result = _roll("stepping-stones")
    stones = scenario.terrain.terrain
    on_stones = [f for f in result.footprints[2:] if stones.start <= f.x <= stones.end]
    assert len(on_stones) == 6
    for foot in on_stones:
        k = round((foot.x - stones.centre(0)) / (stones.length + stones.gap))
        assert foot.x == pytest.approx(stones.centre(k))  # mid-stone
        assert abs(abs(foot.y) - 0.5 * stones.row_spacing) < 1e-9


def test_unseen_step_the_plan_walks_flat_into_a_3_cm_step():
    scenario, result = _roll("unseen-step")
    terrain = scenario.terrain.terrain
    assert np.ptp(result.column("cog_z")) == 0.0  # the plan knows nothing of the step
    # Every foothold past x = 0.7 m is planned 3 cm below the terrain: landing there needs the step detected.
    misses = [terrain.height(f.x, f.y) - f.z for f in result.footprints]
    assert [round(m, 9) for m in misses] == [0.0] * 5 + [0.03] * (len(misses) - 5)
    # The planned swing onto the step cuts 3 cm into it; the full ZMP equation sees the surface 3 cm higher.
    prints = result.footprints
    _, gap = swing_gaps(terrain, prints[3], prints[5], scenario.step_height, scenario.sole)
    assert gap.min() == pytest.approx(-0.03, abs=1e-3)
    error = zmp_error(result, terrain, scenario.gravity)
    assert 0.002 < np.max(error) < 0.006


def test_rtgait_plan_draws_the_heights(tmp_path):
    out = tmp_path / "stairs"
    assert main(["plan", "stairs-up", "--out", str(out), "--quiet", "--no-figures", "--dt", "0.02"]) == 0
    with open(out / "trajectory.csv", encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    assert float(rows[-1]["cog_z"]) == pytest.approx(0.84 + 0.9, abs=1e-6)
    assert max(float(r["lfoot_z"]) for r in rows) == pytest.approx(0.95, abs=1e-6)  # the swing over the top nose
    from rtgait.viz.figures import draw_zmp_cog
    from rtgait.viz.run_data import PlanRun, read_plan_run

    run, info, _ = read_plan_run(out)  # as rtgait plan and rtgait plot draw it
    assert run.heights is not None and len(draw_zmp_cog(run, info).axes) == 4  # x, y, the heights, the side view
    _, result = _roll("stepping-stones")  # level stones: no heights panel
    flat = PlanRun.from_rollout(result)
    assert flat.heights is None and len(draw_zmp_cog(flat, replace(info, terrain=None)).axes) == 2


def test_summary_reports_the_terrain_and_exported_footholds_keep_their_heights(tmp_path):
    out, plan = tmp_path / "slope", tmp_path / "slope-plan.toml"
    argv = ["plan", "slope-up", "--out", str(out), "--no-figures", "--quiet", "--export-footsteps", str(plan)]
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    terrain = summary["terrain"]
    assert terrain["type"] == "slope" and terrain["place_footsteps"] is True
    assert terrain["cog_height_range"] == pytest.approx([0.84, 0.84 + 2.0 * math.tan(TEN_DEGREES)], abs=1e-6)
    assert 0.0 < terrain["zmp_error_max"] < 0.001
    on_ramp = summary["footprints"][5]
    assert on_ramp["pitch"] == pytest.approx(-TEN_DEGREES) and on_ramp["z"] > 0.0
    assert "z" not in summary["footprints"][0]  # level footprints are written as before
    again = load_scenario(str(plan))
    assert [f.z for f in again.nominal_footprints()] == pytest.approx([f.get("z", 0.0) for f in summary["footprints"]])


def test_physics_refuses_stairs_beyond_the_robot_s_legs_before_simulating(tmp_path, capsys):
    # The scene builds every terrain; going down G1's 10 cm stairs, the rear foot flat on the upper tread runs out of
    # ankle dorsiflexion in the double support of step 2, and the swing leg, folded as it passes the stance foot, out
    # of ankle roll from step 3 on (docs/results.md).
    assert main(["simulate", "stairs-down-g1", "--robot", "g1", "--out", str(tmp_path / "sim")]) == 2
    error = capsys.readouterr().err
    assert "step 2" in error and "out of reach for g1" in error
    assert not (tmp_path / "sim").exists()
