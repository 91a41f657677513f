"""The MuJoCo controller levels on synthetic measurements: no error, no correction; the signs; landings."""

from __future__ import annotations

import dataclasses
import itertools
import math

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("pinocchio")

from rtgait.control.controller import (
    ControllerOptions,
    RobotInfo,
    make_controller,
    step_limits,
)
from rtgait.control.foot_control import split_zmp
from rtgait.core.geometry.footsteps import SoleRect, Stride
from rtgait.core.laws.stepping import SteppingLimits
from rtgait.core.planner.levels import CONTROLLER_LEVELS, level_config
from rtgait.core.planner.online import OnlinePlanner, straight_walk
from rtgait.estimation.state import Landing, Measurement
from rtgait.robot.controller_info import robot_info
from tests.synthetic_robot import CONFIG, DT, INFO, SOLE, WEIGHT, foot_state

EXACT = ControllerOptions(measurement_filter=0.0, dcm_bias=False)
"""No filter on the measurement, and no DCM bias estimation: the synthetic measurements here hold the DCM off the plan
without a ZMP to match (the bias filter would take that for a bias; its own tests are tests/estimation)."""


def on_plan(t, values, support, dcm_error=(0.0, 0.0), landings=(), loaded=None) -> Measurement:
    """The measurement of a robot exactly on the plan: COM state, DCM, ZMP, and each foot's load and CoP as the ZMP
    split asks; ``loaded`` overrides which feet are loaded (left, right)."""
    left, right = values.left_foot, values.right_foot
    zmp = (values.zmp_x, values.zmp_y)
    split = split_zmp(zmp, left, right, SOLE, support)
    fl = split.left_ratio * WEIGHT
    loaded = loaded or (support != "right", support != "left")
    dcm = (values.dcm_x + dcm_error[0], values.dcm_y + dcm_error[1])
    com = (values.cog_x + dcm_error[0], values.cog_y + dcm_error[1], values.cog_z)
    return Measurement(
        t, com, (values.cog_vx, values.cog_vy, values.cog_vz), dcm, zmp, WEIGHT,
        foot_state(left, fl, split.left_cop, loaded[0]), foot_state(right, WEIGHT - fl, split.right_cop, loaded[1]),
        tuple(landings), 0,
    )  # fmt: skip


def controller(level, steps=3, options=EXACT):
    ctl = make_controller(level, CONFIG, straight_walk(CONFIG, steps, 0.1), SOLE, INFO, dt=DT, options=options)
    ctl.start(0.0)
    return ctl


def reference(steps=3):
    planner = OnlinePlanner(level_config(CONFIG, "open-loop", SOLE), straight_walk(CONFIG, steps, 0.1))
    planner.start(0.0)
    return planner


@pytest.mark.parametrize("level", CONTROLLER_LEVELS)
def test_on_the_plan_every_level_gives_the_plan(level):
    ctl, plan = controller(level, steps=2), reference(steps=2)
    worst = 0.0
    for k in range(round(plan.end_time / DT)):
        t = k * DT
        values, support, _ = plan.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support))
        errors = [
            *(a - b for a, b in zip(out.com, values.cog, strict=True)),
            *(a - b for a, b in zip(out.left_foot, values.left_foot, strict=True)),
            *(a - b for a, b in zip(out.right_foot, values.right_foot, strict=True)),
            out.zmp_command[0] - values.zmp_x, out.zmp_command[1] - values.zmp_y, *out.offsets, *out.com_offset,
        ]  # fmt: skip
        worst = max(worst, max(abs(e) for e in errors))
        assert out.support == support and not [e for e in out.events if e.kind != "replan"]
    # Open loop and stabilized: the same plan, no correction; adaptive: its plans from the measured (= planned) state
    # reproduce the plan to the connection's round-off.
    assert worst < (1e-6 if level == "adaptive" else 1e-12)


@pytest.mark.parametrize("level", ["stabilized", "adaptive"])
def test_on_the_plan_the_dcm_bias_filter_finds_no_bias(level):
    """The plan's DCM and ZMP obey the pendulum, so the bias filter finds none: the targets stay on the plan, to its
    discrete pendulum's difference from the plan's (a ZMP linear over each tick)."""
    options = dataclasses.replace(EXACT, dcm_bias=True)
    ctl, plan = controller(level, steps=2, options=options), reference(steps=2)
    worst = 0.0
    for k in range(round(plan.end_time / DT)):
        t = k * DT
        values, support, _ = plan.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support))
        worst = max(worst, *(abs(a - b) for a, b in zip(out.com, values.cog, strict=True)),
                    abs(out.zmp_command[0] - values.zmp_x), abs(out.zmp_command[1] - values.zmp_y))  # fmt: skip
    assert ctl.dcm_bias is not None and max(map(abs, ctl.dcm_bias.bias)) < 1e-6
    assert worst < 1e-5


def test_the_targets_are_the_plans_quantities_by_name():
    """The open-loop targets against the plan's closed form (COM, ZMP, DCM = c + c'/w) and the footprints (feet in
    double support), not against the sample: a sample field the controller reads under another name fails here."""
    ctl = controller("open-loop", steps=2)
    planner, w = ctl.planner, ctl.planner.w
    reference_apart = 0.0
    for k in range(0, round(planner.end_time / DT), 7):
        t = k * DT
        values, support, _ = planner.sample_values(t)  # the measurement's (open loop: not acted on)
        out = ctl.tick(t, on_plan(t, values, support))
        plan = planner.current_plan
        cog, vel, _ = (a[0] for a in plan.evaluate(t))
        assert out.com == pytest.approx((*cog, CONFIG.cog_height), abs=1e-9)
        assert out.zmp_planned == pytest.approx(plan.zmp.evaluate(t)[0], abs=1e-9) == out.zmp_command
        assert out.dcm_planned == pytest.approx(cog + vel / w, abs=1e-9)
        if support == "double":
            feet = {f.side: (f.x, f.y, 0.0, f.yaw) for f in planner.contact_feet(out.phase)}
            assert (out.left_foot, out.right_foot) == (pytest.approx(feet["left"]), pytest.approx(feet["right"]))
        reference_apart = max(reference_apart, math.dist(out.zmp_planned, (values.zmp_ref_x, values.zmp_ref_y)))
    assert reference_apart > 1e-5, "the walk tells the planned ZMP from the reference ZMP"


def test_the_measurement_filter_lags_by_little():
    ctl, plan = controller("stabilized", steps=2, options=ControllerOptions()), reference(steps=2)
    worst = 0.0
    for k in range(round(plan.end_time / DT)):
        values, support, _ = plan.sample_values(k * DT)
        out = ctl.tick(k * DT, on_plan(k * DT, values, support))
        worst = max(worst, abs(out.com[0] - values.cog_x), abs(out.com[1] - values.cog_y), *map(abs, out.offsets))
    assert 0.0 < worst < 1e-3


@pytest.mark.parametrize("axis", [0, 1])
def test_a_dcm_error_shifts_the_zmp_ahead_and_pulls_the_com_target_back(axis):
    ctl, plan = controller("stabilized"), reference()
    error = [0.0, 0.0]
    error[axis] = 0.02 if axis == 0 else -0.02  # ahead in x, to the right in y
    for k in range(100):  # the start's double support: the ZMP between the feet, far from the polygon's edges
        values, support, _ = plan.sample_values(k * DT)
        out = ctl.tick(k * DT, on_plan(k * DT, values, support, dcm_error=error))
    sign = math.copysign(1.0, error[axis])
    # The law: p_cmd = p_ref + (1 + k_p / w) e, so the ZMP goes out along the error; the COM admittance moves the COM
    # target against it (a COM accelerated backward moves the ZMP forward, p = c - c''/w^2).
    gains = ctl.options.dcm
    expected = (1.0 + gains.k_p / ctl.planner.w) * error[axis]
    planned_zmp = (values.zmp_x, values.zmp_y)
    assert sign * (out.zmp_command[axis] - planned_zmp[axis]) >= abs(expected)
    assert sign * out.com_offset[axis] < -1e-4
    assert out.com[axis] - values.cog[axis] == pytest.approx(out.com_offset[axis])
    assert out.com_offset[1 - axis] == pytest.approx(0.0, abs=1e-9)


def test_open_loop_ignores_errors():
    ctl, plan = controller("open-loop"), reference()
    values, support, _ = plan.sample_values(0.05)
    out = ctl.tick(0.05, on_plan(0.05, values, support, dcm_error=(0.05, 0.05)))
    assert out.com == values.cog and out.zmp_command == (values.zmp_x, values.zmp_y)


def test_adaptive_observes_every_tick(monkeypatch):
    ctl = controller("adaptive")
    planner = ctl.planner
    seen = []
    observe = planner.observe
    monkeypatch.setattr(planner, "observe", lambda t, c, v: (seen.append(t), observe(t, c, v)))
    plan = reference()
    for k in range(50):
        values, support, _ = plan.sample_values(k * DT)
        ctl.tick(k * DT, on_plan(k * DT, values, support))
    assert seen == [k * DT for k in range(50)]


def test_adaptive_replans_on_a_large_dcm_error():
    ctl, plan = controller("adaptive"), reference()
    events = []
    for k in range(100):
        values, support, _ = plan.sample_values(k * DT)
        events += ctl.tick(k * DT, on_plan(k * DT, values, support, dcm_error=(0.04, 0.0) if k > 50 else (0, 0))).events
    assert [(e.kind, e.detail) for e in events][:1] == [("replan", "dcm-error")]


@pytest.mark.parametrize("reference_kind", ["dcm", "measured"])
def test_a_dcm_error_replan_takes_the_measured_dcm_and_steps_the_com_only_when_asked(reference_kind):
    """``com_reference="dcm"`` (default): the replanned plan's DCM is the measured one and its COM goes on from where
    the plan had it (no step of the COM target); ``"measured"``: its COM is the measured COM, a step by the error."""
    options = dataclasses.replace(EXACT, com_reference=reference_kind)
    ctl, plan = controller("adaptive", options=options), reference()
    error = (0.03, -0.01)  # the COM and the DCM off the plan by this (m)
    for k in range(100):
        t = k * DT
        values, support, _ = plan.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support, dcm_error=error if k == 99 else (0.0, 0.0)))
    assert ("replan", "dcm-error") in [(e.kind, e.detail) for e in out.events]
    after, _, _ = ctl.planner.sample_values(t)
    dcm = (values.dcm_x + error[0], values.dcm_y + error[1])  # the measurement's
    assert (after.dcm_x, after.dcm_y) == pytest.approx(dcm, abs=1e-6)
    shift = (0.0, 0.0) if reference_kind == "dcm" else error  # the plan's COM, or the measurement's
    com = (values.cog_x + shift[0], values.cog_y + shift[1])
    assert (after.cog_x, after.cog_y) == pytest.approx(com, abs=1e-6)


def test_the_controller_acts_on_the_measurement_s_dcm():
    """The DCM is made once, by the estimator (``Measurement.dcm``): the controller's law and its DCM-error replan act
    on that value, which the run logs, and not on one made again from the COM state. A measurement whose DCM field
    is off the plan while its COM state is on it moves the ZMP command and replans; the converse does neither."""
    error = (0.0, -0.04)

    def run(level, moved):
        ctl, plan = controller(level), reference()
        outs = []
        for k in range(100):
            values, support, _ = plan.sample_values(k * DT)
            m = on_plan(k * DT, values, support)
            if moved == "dcm":
                m = m._replace(dcm=(m.dcm[0] + error[0], m.dcm[1] + error[1]))
            else:  # the COM state moved so that c + c'/w moves by the error, the DCM field left on the plan
                m = m._replace(com=(m.com[0] + error[0], m.com[1] + error[1], m.com[2]))
            outs.append(ctl.tick(k * DT, m))
        return ctl, values, outs

    ctl, values, outs = run("stabilized", "dcm")
    expected = (1.0 + ctl.options.dcm.k_p / ctl.planner.w) * error[1]
    assert outs[-1].zmp_command[1] - values.zmp_y <= expected < -0.04
    _, values, outs = run("stabilized", "com")
    assert outs[-1].zmp_command == pytest.approx((values.zmp_x, values.zmp_y), abs=1e-12)
    _, _, outs = run("adaptive", "dcm")
    assert ("replan", "dcm-error") in [(e.kind, e.detail) for out in outs for e in out.events]
    _, _, outs = run("adaptive", "com")
    assert ("replan", "dcm-error") not in [(e.kind, e.detail) for out in outs for e in out.events]


def walk_to(ctl, t_end, t=0.0, **overrides):
    """Tick ``ctl`` on its own plan from ``t`` until ``t_end`` (s); returns the last targets and the next tick's
    time."""
    out = None
    while t < t_end - 1e-9:
        values, support, _ = ctl.planner.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support, **overrides))
        t += DT
    return out, t


def planned_height(values, swing):
    """The plan's height (m) of the swing foot ``swing`` (0 left, 1 right) in the sample ``values``."""
    return values.lfoot_z if swing == 0 else values.rfoot_z


def first_swing(ctl):
    """Phase 1, the first single support: its start, duration, and which foot swings (0 left, 1 right)."""
    planner = ctl.planner
    swing = 0 if planner.footprints()[0].side == "left" else 1  # F[0] lifts off first and lands on F[2]
    return planner.phase_start(1), planner.timeline.duration(1), swing


@pytest.mark.parametrize("blend", [0.0, 0.04])
def test_adaptive_early_touchdown_reanchors_and_switches_support(blend):
    ctl = controller("adaptive", options=ControllerOptions(measurement_filter=0.0, anchor_blend=blend))
    start, duration, swing = first_swing(ctl)
    side = ("left", "right")[swing]
    out, t = walk_to(ctl, start + 0.75 * duration)
    planner = ctl.planner
    target = planner.footprints()[2]  # where the swing foot was to land
    landing = Landing(t, side, target.x + 0.012, target.y - 0.006, 0.001, target.yaw + 0.01, 0.0, 0.0, 40.0)
    values, support, _ = planner.sample_values(t)
    swing_z = planned_height(values, swing)
    loaded = (True, True)
    out = ctl.tick(t, on_plan(t, values, support, landings=[landing], loaded=loaded))
    kinds = [(e.kind, e.detail) for e in out.events]
    assert ("landing", "early") in kinds and kinds[kinds.index(("landing", "early")) + 1][0] == "touchdown"
    moved = planner.footprints()[2]
    assert (moved.x, moved.y, moved.yaw) == pytest.approx((landing.x, landing.y, landing.yaw))
    assert out.support == "double", "support switches at once"
    # Where it landed, going on down with the plan, no more than late_descent_limit below where it touched; the IK's
    # target gets there at once, or with a blend over anchor_blend from where the plan had it (x, y, yaw).
    floor = swing_z - ctl.options.late_descent_limit
    held = out.left_foot if swing == 0 else out.right_foot
    planned = values.left_foot if swing == 0 else values.right_foot
    start_pose = (landing.x, landing.y, landing.yaw) if blend == 0.0 else (planned[0], planned[1], planned[3])
    assert held == pytest.approx((*start_pose[:2], max(swing_z, floor), start_pose[2]), abs=1e-9)
    landed_at, lowest = t, swing_z
    while t < start + duration - DT:
        t += DT
        values, support, _ = planner.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support, loaded=loaded))
        assert out.support == "double"
        z = planned_height(values, swing)
        lowest = min(lowest, z)
        foot = out.left_foot if swing == 0 else out.right_foot
        if t >= landed_at + ctl.options.anchor_blend:
            assert foot == pytest.approx((landing.x, landing.y, max(z, floor), landing.yaw), abs=1e-9)
        else:
            assert foot[2] == pytest.approx(max(z, floor), abs=1e-9)
    assert lowest < floor, "the test reaches the floor"
    # The plan's double support then rests on the landed foot, at the floor's height: continuous.
    values, support, _ = planner.sample_values(t + DT)
    out = ctl.tick(t + DT, on_plan(t + DT, values, support))
    assert support == "double"
    foot = out.left_foot if swing == 0 else out.right_foot
    assert foot == pytest.approx((landing.x, landing.y, max(0.0, floor), landing.yaw), abs=1e-9)


@pytest.mark.parametrize("acceleration", [0.0, 9.81])
@pytest.mark.parametrize(("met", "ground"), [(-0.012, -0.012), (-0.003, 0.0), (0.0, 0.0)])
def test_adaptive_late_touchdown_lowers_the_foot_then_stands_at_the_measured_ground(met, ground, acceleration):
    # Heights: ours only (no foot force control); late at once (no grace for the landing's detection); the descent
    # at full speed from its first tick (0) or from rest at gravity's peak acceleration. The sole meets the floor
    # `met` below the other one (m); within ground_tolerance (5 mm, the legs' calibration error) that is the other
    # foot's ground, beyond it a lower ground (`ground`).
    options = ControllerOptions(
        measurement_filter=0.0, foot=None, late_grace=0.0, late_descent_acceleration=acceleration
    )
    ctl = controller("adaptive", options=options)
    start, duration, swing = first_swing(ctl)
    side = ("left", "right")[swing]
    not_down = (True, False) if swing == 1 else (False, True)
    walk_to(ctl, start + duration)  # the swing ends in the air: the plan's double support begins, the foot is not down
    t = start + duration
    planner = ctl.planner
    heights = []
    ticks = round(planner.timeline.duration(2) / DT) - 2  # the plan's double support, the foot not down
    for _ in range(ticks):
        values, support, _ = planner.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support, loaded=not_down))
        assert support == "double" and out.support == ("left", "right")[1 - swing], "the other foot carries it"
        heights.append((out.left_foot if swing == 0 else out.right_foot)[2])
        t += DT
    options = ctl.options
    # Finite differences of the target: it leaves rest (the swing's end) without a step in velocity, reaches the
    # descent speed, accelerates no faster than gravity and stays above the limit.
    rates = [(b - a) / DT for a, b in itertools.pairwise([0.0, *heights])]
    if acceleration == 0.0:  # a step of the velocity: 0.3 mm per tick, the 2 cm limit reached in 67 ticks
        assert rates[0] == pytest.approx(-options.late_descent_speed, rel=1e-6)
        assert heights[-1] == pytest.approx(-options.late_descent_limit), "down to the limit, no further"
    else:
        assert abs(rates[0]) < 0.01 * options.late_descent_speed, "the descent starts at rest"
        assert max(abs(b - a) / DT for a, b in itertools.pairwise(rates)) <= acceleration * 1.001
    assert min(rates) == pytest.approx(-options.late_descent_speed, rel=1e-6), "at full speed"
    assert all(h >= -options.late_descent_limit - 1e-12 for h in heights)
    # It lands with its sole at `ground` (m): re-anchored; its target goes back up to the measured ground over the
    # single support it carries next, phase 3 (the target's own depth kept would extend the stance leg and lift the
    # body).
    target = planner.footprints()[2]
    landing = Landing(t, side, target.x - 0.01, target.y, met, target.yaw, 0.0, 0.0, 40.0)
    values, support, _ = planner.sample_values(t)
    out = ctl.tick(t, on_plan(t, values, support, landings=[landing], loaded=(True, True)))
    assert [e.detail for e in out.events if e.kind == "landing"] == ["late"]
    assert any(e.kind == "touchdown" for e in out.events)
    assert planner.footprints()[2].x == pytest.approx(landing.x)
    assert out.support == "double"
    landed = (out.left_foot if swing == 0 else out.right_foot)[2]
    assert heights[-1] - options.late_descent_speed * DT <= landed <= heights[-1], "on down by at most a tick"
    landed_at, end = t, planner.phase_start(3) + planner.timeline.duration(3)
    middle = 0.5 * (landed_at + end)
    out, t = walk_to(ctl, middle + 0.5 * DT, t + DT)
    halfway = 0.5 * (ground + landed)
    slope = (ground - landed) / (end - landed_at)
    assert (out.left_foot if swing == 0 else out.right_foot)[2] == pytest.approx(halfway, abs=slope * DT)
    out, t = walk_to(ctl, end + DT, t)
    assert (out.left_foot if swing == 0 else out.right_foot)[2] == pytest.approx(ground, abs=1e-12)
    # Through the next double support (phase 4), as the stance foot, it keeps that height; over its own next swing
    # (phase 5) the height is blended out, so it lands at the plan's height.
    out, t = walk_to(ctl, planner.phase_start(5), t)
    assert (out.left_foot if swing == 0 else out.right_foot)[2] == pytest.approx(ground, abs=1e-12)
    middle = planner.phase_start(5) + 0.5 * planner.timeline.duration(5)
    values, _, _ = planner.sample_values(middle)
    out, t = walk_to(ctl, middle + DT, t)
    blended = (out.left_foot if swing == 0 else out.right_foot)[2] - planned_height(values, swing)
    assert blended == pytest.approx(0.5 * ground, abs=1e-9)
    out, t = walk_to(ctl, planner.phase_start(6) + DT, t)
    assert (out.left_foot if swing == 0 else out.right_foot)[2] == pytest.approx(0.0, abs=1e-9)


RAMP = 0.2  # rad: a ramp down, its footholds 2 cm lower at every 0.1 m step
RAMP_DROP = 0.02


def sunk(m: Measurement, drift: float) -> Measurement:
    """``m`` with both soles measured ``drift`` (m) lower: the estimator's frame sunk under the robot."""
    feet = [foot._replace(pose=(*foot.pose[:2], foot.pose[2] + drift, foot.pose[3])) for foot in (m.left, m.right)]
    return m._replace(left=feet[0], right=feet[1])


@pytest.mark.parametrize(("drift", "depth"), [(0.0, 0.0), (-0.03, 0.0), (0.0, -0.008), (-0.03, -0.008)])
def test_adaptive_late_touchdown_down_a_ramp_stands_at_the_ground_it_met_relative_to_its_foothold(drift, depth):
    # The footholds are 2, 4, 6 cm down a ramp; the late foot meets the ground `depth` below its foothold, measured in
    # an estimated frame `drift` below the world (both soles). Its target stands `depth` below the plan: the offset
    # over the plan is the ground's depth under the foothold, measured against the other foot (the measured height
    # itself, -2 cm and lower, would sink every stance target by the foothold's depth down to late_descent_limit).
    strides = [Stride(0.1, CONFIG.step_width, 0.0, -RAMP_DROP, RAMP)] * 3 + [
        Stride(0.0, CONFIG.step_width, 0.0, 0.0, RAMP)
    ]
    options = ControllerOptions(measurement_filter=0.0, foot=None, late_grace=0.0)
    ctl = make_controller("adaptive", CONFIG, strides, SOLE, INFO, dt=DT, options=options)
    ctl.start(0.0)
    start, duration, swing = first_swing(ctl)
    side = ("left", "right")[swing]
    not_down = (True, False) if swing == 1 else (False, True)
    _, t = walk_to(ctl, start + duration)
    _, t = walk_to(ctl, t + 0.02, t, loaded=not_down)  # the swing ended in the air: late, its target descending
    planner = ctl.planner
    target = planner.footprints()[2]
    assert target.z == pytest.approx(-RAMP_DROP)
    landing = Landing(t, side, target.x, target.y, target.z + depth + drift, target.yaw, 0.0, RAMP, 40.0)
    values, support, _ = planner.sample_values(t)
    out = ctl.tick(t, sunk(on_plan(t, values, support, landings=[landing], loaded=(True, True)), drift))
    assert [e.detail for e in out.events if e.kind == "landing"] == ["late"]
    # Over the single support it carries next (phase 3) its target goes to `depth` below the plan, and stays.
    end = planner.phase_start(3) + planner.timeline.duration(3)
    out, t = walk_to(ctl, end + DT, t + DT)
    values, _, _ = planner.sample_values(t - DT)
    foot = out.left_foot if swing == 0 else out.right_foot
    assert foot[2] - planned_height(values, swing) == pytest.approx(depth, abs=1e-9)


def test_stabilized_logs_landings_without_touching_the_plan():
    ctl = controller("stabilized")
    start, duration, swing = first_swing(ctl)
    _, t = walk_to(ctl, start + 0.75 * duration)
    before = ctl.planner.footprints()
    target = before[2]
    landing = Landing(t, ("left", "right")[swing], target.x + 0.02, target.y, 0.0, target.yaw, 0.0, 0.0, 40.0)
    values, support, _ = ctl.planner.sample_values(t)
    out = ctl.tick(t, on_plan(t, values, support, landings=[landing]))
    assert [(e.kind, e.detail) for e in out.events] == [("landing", "early")]
    assert ctl.planner.footprints() == before and out.support == support


def test_step_limits_scale_with_the_robot_and_keep_the_soles_apart():
    adjust = step_limits(INFO)
    assert adjust.limits.max_length == pytest.approx(0.35 * 0.84 / 0.8)
    assert adjust.limits.min_width >= 2 * SOLE.inner + 0.02 and adjust.limits.max_width > adjust.limits.min_width
    small = step_limits(RobotInfo(30.0, SoleRect(0.08, 0.05, 0.04, 0.04), 0.4))
    assert small.limits.max_length == pytest.approx(0.175) and small.limits.min_width == pytest.approx(0.1)
    # The core's closed loop ("always"): every plan from the measured state, step adjustment after each.
    timed = dataclasses.replace(adjust, adapt_timing=True)  # ControllerOptions' default adds step timing adaptation
    ctl = controller("adaptive", options=ControllerOptions(measured_replanning="always"))
    assert ctl.planner.config.step_adjustment == timed and ctl.planner.config.feedback == "measured"
    # The default ("on-error"): the plan continues itself; the measured state and step adjustment on a DCM error only.
    ctl = controller("adaptive")
    assert ctl.planner.config.step_adjustment is None and ctl.planner.config.feedback == "planned"
    assert ctl.options.step_adjustment == timed
    assert controller("adaptive", options=ControllerOptions(adapt_timing=False)).options.step_adjustment == adjust
    with pytest.raises(ValueError, match="must be one of"):
        make_controller("stiff", CONFIG, None, SOLE, INFO)


LENGTHENING = ControllerOptions(
    measurement_filter=0.0, adapt_timing=True,
    step_adjustment=dataclasses.replace(
        step_limits(INFO), limits=dataclasses.replace(step_limits(INFO).limits, max_single_support=1.2)
    ),
)  # fmt: skip


@pytest.mark.parametrize(("outward", "options"), [(True, EXACT), (False, EXACT), (True, LENGTHENING)])
def test_adaptive_keeps_the_plan_for_an_outward_dcm_error_in_single_support(outward, options):
    # The first single support: F[1] carries it; an error away from the swing foot cannot be caught by any landing
    # on the swing foot's side, so the plan under way is kept; toward the swing foot it replans from the measured
    # state. With steps that may be held longer (max_single_support), the outward error is replanned too: the
    # stance held longer is its answer.
    ctl, plan = controller("adaptive", options=options), reference()
    start, duration, _ = first_swing(ctl)
    stance = ctl.planner.footprints()[1]
    away = 1.0 if stance.side == "left" else -1.0
    error = (0.0, 0.04 * (away if outward else -away))
    before = ctl.planner.footprints()
    events, worst = [], 0.0
    for k in range(round((start + 0.3 * duration) / DT), round((start + 0.6 * duration) / DT)):
        t = k * DT
        values, support, _ = plan.sample_values(t)
        if k == round((start + 0.3 * duration) / DT):
            walk_to(ctl, t)
        out = ctl.tick(t, on_plan(t, values, support, dcm_error=error))
        events += out.events
        worst = max(worst, math.dist(out.com[:2], (values.cog_x, values.cog_y)) - math.hypot(*out.com_offset))
    kinds = {e.kind for e in events}
    if options is LENGTHENING:
        assert "replan" in kinds and "replan-skipped" not in kinds
        decision = ctl.planner.step_adjustments[-1]
        assert decision.single_support > decision.nominal_single_support, decision.reason
        assert "later" in decision.reason
    elif outward:
        assert "replan-skipped" in kinds and "replan" not in kinds
        assert ctl.planner.footprints() == before
        assert worst < 1e-9, "the IK's COM target is the plan's with the feedback law's correction"
    else:
        assert "replan" in kinds and "replan-skipped" not in kinds


def test_step_limits_come_from_the_robot_description(talos):
    # A described [stepping] table is the stride box of step adjustment, not the leg-length scaling.
    limits = SteppingLimits(max_length=0.2, min_width=0.16, max_width=0.3, max_swing_speed=0.9, min_single_support=0.5)
    info = RobotInfo(90.0, SOLE, 0.84, limits)
    ctl = make_controller("adaptive", CONFIG, straight_walk(CONFIG, 3, 0.1), SOLE, info, dt=DT)
    adjust = ctl.options.step_adjustment
    assert adjust.limits == limits and adjust.adapt_timing
    assert dataclasses.replace(step_limits(info), adapt_timing=True) == adjust
    assert step_limits(info, SteppingLimits()).limits.max_length == 0.35
    # A loaded robot carries its description's table, also through a sole given apart.
    assert robot_info(talos).stepping == talos.description.stepping is not None
    other = SoleRect(0.1, 0.1, 0.06, 0.06)
    options = ControllerOptions(adapt_timing=True)
    ctl = make_controller("adaptive", CONFIG, None, other, robot_info(talos), options=options)
    adjust = ctl.options.step_adjustment
    assert adjust.limits.max_length == talos.description.stepping.max_length and adjust.sole == other
    assert adjust.adapt_timing
    with pytest.raises(ValueError, match="adapt_timing"):
        ControllerOptions(adapt_timing=1)


def test_a_later_step_that_catches_nothing_is_kept_and_the_swinging_one_moves():
    # A forward DCM error far beyond any step: late in a single support (within min_time_to_touchdown of the
    # touch-down) the step adjustment would move the next step's landing without catching it: the core keeps it
    # (on_failure="keep"); earlier, the swinging foot's own landing takes the best candidate.
    error = (0.3, 0.0)
    for when, kept in ((0.85, True), (0.4, False)):
        ctl, plan = controller("adaptive"), reference()
        start, duration, _ = first_swing(ctl)
        t = round((start + when * duration) / DT) * DT
        walk_to(ctl, t)
        before = ctl.planner.footprints()
        values, support, _ = plan.sample_values(t)
        events = ctl.tick(t, on_plan(t, values, support, dcm_error=error)).events
        kinds = [e.kind for e in events]
        assert "replan" in kinds
        decision = ctl.planner.step_adjustments[-1]
        assert decision.emergency
        if kept:
            assert "step-refused" in kinds and "step-adjustment" not in kinds
            assert decision.step == 2 and ctl.planner.footprints() == before
        else:
            assert "step-adjustment" in kinds and decision.step == 1
            moved = [a for a, b in zip(ctl.planner.footprints(), before, strict=True) if a != b]
            assert moved and moved[0].x > before[2].x  # the swinging foot lands ahead, toward the error


# ----- the blend of a re-anchored foot's IK target (ControllerOptions.anchor_blend) ---------------------------------
# The minimum-jerk share b(s) = 1 - 10 s^3 + 15 s^4 - 6 s^5 has its steepest slope, 15/8, at s = 1/2 and its largest
# curvature, 10/sqrt(3), at s = 1/2 -+ sqrt(3)/6: a jump J blended over T moves the target at most 15/8 J dt/T per tick
# and changes that by at most 10/sqrt(3) J (dt/T)^2.
PEAK_SLOPE, PEAK_CURVATURE = 15.0 / 8.0, 10.0 / math.sqrt(3.0)


def horizontal(out, swing):
    foot = out.left_foot if swing == 0 else out.right_foot
    return (foot[0], foot[1], foot[3])


@pytest.mark.parametrize("blend", [0.0, 0.04])
def test_a_late_foot_re_anchored_on_the_ground_moves_there_smoothly(blend):
    options = ControllerOptions(measurement_filter=0.0, foot=None, late_grace=0.0, anchor_blend=blend)
    ctl = controller("adaptive", options=options)
    start, duration, swing = first_swing(ctl)
    side = ("left", "right")[swing]
    not_down = (True, False) if swing == 1 else (False, True)
    _, t = walk_to(ctl, start + duration)  # the swing ends in the air: late
    out, t = walk_to(ctl, t + 0.01, t, loaded=not_down)
    planner = ctl.planner
    target = planner.footprints()[2]
    # It lands 10 mm behind and 4 mm inside its target, turned 10 mrad: the planner re-anchors it there.
    landing = Landing(t, side, target.x - 0.01, target.y + 0.004, -0.003, target.yaw + 0.01, 0.0, 0.0, 40.0)
    path = [horizontal(out, swing)]
    values, support, _ = planner.sample_values(t)
    out = ctl.tick(t, on_plan(t, values, support, landings=[landing], loaded=(True, True)))
    assert any(e.kind == "touchdown" for e in out.events)
    path.append(horizontal(out, swing))
    for _ in range(round(0.06 / DT)):  # its target from the plan: where it landed
        t += DT
        values, support, _ = planner.sample_values(t)
        path.append(horizontal(ctl.tick(t, on_plan(t, values, support, loaded=(True, True))), swing))
    anchored = (landing.x, landing.y, landing.yaw)
    assert path[-1] == pytest.approx(anchored, abs=1e-12), "there after anchor_blend"
    if blend == 0.0:  # at once: the loaded foot's target steps by the whole re-anchoring in one tick
        assert path[1] == pytest.approx(anchored, abs=1e-12)
        return
    assert path[1] == pytest.approx(path[0], abs=1e-12), "no jump at the touch-down"
    assert path[1 + round(blend / DT)] == pytest.approx(anchored, abs=1e-12), "there after anchor_blend"
    jump = math.hypot(0.01, 0.004)
    steps = [math.dist(a[:2], b[:2]) for a, b in itertools.pairwise(path)]
    assert max(steps) <= PEAK_SLOPE * jump * DT / blend * (1.0 + 1e-6)
    assert max(steps) > 0.9 * PEAK_SLOPE * jump * DT / blend, "the bound is reached: the blend is the quintic's"
    rates = [(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(path)]
    curvature = [math.dist(a, b) for a, b in itertools.pairwise(rates)]
    assert max(curvature) <= PEAK_CURVATURE * jump * (DT / blend) ** 2 * (1.0 + 1e-3)
    yaw_steps = [abs(b[2] - a[2]) for a, b in itertools.pairwise(path)]
    assert max(yaw_steps) <= PEAK_SLOPE * 0.01 * DT / blend * (1.0 + 1e-6)


@pytest.mark.parametrize("blend", [0.0, 0.04])
def test_a_swing_foot_re_anchored_in_its_last_milliseconds_is_not_rushed(blend):
    # On time, 5 ms before the plan's touch-down, 8 mm from its target: the planner's retargeted swing runs to the
    # measured landing in those 5 ms (1.6 mm per tick and more); the IK's target takes the blend's time.
    ctl = controller("adaptive", options=ControllerOptions(measurement_filter=0.0, anchor_blend=blend))
    start, duration, swing = first_swing(ctl)
    side = ("left", "right")[swing]
    out, t = walk_to(ctl, start + duration - 0.005)
    planner = ctl.planner
    target = planner.footprints()[2]
    landing = Landing(t, side, target.x + 0.008, target.y, 0.001, target.yaw, 0.0, 0.0, 40.0)
    path = [horizontal(out, swing)]
    for k in range(round(0.06 / DT)):
        values, support, _ = planner.sample_values(t)
        out = ctl.tick(t, on_plan(t, values, support, landings=[landing] if k == 0 else [], loaded=(True, True)))
        if k == 0:
            assert [e.detail for e in out.events if e.kind == "landing"] == ["on time"]
        path.append(horizontal(out, swing))
        t += DT
    assert path[-1] == pytest.approx((landing.x, landing.y, landing.yaw), abs=1e-12)
    largest = max(math.dist(a[:2], b[:2]) for a, b in itertools.pairwise(path))
    if blend == 0.0:
        assert largest > 1.5e-3
    else:
        assert largest <= PEAK_SLOPE * 0.008 * DT / blend * 1.05


def test_anchor_blend_is_validated():
    for bad in (-0.01, math.nan, math.inf):
        with pytest.raises(ValueError, match="anchor_blend"):
            ControllerOptions(anchor_blend=bad)
