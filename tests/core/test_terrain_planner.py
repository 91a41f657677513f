"""The analytical planner over height changes (the 3D-DCM/VRP form, docs/method.md): the COG height obeys the
pendulum equation about the footholds' heights, stays continuous across every replanning in both connection
modes, ends at rest; the full ZMP equation on the planned COG measures what the vertical motion adds."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rtgait.core.analysis.height_error import smooth_height_profile, zmp_error
from rtgait.core.analysis.rollout import ScheduledChange, rollout
from rtgait.core.geometry.footsteps import Stride
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig
from rtgait.scenario.loading import load_scenario


def _walk(name: str, **changes):
    scenario = load_scenario(name)
    if changes:
        scenario = replace(scenario, **changes)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    return scenario, planner, rollout(planner, scenario.dt, scenario.sole, scenario.changes)


def test_cog_height_obeys_the_pendulum_about_the_stance_height():
    scenario, planner, result = _walk("stairs-up")
    w2 = planner.w**2
    cz, az = result.column("cog_z"), result.column("cog_az")
    single = result.support != "double"
    stance_z = np.array([result.contacts[int(q)][0].z for q in result.phase[single]])
    # c_z - c_z'' / w^2 = h + zc, h the stance foot's height in single support (an independent truth: the footholds).
    np.testing.assert_allclose((cz - az / w2)[single], stance_z + scenario.cog_height, atol=1e-9)
    # It ends at rest zc above the top of the stairs.
    assert cz[-1] == pytest.approx(scenario.cog_height + 0.9, abs=1e-6)
    assert abs(result.column("cog_vz")[-1]) < 1e-6


def test_cog_height_by_differences_matches_the_planned_rates():
    _, _, result = _walk("slope-down")
    t, cz = result.times, result.column("cog_z")
    vz = np.gradient(cz, t)
    assert np.max(np.abs(vz - result.column("cog_vz"))[1:-1]) < 2e-3  # m/s: the closed form's rates are its own


@pytest.mark.parametrize("connection", ["real-time", "quasi-real-time"])
def test_height_continuous_across_replanning_with_a_change(connection):
    scenario = load_scenario("stairs-up")
    scenario = replace(scenario, connection=connection)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    # A change of step 4's length, decided at its connection mode's deadline: its rise is kept.
    result = rollout(planner, scenario.dt, scenario.sole, (ScheduledChange(4, length=0.22),))
    assert len(result.plans) >= 9 and result.changes
    assert [f.z for f in result.footprints][5] == pytest.approx(0.45)
    dt = scenario.dt
    cz, vz, az = result.column("cog_z"), result.column("cog_vz"), result.column("cog_az")
    for plan in result.plans[1:]:
        k = round(plan.t / dt)  # replans fall on ticks: phases are whole multiples of dt here
        assert result.times[k] == pytest.approx(plan.t)
        # The sample at the replan comes from the new plan; the tick before from the old: a Taylor step joins them.
        assert cz[k] == pytest.approx(cz[k - 1] + vz[k - 1] * dt + 0.5 * az[k - 1] * dt**2, abs=2e-6)
        assert vz[k] == pytest.approx(vz[k - 1] + az[k - 1] * dt, abs=2e-3)


def test_level_walk_has_no_vertical_column():
    config = PlannerConfig()
    planner = OnlinePlanner(config, [Stride(0.1, 0.19)] * 3 + [Stride(0.0, 0.19)])
    planner.start(0.0)
    for t in np.arange(0.0, 6.0, 0.05):
        values = planner.sample_values(float(t))[0]
        assert (values.cog_z, values.cog_vz, values.cog_az) == (0.8, 0.0, 0.0)


def test_full_zmp_error_is_small_for_the_vrp_and_large_for_a_double_support_height_profile():
    scenario, _, result = _walk("stairs-up")
    terrain = scenario.terrain.terrain
    vrp = zmp_error(result, terrain, scenario.gravity)
    single = result.support != "double"
    assert np.max(vrp[single]) < 1e-9  # single support: the surface is at the VRP's support height, exactly
    assert np.max(vrp) < 0.005  # double support between treads: millimetres
    smooth = zmp_error(result, terrain, scenario.gravity, smooth_height_profile(result, scenario.cog_height))
    assert np.max(smooth) > 10 * np.max(vrp)


def test_stepping_stones_error_is_zero_on_level_stones():
    scenario, _, result = _walk("stepping-stones")
    assert np.max(zmp_error(result, scenario.terrain.terrain, scenario.gravity)) < 1e-9
    assert math.isclose(result.column("cog_z").max(), scenario.cog_height)


def test_a_touchdown_keeps_the_planned_height_of_the_foothold():
    scenario = load_scenario("stairs-up")
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    planner.start(0.0)
    timeline = planner.timeline
    t = timeline.start_time(3) + 0.5  # step 2's single support: F[3] on the first tread is being swung to
    planner.sample(t)
    planned = planner.footprints()[3]
    assert planned.z == pytest.approx(0.15)
    planner.touchdown(t + 0.1, planned.side, planned.x + 0.01, planned.y, planned.yaw)
    assert planner.footprints()[3].z == pytest.approx(0.15)
    assert planner.footprints()[3].x == pytest.approx(planned.x + 0.01)


def _short_touchdown(name: str, index: int, short: float):
    """The footprints of ``name`` before and after ``F[index]`` lands ``short`` (m) behind its foothold."""
    scenario = load_scenario(name)
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    planner.start(0.0)
    t = planner.timeline.start_time(2 * index - 3) + 0.5  # the single support that swings F[index]
    planner.sample(t)
    before = planner.footprints()
    planned = before[index]
    planner.touchdown(t + 0.1, planned.side, planned.x - short, planned.y, planned.yaw)
    return before, planner.footprints()


def test_a_touchdown_short_on_a_slope_leaves_the_later_footholds_where_they_were_placed():
    # F[13] is the last foothold on the ramp of slope-down-g1 (pitched), F[14] the first level one after it, 6 cm past
    # the ramp's end under G1's heel: a landing 3 cm short must not carry it back over the ramp.
    before, after = _short_touchdown("slope-down-g1", 13, 0.03)
    assert before[13].pitch > 0.1 and before[14].pitch == 0.0
    assert after[13].x == pytest.approx(before[13].x - 0.03)
    # The planned surface stays, at its height 3 cm up the ramp (down it, a landing short is higher).
    assert after[13].pitch == before[13].pitch
    assert after[13].z == pytest.approx(before[13].z + 0.03 * math.tan(before[13].pitch), abs=1e-12)
    for later, placed in zip(after[14:], before[14:], strict=True):
        assert (later.x, later.y, later.z, later.yaw, later.pitch) == pytest.approx(
            (placed.x, placed.y, placed.z, placed.yaw, placed.pitch), abs=1e-12
        )


@pytest.mark.parametrize("name", ["stairs-up", "fig8"])
def test_a_touchdown_short_on_level_ground_carries_the_later_footholds_with_it(name):
    # A foothold on a level tread (or the floor) keeps its height where it moves: the footprints after it follow it.
    before, after = _short_touchdown(name, 3, 0.01)
    assert before[3].pitch == 0.0
    for later, placed in zip(after[4:], before[4:], strict=True):
        assert (later.x - placed.x, later.y - placed.y, later.z - placed.z) == pytest.approx((-0.01, 0.0, 0.0))


@pytest.mark.parametrize("phase_share", [0.3, 0.7])
def test_a_replan_mid_phase_continues_the_height(phase_share):
    scenario = load_scenario("stairs-up")
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    planner.start(0.0)
    timeline = planner.timeline
    for q in (3, 4, 5):  # a single support climbing, the double support between treads, the next single support
        t = timeline.start_time(q) + phase_share * timeline.duration(q)
        before = planner.sample(t).values
        assert planner.replan_now(t) is not None
        after = planner.sample(t).values
        # From the plan itself: the new plan starts where the old one was, height and vertical velocity included.
        assert after[2] == pytest.approx(before[2], abs=1e-9)
        assert after[5] == pytest.approx(before[5], abs=1e-9)
    end = planner.end_time
    assert planner.sample(end).values[2] == pytest.approx(scenario.cog_height + 0.9, abs=1e-6)
