"""Walking in physics: a feasible plan is walked, a plan whose ZMP leaves the support polygon is not, pushes act,
and the outputs are written."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.core.analysis.rollout import ScheduledChange, rollout
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push
from rtgait.io.sim_run import SIM_CSV_COLUMNS, sim_csv_columns, simulate, write_sim_outputs
from rtgait.robot.motion import robot_scenario
from rtgait.sim.loop import LoopOptions
from rtgait.sim.run_loop import run_sim_loop


def planned(scenario, robot):
    """The plan alone, sampled at 1 kHz, for the robot."""
    walk = robot_scenario(scenario, robot)
    return rollout(OnlinePlanner(walk.planner_config(), walk.strides()), 0.001, walk.sole, walk.changes)


def test_a_feasible_walk_is_walked(talos, short_walk):
    scenario, result = short_walk
    plan = planned(scenario, talos)
    assert not plan.zmp_outside
    assert not result.fell and not result.tipped
    assert result.steps_planned == scenario.steps + 1
    assert result.steps_completed == result.steps_planned
    # The robot ends where the plan ends: COG over the last footprints (0.05 m x 3 + 0.15 m ahead).
    end = (plan.column("cog_x")[-1], plan.column("cog_y")[-1])
    np.testing.assert_allclose(result.cog[-1, :2], end, atol=0.02)
    assert end[0] == pytest.approx(0.30, abs=1e-9)
    assert result.distance_walked == pytest.approx(0.30, abs=0.03)
    # The measured ZMP follows the plan: centimetres, the sole being 0.21 x 0.13 m.
    assert result.zmp_tracking_error_rms < 0.05
    # Each foot is on the floor when the plan says it supports the robot.
    left_support = result.support == 1
    right_support = result.support == 2
    assert result.contact[left_support, 0].mean() > 0.98 and result.contact[right_support, 1].mean() > 0.98
    # The swing foot is off the floor for most of its swing; it stays in touch for a few hundredths of a second
    # after lift-off and lands a little early, as the loaded stance leg gives a few millimetres.
    assert result.contact[left_support, 1].mean() < 0.25 and result.contact[right_support, 0].mean() < 0.25


def test_a_plan_leaving_the_support_polygon_tips_or_falls(talos, talos_sim, shorten):
    # fig4's change (0.05 -> 0.15 m decided at lift-off, real-time, 0.2 s of double support) made at step 2 of 3.
    scenario = shorten("fig4", 3, (ScheduledChange(2, length=0.15, through=3),))
    plan = planned(scenario, talos)
    assert plan.zmp_outside, "precondition: the planned ZMP leaves the support polygon"
    result = simulate(scenario, talos, sim=talos_sim, controller="open-loop")  # the paper's outcome: the plan alone
    exits = plan.times[plan.margin < 0.0][0]
    assert result.fell or result.tipped
    event = result.tip_time if result.tipped else result.fall_time
    # Caused by the plan: the robot loses flat contact once the planned ZMP has left the polygon, not before.
    assert exits - 0.05 <= event <= exits + 1.0


@pytest.mark.parametrize("direction", [(0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)])
def test_pushes_move_the_base_in_their_direction(talos, talos_sim, shorten, direction):
    scenario = shorten("fig8", 1)
    # Pushed while standing, during the start's hold (negative times on the walk's clock): the servos alone answer.
    options = LoopOptions(start_ramp=0.5, start_hold=1.5)
    push = Push(start=-1.0, duration=0.1, force=tuple(120.0 * d for d in direction))
    quiet = simulate(scenario, talos, sim=talos_sim, options=options)
    pushed = simulate(scenario, talos, sim=talos_sim, options=options, push=push)

    def velocity(result, t):
        k = int(np.argmin(np.abs(result.times - t)))
        return (result.base_position[k + 5] - result.base_position[k - 5]) / 0.01

    change = velocity(pushed, -0.9) - velocity(quiet, -0.9)
    along = float(change @ np.array(direction))
    # 12 N s on 90 kg would be 0.13 m/s for a free body; standing on both soles, the stiff robot rocks on them
    # rather than sliding, and its base picks up about 0.05 m/s, in the push's direction.
    assert along > 0.03
    assert np.linalg.norm(change - along * np.array(direction)) < 0.2 * along
    assert np.allclose(pushed.base_position[:1000], quiet.base_position[:1000]), "nothing differs before the push"


def test_a_robot_pushed_over_falls_at_the_first_tick_its_base_tilts_past_the_limit(talos, talos_sim, shorten):
    """100 N s sideways while standing tips Talos over its soles' edge: the run ends at the first tick whose base,
    as MuJoCo has it, is tilted past the fall limits' documented 45 degrees from upright, and says so; the base stays
    well above the "too low" limit until then, so the tilt is what ended it."""
    import mujoco

    from rtgait.sim.contact import FallLimits

    limits = FallLimits()
    limit = limits.tilt
    assert limit == pytest.approx(math.radians(45.0))
    options = LoopOptions(start_ramp=0.5, start_hold=1.5)
    push = Push(start=-1.0, duration=0.1, force=(0.0, 1000.0, 0.0))
    result = simulate(shorten("fig8", 1), talos, sim=talos_sim, options=options, push=push)
    # The tilt of each tick's base (the state at the tick, before its physics): the angle of the base's z axis from
    # the vertical, from its rotation matrix.
    rotation = np.empty(9)
    tilt = []
    for qx, qy, qz, qw in result.base_quaternion:
        mujoco.mju_quat2Mat(rotation, np.array([qw, qx, qy, qz]))
        tilt.append(math.acos(min(rotation[8], 1.0)))
    beyond = np.flatnonzero(np.array(tilt) > limit)
    assert beyond.size, f"the push did not tip the robot over (largest tilt {max(tilt):.2f} rad)"
    assert result.fell and result.fall_cause == "base tilted"
    assert result.fall_time == result.times[beyond[0]] == result.times[-1]  # the first tick past it ends the run
    assert result.fall_time > push.start + push.duration
    start_height = result.base_position[0, 2]
    assert result.base_position[:, 2].min() > (limits.base_height_fraction + 0.1) * start_height
    assert result.summary()["fall_cause"] == "base tilted"


def test_walking_by_velocity_command(talos, talos_sim, shorten):
    scenario = shorten("fig8", 2)
    fractions: list[float] = []
    result = simulate(scenario, talos, sim=talos_sim, velocity=(0.1, 0.0, 0.0), progress=fractions.append)
    assert result.steps_planned == 3 and result.steps_completed == 3 and not result.fell
    # Two strides of vx * (T_s + T_dbl) = 0.08 m, then the closing step.
    assert result.cog[-1, 0] == pytest.approx(0.16, abs=0.02)
    assert fractions[-1] == 1.0 and fractions == sorted(fractions)


def test_outputs(short_walk, tmp_path):
    _, result = short_walk
    summary = write_sim_outputs(result, tmp_path / "out", title="short")
    folder = tmp_path / "out"
    with open(folder / "sim.csv", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    # The fixed columns, then one torque column per actuated joint.
    assert tuple(rows[0]) == sim_csv_columns(result)
    assert tuple(rows[0][: len(SIM_CSV_COLUMNS)]) == SIM_CSV_COLUMNS
    assert rows[0][len(SIM_CSV_COLUMNS) :] == [f"tau_{name}" for name in result.joint_names]
    assert len(rows) - 1 == len(result.times) == summary["rows"]
    table = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(table[:, 0], result.times, atol=1e-12)
    column = {name: i for i, name in enumerate(rows[0])}
    quaternion = [column[f"base_q{axis}"] for axis in "xyzw"]
    np.testing.assert_allclose(table[:, quaternion], result.base_quaternion, atol=1e-9)
    contacts = table[:, len(SIM_CSV_COLUMNS) - 2 : len(SIM_CSV_COLUMNS)]
    assert set(np.unique(contacts)) <= {0.0, 1.0}
    np.testing.assert_allclose(table[:, len(SIM_CSV_COLUMNS) :], result.torque, rtol=1e-5, atol=1e-4)
    saved = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    assert saved == summary
    for key in (
        "fell",
        "fall_time",
        "steps_completed",
        "distance_walked",
        "zmp_tracking_error_rms",
        "real_time_factor",
        "legs_touched",
        "control_dt",
        "physics_dt",
        "fall_cause",
        "steps_planned",
        "missed_landings",
        "step_adjustments",
        "foot_slip_max",
        "pushes",
        "controller",
        "zmp_error",
    ):
        assert key in summary
    for measure in ("vs_plan", "vs_command", "vs_commanded_motion"):
        assert 0.0 < summary["zmp_error"][measure]["rms"] < 0.05, measure  # centimetres at most, on a 0.13 m sole
    assert summary["fell"] is False and summary["fall_time"] is None and summary["legs_touched"] is False
    assert summary["control_dt"] == 0.001 and summary["physics_dt"] == 0.001
    assert math.isfinite(summary["zmp_tracking_error_rms"])
    assert (folder / "zmp_sim.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in folder.iterdir()) == ["sim.csv", "sim.parquet", "summary.json", "zmp_sim.png"]


def test_bad_input(talos, talos_sim, shorten):
    with pytest.raises(ValueError, match="duration"):
        Push(start=1.0, duration=0.0, force=(1.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="no such body"):
        simulate(shorten("fig8", 1), talos, sim=talos_sim, push=Push(0.1, 0.1, (1.0, 0.0, 0.0), body="nope"))
    planner = OnlinePlanner(robot_scenario(shorten("fig8", 1), talos).planner_config(), None)
    with pytest.raises(ValueError, match="stop_after_steps"):
        run_sim_loop(talos_sim, planner)
