"""Batched evaluation and sweeps off the flat floor: the footholds' heights (and the stances' support heights, lowered
before a step down) carried through the vertical column, the batch equal to the per-walk planner (its rollout, what
``rtgait plan`` reports: the COG height's range and the ZMP error the vertical motion adds) on stairs up and down,
slopes and an unseen step, and a sweep file naming a terrain scenario, a height field's among them."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import sweep

from rtgait.core.analysis.batch import StraightWalk, evaluate_parameters, evaluate_walks, walk_family
from rtgait.core.analysis.family_key import family_key
from rtgait.core.analysis.rollout import ScheduledChange, rollout
from rtgait.core.geometry.footsteps import place_footsteps, standing_feet
from rtgait.core.geometry.support_height import support_heights
from rtgait.core.planner.online import OnlinePlanner
from rtgait.scenario.loading import load_scenario
from rtgait.sweep.pendulum import evaluate_group, groups, rolled_out
from rtgait.sweep.spec import case_scenario, load_spec, parse_spec, scenario_from_document
from rtgait.sweep.store import PENDULUM_COLUMNS, TERRAIN_COLUMNS, read_results

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "heightfield"


def _prints(scenario):
    return place_footsteps(standing_feet(scenario.step_width, scenario.first_foot), scenario.strides())


def _heights(scenario) -> np.ndarray:
    return np.array([foot.z for foot in _prints(scenario)])


def _walk(scenario, changes=()) -> StraightWalk:
    support = tuple(support_heights(_prints(scenario)))  # the stances' support heights, as the walk takes them
    return StraightWalk(scenario.planner_config(), scenario.sole, scenario.dt, scenario.steps, scenario.step_length,
                        tuple(changes), tuple(_heights(scenario)), support)  # fmt: skip


@pytest.mark.parametrize(("base", "drop"), [("stairs-up", -0.9), ("stairs-down", 0.9), ("stairs-down-185", 6 * 0.185)])
@pytest.mark.parametrize("connection", ["quasi-real-time", "real-time"])
def test_the_batched_cog_height_on_stairs_is_the_planner_s_at_every_tick(base, drop, connection):
    scenario = case_scenario(load_scenario(base), {"connection": connection})
    change = ScheduledChange(step=3, length=0.22)  # handed over on the stairs: the rise of each stride stays
    run = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole, [change])
    walk = _walk(scenario, [change])
    family = walk_family(family_key(walk.config, walk.sole, walk.dt, walk.steps, walk.shapes()))
    cog_z = family.cog_heights(_heights(scenario), walk.support)[0]
    np.testing.assert_allclose(family.times, run.times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cog_z, run.column("cog_z"), rtol=0, atol=1e-9)
    assert cog_z[0] - cog_z[-1] == pytest.approx(drop, abs=1e-6)  # six risers climbed or come down, at rest
    lowered = np.subtract(walk.support, walk.heights) < -1e-9
    assert lowered.any() == (drop > 0)  # down the stairs the stances before a step down hold a lower support height
    if drop > 0:  # and without them the batch would not be the planner: the test sees them
        assert np.abs(family.cog_heights(_heights(scenario))[0] - run.column("cog_z")).max() > 1e-3
    # The whole batch: the horizontal numbers as before, the COG height's range as `rtgait plan` reports it.
    result = evaluate_parameters(walk, walk.parameters())
    assert result.zmp_margin_min[0] == pytest.approx(run.zmp_margin_min, abs=1e-9)
    assert result.cog_z_min[0] == pytest.approx(run.column("cog_z").min(), abs=1e-9)
    assert result.cog_z_max[0] == pytest.approx(run.column("cog_z").max(), abs=1e-9)


def test_walks_with_and_without_heights_in_one_batch():
    stairs = load_scenario("stairs-up")
    flat = StraightWalk(stairs.planner_config(), stairs.sole, stairs.dt, stairs.steps, stairs.step_length)
    result = evaluate_walks([flat, _walk(stairs), flat])
    assert np.isnan(result.cog_z_min[[0, 2]]).all()
    assert result.cog_z_max[1] == pytest.approx(0.84 + 6 * 0.15, abs=1e-9)  # at rest on the top landing
    assert result.zmp_margin_min[0] == result.zmp_margin_min[1]  # the vertical motion leaves the horizontal alone
    assert evaluate_walks([flat]).cog_z_min is None  # on the flat floor: nothing new


@pytest.mark.parametrize(
    ("base", "axes"),
    [
        ("stairs-up", {"timing.double_support": [0.3, 0.45], "connection": ["quasi-real-time", "real-time", "auto"]}),
        ("slope-down", {"walk.step_length": [0.2, 0.22], "connection": ["quasi-real-time"]}),
        # A plan that does not know the terrain: flat heights, the ZMP error from the step it does not know.
        ("unseen-step", {"timing.double_support": [0.2, 0.3], "connection": ["quasi-real-time"]}),
        # Down: the stance before each step down holds its support height half a riser lower.
        ("stairs-down", {"timing.double_support": [0.3], "connection": ["quasi-real-time", "real-time"]}),
        ("stairs-down-185", {"timing.double_support": [0.3, 0.45], "connection": ["quasi-real-time", "auto"]}),
    ],
)
def test_a_terrain_sweep_gives_the_per_walk_planner_s_results(base, axes):
    spec = parse_spec({"base": base, "axes": axes})
    cases = [(str(i), values) for i, values in enumerate(spec.cases())]
    for group in groups(spec, cases):
        batched = evaluate_group(spec, group)
        for key, values in group:
            want = rolled_out(case_scenario(spec.base, values), values["connection"])
            got = batched[key]
            assert set(got) == set(want) == {*PENDULUM_COLUMNS, *TERRAIN_COLUMNS}
            for field in ("zmp_margin_min", "zmp_deviation_max_x", "zmp_deviation_max_y", *TERRAIN_COLUMNS):
                assert got[field] == pytest.approx(want[field], abs=1e-9), (values, field)
            assert got["zmp_error_max"] > 1e-4  # a tenth of a millimetre at least: not a test passing on zeros
            assert got["zmp_margin_min_time"] == want["zmp_margin_min_time"]


def test_a_sweep_file_names_a_height_field_scenario_and_writes_its_columns(tmp_path, monkeypatch):
    folder = tmp_path / "walks"
    folder.mkdir()
    for name in ("heightfield-bumps.toml", "bumps.npy"):
        shutil.copy(EXAMPLES / name, folder / name)
    spec_path = tmp_path / "sweep.toml"
    spec_path.write_text('base = "walks/heightfield-bumps.toml"\n[axes]\n"walk.step_length" = [0.18, 0.2]\n')
    spec = load_spec(spec_path)
    assert Path(spec.base_document["terrain"]["file"]) == folder / "bumps.npy"  # workers read it from anywhere
    monkeypatch.chdir("/")
    assert scenario_from_document(spec.base_document) == spec.base  # as a physics worker rebuilds it
    assert sweep([str(spec_path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    rows = read_results(tmp_path / "out")
    assert len(rows) == 2 and all(0.84 < row["cog_z_max"] < 0.84 + 0.05 for row in rows)
    # Different step lengths put the feet on other heights of the bumps: different COG heights.
    assert rows[0]["cog_z_max"] != rows[1]["cog_z_max"]
    # Another grid in the same file is another base: its cases are not the ones done (a resumed sweep redoes them).
    np.save(folder / "bumps.npy", 0.5 * np.load(folder / "bumps.npy"))
    assert load_spec(spec_path).fingerprint() != spec.fingerprint()


def test_a_flat_sweep_has_no_terrain_columns(spec_file, tmp_path):
    assert sweep([str(spec_file('base = "tiny.toml"\n[axes]\n"change.length" = [0.05, 0.08]\n')),
                  "--out", str(tmp_path / "flat"), "--quiet"]) == 0  # fmt: skip
    assert not set(TERRAIN_COLUMNS) & set(read_results(tmp_path / "flat")[0])
