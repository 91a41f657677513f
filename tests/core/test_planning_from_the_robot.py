"""Planning from the robot: start anywhere, replan from the measured state at any instant, re-anchor on real
footholds, the DCM in every sample, step adjustment.

Independent truths: the pendulum equation, the connection conditions (a plan made from a state starts exactly at
it), rigid-motion invariance (a walk started elsewhere is the same walk moved), the strides (after a touchdown the
later footprints are the old strides applied to the measured foothold), the free pendulum (an observation carried
to the connection instant).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.geometry.footsteps import Footstep, SoleRect, Timing, place_step
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig, straight_walk

SOLE = SoleRect(0.13, 0.10, 0.07, 0.07)
DT = 0.001


def _walk_until(planner: OnlinePlanner, t_end: float, t: float = 0.0, observe=None) -> float:
    while t < t_end:
        s = planner.sample(t)
        if observe is not None:
            observe(t, s)
        t += DT
    return t


def _rigid(x: float, y: float, yaw: float, dx: float, dy: float, dyaw: float) -> tuple[float, float, float]:
    c, s = math.cos(dyaw), math.sin(dyaw)
    return dx + c * x - s * y, dy + s * x + c * y, yaw + dyaw


# ----- 1. start anywhere ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("connection", ["real-time", "quasi-real-time"])
def test_a_walk_started_elsewhere_is_the_same_walk_moved(connection):
    cfg = PlannerConfig(timing=Timing(0.7, 0.1), connection=connection)
    home = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.15))
    home.start(0.0)
    dx, dy, dyaw = 1.3, -0.4, 2.2
    feet = []
    for foot in home.footprints()[:2]:
        x, y, yaw = _rigid(foot.x, foot.y, foot.yaw, dx, dy, dyaw)
        feet.append(Footstep(x, y, yaw, foot.side))
    left, right = sorted(feet, key=lambda f: f.side)
    away = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.15))
    away.start(0.0, feet=(left, right))
    c, s = math.cos(dyaw), math.sin(dyaw)
    for t in np.arange(0.0, home.end_time, 0.037):
        a, b = home.sample(float(t)), away.sample(float(t))
        for part in ("cog", "zmp", "dcm"):
            xa, ya = getattr(a, part)[:2]
            want = (dx + c * xa - s * ya, dy + s * xa + c * ya)
            assert getattr(b, part)[:2] == pytest.approx(want, abs=1e-9), (part, t)
        vx, vy = a.cog_vel[:2]
        assert b.cog_vel[:2] == pytest.approx((c * vx - s * vy, s * vx + c * vy), abs=1e-9)
    for ha, hb in zip(home.footprints(), away.footprints(), strict=True):
        assert (hb.x, hb.y) == pytest.approx(_rigid(ha.x, ha.y, ha.yaw, dx, dy, dyaw)[:2], abs=1e-12)


def test_start_from_a_moving_cog_begins_exactly_there():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    p = OnlinePlanner(cfg, straight_walk(cfg, 3, 0.1))
    p.start(2.0, cog=(0.03, -0.01), cog_vel=(0.1, 0.05))
    s = p.sample(2.0)
    assert s.cog[:2] == pytest.approx([0.03, -0.01], abs=1e-12)
    assert s.cog_vel[:2] == pytest.approx([0.1, 0.05], abs=1e-12)
    assert s.dcm == pytest.approx(s.cog[:2] + s.cog_vel[:2] / p.w, abs=1e-12)
    trajectory = p.current_plan
    times = np.linspace(2.0, 2.99, 50)
    assert np.abs(trajectory.pendulum_residual(times)).max() < 1e-9
    end = p.sample(p.end_time)
    assert np.abs(end.cog_vel[:2]).max() < 1e-9  # it still ends at rest


def test_start_refuses_feet_of_the_wrong_sides():
    p = OnlinePlanner(PlannerConfig(), straight_walk(PlannerConfig(), 2, 0.1))
    with pytest.raises(ValueError, match="left, right"):
        p.start(0.0, feet=(Footstep(0, 0.1, 0, "right"), Footstep(0, -0.1, 0, "left")))


# ----- 2. replanning from the measured state ----------------------------------------------------------------------
def test_measured_feedback_connects_from_the_observation_carried_by_the_pendulum():
    cfg = PlannerConfig(timing=Timing(0.7, 0.1), feedback="measured")
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    p.start(0.0)
    t_conn = p.phase_start(4)
    t_obs = t_conn - 0.05
    t = _walk_until(p, t_obs)
    planned = p.sample(t_obs)
    offset, kick = np.array([0.01, -0.02]), np.array([0.05, 0.08])
    p.observe(t_obs, planned.cog[:2] + offset, planned.cog_vel[:2] + kick)
    zmp_before = p.current_plan.zmp.evaluate(t_conn, side="left")[0]
    planned_at_conn = p.current_plan.evaluate(t_conn)
    after = p.sample(t_conn)  # the replan at the double-support start
    assert p.plans[-1].t == t_conn
    w = p.w
    d = t_conn - t_obs  # the deviation from the plan is a free pendulum: e'' = w^2 e
    e = offset * math.cosh(w * d) + kick / w * math.sinh(w * d)
    de = offset * w * math.sinh(w * d) + kick * math.cosh(w * d)
    assert after.cog[:2] == pytest.approx(planned_at_conn[0][0] + e, abs=1e-9)
    assert after.cog_vel[:2] == pytest.approx(planned_at_conn[1][0] + de, abs=1e-9)
    assert after.zmp == pytest.approx(zmp_before, abs=1e-9), "the ZMP asked of the robot stays continuous"
    times = np.linspace(t_conn, t_conn + 2.0, 200)
    assert np.abs(p.current_plan.pendulum_residual(times)).max() < 1e-9
    del t


def test_planned_feedback_ignores_observations():
    cfg = PlannerConfig(timing=Timing(0.7, 0.1))
    a, b = OnlinePlanner(cfg, straight_walk(cfg, 4, 0.1)), OnlinePlanner(cfg, straight_walk(cfg, 4, 0.1))
    a.start(0.0)
    b.start(0.0)
    for t in np.arange(0.0, 4.0, 0.01):
        sa, sb = a.sample(float(t)), b.sample(float(t))
        b.observe(float(t), sb.cog[:2] + 0.05, sb.cog_vel[:2])
        assert sa.values.tolist() == sb.values.tolist()


# ----- 3. replanning at any instant ------------------------------------------------------------------------------
@pytest.mark.parametrize("fraction", [0.1, 0.25, 0.4])
@pytest.mark.parametrize("phase", [3, 4, 5])
def test_replan_now_from_a_state_on_the_plan_reproduces_it(phase, fraction):
    cfg = PlannerConfig(timing=Timing(0.7, 0.1), connection="quasi-real-time")
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    p.start(0.0)
    t = p.phase_start(phase) + fraction * (p.phase_start(phase + 1) - p.phase_start(phase))
    _walk_until(p, t)
    old = p.current_plan
    record = p.replan_now(t)
    assert record is not None and record.t == t and record.reason == "request"
    new = p.current_plan
    times = np.linspace(t, p.phase_start(phase + 4), 300)
    # Round-off grows as the free segment shortens (its quartic's coefficients scale as 1/T^4): 0.1 um for the
    # 25 ms left of a double support, far less over a single support.
    for a, b in zip(old.evaluate(times), new.evaluate(times), strict=True):
        assert np.abs(a - b).max() < 1e-7
    assert np.abs(old.zmp.evaluate(times) - new.zmp.evaluate(times)).max() < 1e-7


def test_replan_now_from_a_perturbed_state_starts_exactly_there_and_obeys_the_pendulum():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2), feedback="measured")
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    p.start(0.0)
    t = p.phase_start(5) + 0.25  # mid single support
    _walk_until(p, t)
    s = p.sample(t)
    dc, dv = np.array([0.005, 0.01]), np.array([0.02, -0.03])
    p.observe(t, s.cog[:2] + dc, s.cog_vel[:2] + dv)
    zmp_before = p.current_plan.zmp.evaluate(t)[0], p.current_plan.zmp.evaluate(t, derivative=1)[0]
    p.replan_now(t)
    after = p.sample(t)
    assert after.cog[:2] == pytest.approx(s.cog[:2] + dc, abs=1e-12)
    assert after.cog_vel[:2] == pytest.approx(s.cog_vel[:2] + dv, abs=1e-12)
    assert after.zmp == pytest.approx(zmp_before[0], abs=1e-12)
    assert p.current_plan.zmp.evaluate(t, derivative=1)[0] == pytest.approx(zmp_before[1], abs=1e-9)
    times = np.linspace(t, p.end_time, 500)
    assert np.abs(p.current_plan.pendulum_residual(times)).max() < 1e-9
    # The free segment ends with the phase: from there on the plan rests on the footprints again.
    end = p.phase_start(6)
    stance = p.footprints()[3]
    assert p.current_plan.zmp.evaluate(end)[0] == pytest.approx([stance.x, stance.y], abs=1e-9)


def test_replan_now_near_the_end_of_a_phase_waits_for_the_next_double_support():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    p = OnlinePlanner(cfg, straight_walk(cfg, 3, 0.1))
    p.start(0.0)
    t = p.phase_start(2) - 0.01
    _walk_until(p, t)
    assert p.replan_now(t) is None


def test_a_large_dcm_error_replans_by_itself():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2), feedback="measured", replan_dcm_error=0.02)
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    p.start(0.0)
    t = p.phase_start(3) + 0.3
    _walk_until(p, t)
    s = p.sample(t)
    count = p.replan_count
    p.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, 0.03]))  # DCM error 9 mm: below the threshold
    assert p.replan_count == count
    p.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, 0.1]))  # 29 mm: above
    assert p.replan_count == count + 1 and p.plans[-1].reason == "dcm-error"


# ----- 4. re-anchoring on real footholds --------------------------------------------------------------------------
def test_touchdown_moves_the_footprint_and_the_later_ones_keep_their_strides():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.12))
    p.start(0.0)
    t = _walk_until(p, p.phase_start(6) + 0.05)  # double support after step 3 landed on F[4]
    strides = [p.walk.stride(k) for k in range(1, 8)]
    landed = p.footprints()[4]
    index = p.touchdown(t, landed.side, landed.x + 0.03, landed.y - 0.02, landed.yaw + 0.05)
    assert index == 4
    prints = p.footprints()
    assert (prints[4].x, prints[4].y, prints[4].yaw) == pytest.approx((landed.x + 0.03, landed.y - 0.02, 0.05))
    for k in range(4, 7):  # step k lands F[k + 1] from F[k] with its old stride
        want = place_step(prints[k], strides[k - 1])
        assert (prints[k + 1].x, prints[k + 1].y, prints[k + 1].yaw) == pytest.approx((want.x, want.y, want.yaw))
    # The next plan rests on the measured foothold: the single support of step 4 stands on F[4].
    _walk_until(p, p.phase_start(7) + 0.3, t)
    assert p.sample(p.phase_start(7) + 0.3).zmp == pytest.approx([prints[4].x, prints[4].y], abs=1e-9)


def test_slips_never_accumulate():
    cfg = PlannerConfig(timing=Timing(0.5, 0.1, start=0.5))
    p = OnlinePlanner(cfg, straight_walk(cfg, 20, 0.1))
    p.start(0.0)
    t = 0.0
    for step in range(1, 15):
        t = _walk_until(p, p.phase_start(2 * step) + 0.01, t)
        landed = p.footprints()[step + 1]
        p.touchdown(t, landed.side, landed.x + 0.01, landed.y, landed.yaw)  # every landing 1 cm long
    prints = p.footprints()
    # Each landing is its stride (0.1 m) from the measured one before it, plus the new 1 cm: the error does not grow
    # (without re-anchoring, the measured feet would drift 1 cm further from the plan at every step).
    gaps = [prints[k + 1].x - prints[k].x for k in range(2, 15)]
    assert gaps == pytest.approx([0.11] * len(gaps), abs=1e-9)


# ----- 5. the DCM --------------------------------------------------------------------------------------------------
def test_every_sample_carries_the_dcm():
    cfg = PlannerConfig()
    p = OnlinePlanner(cfg, straight_walk(cfg, 3, 0.1))
    p.start(0.0)
    for t in np.linspace(0.0, p.end_time, 97):
        s = p.sample(float(t))
        assert s.dcm == pytest.approx(s.cog[:2] + s.cog_vel[:2] / p.w, abs=1e-15)


# ----- 7. step adjustment -----------------------------------------------------------------------------------------
def _pushed(push_velocity, adjust: StepAdjustment | None, fraction: float = 0.35):
    cfg = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=adjust
    )
    p = OnlinePlanner(cfg, straight_walk(cfg, 8, 0.1))
    p.start(0.0)
    t = p.phase_start(5) + fraction * 0.7
    _walk_until(p, t, observe=lambda t, s: p.observe(t, s.cog[:2], s.cog_vel[:2]))
    s = p.sample(t)
    p.observe(t, s.cog[:2], s.cog_vel[:2] + np.asarray(push_velocity))
    p.replan_now(t)
    return p, t


@pytest.mark.parametrize("push", [(0.0, -0.15), (0.25, 0.0), (-0.2, 0.0), (0.0, 0.11)])
def test_step_adjustment_keeps_the_zmp_inside_where_the_ankle_alone_cannot(push):
    adjust = StepAdjustment(SOLE)
    plain, _ = _pushed(push, None)
    halfwidth = 0.07
    stance = plain.footprints()[3]
    zmp = plain.current_plan.zmp.evaluate(np.linspace(plain.plans[-1].t, plain.phase_start(6), 50))
    outside = np.max(np.abs(zmp - [stance.x, stance.y]) - [0.13, halfwidth])
    assert outside > 0.0, "without stepping the plan asks for a ZMP off the stance foot"
    adjusted, t = _pushed(push, adjust)
    decision = adjusted.step_adjustments[-1]
    assert decision.step == 3 and not decision.emergency
    assert decision.margin_after >= adjust.required_margin - 1e-9
    # The landing moved toward the push, within the stride box.
    moved = np.subtract(decision.landing, decision.nominal)
    assert np.dot(moved, push) > 0.0
    zmp = adjusted.current_plan.zmp.evaluate(np.linspace(t, adjusted.phase_start(6), 80))
    assert np.all(np.abs(zmp - [stance.x, stance.y]) <= [0.13 + 1e-9, halfwidth + 1e-9])
    # The swing foot continues smoothly to the new landing and lands there.
    poses = [adjusted.sample(float(u)).right_foot for u in np.arange(t, adjusted.phase_start(6) + 0.05, DT)]
    steps = np.abs(np.diff(np.array(poses)[:, :2], axis=0)).max()
    assert steps < 3.0 * DT, f"the swing foot jumps {steps} m in a tick"
    assert poses[-1][:2] == pytest.approx(decision.landing, abs=1e-9)


@pytest.mark.parametrize("on_failure", ["continue", "stop"])
def test_a_push_no_step_can_catch_takes_the_best_capture_step(on_failure):
    adjust = StepAdjustment(SOLE, on_failure=on_failure)
    p, t = _pushed((0.0, 0.6), adjust)  # outward on the left stance foot: the right foot cannot cross over
    decision = p.step_adjustments[-1]
    assert decision.emergency and decision.margin_before < -0.1
    assert decision.margin_after >= 0.0, "the plan under way is the realisable one, from the planned state"
    moved = np.subtract(decision.landing, decision.nominal)
    assert moved[1] > 0.0, "the capture step goes toward the push"
    if on_failure == "stop":
        assert "emergency stop" in decision.reason
        assert p.n_steps == decision.step + 1, "the walk stops with the step after the capture step"
    else:
        assert "walking on" in decision.reason and p.n_steps == 9
        # The plan under way starts from the planned state again, not the measured one (0.6 m/s faster sideways).
        assert p.sample(t).cog_vel[1] < 0.3


def test_step_adjustment_respects_the_stride_box():
    adjust = StepAdjustment(SOLE, SteppingLimits(max_length=0.2, min_width=0.15, max_width=0.3))
    p, _ = _pushed((0.4, -0.2), adjust)
    decision = p.step_adjustments[-1]
    stance = p.footprints()[decision.step]
    forward, lateral = decision.landing[0] - stance.x, stance.y - decision.landing[1]
    assert -0.2 - 1e-9 <= forward <= 0.2 + 1e-9
    assert 0.15 - 1e-9 <= lateral <= 0.3 + 1e-9


def test_touchdown_reported_at_the_landing_instant_re_anchors_the_new_double_support():
    """The loop's order is observe, touchdown, sample: the landing tick is the first of the double support."""
    cfg = PlannerConfig(timing=Timing(0.8, 0.2))
    p = OnlinePlanner(cfg, straight_walk(cfg, 5, 0.1))
    p.start(0.0)
    landing = p.phase_start(4)
    _walk_until(p, landing - DT / 2)  # the last sample is in step 2's single support
    nominal = p.footprints()[3]
    index = p.touchdown(landing, nominal.side, nominal.x + 0.02, nominal.y, nominal.yaw)
    assert index == 3
    # The double support's plan ends on the landed foot: the next single support stands on it.
    end = p.phase_start(5)
    assert p.current_plan.zmp.evaluate(end)[0] == pytest.approx([nominal.x + 0.02, nominal.y], abs=1e-9)
    assert p.sample(landing).zmp == pytest.approx(p.current_plan.zmp.evaluate(landing)[0], abs=1e-12)


def test_a_dcm_error_near_the_end_of_a_phase_waits_for_the_next_one():
    cfg = PlannerConfig(timing=Timing(0.8, 0.2), feedback="measured", replan_dcm_error=0.02)
    p = OnlinePlanner(cfg, straight_walk(cfg, 6, 0.1))
    p.start(0.0)
    t = p.phase_start(4) - 0.05  # 50 ms before the single support ends
    _walk_until(p, t)
    s = p.sample(t)
    count = p.replan_count
    p.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, 0.2]))
    assert p.replan_count == count, "no replan over a 50 ms remainder"
