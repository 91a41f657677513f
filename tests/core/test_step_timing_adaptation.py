"""Step timing adaptation (Morisawa et al. 2006): step adjustment may also shorten the single support of the step it
adjusts.

Independent truths: the pendulum plant integrated in closed form (:mod:`rtgait.core.pendulum.loop`) and the
capturability bounds of the LIPM (a push beyond the one-step bound at the nominal touch-down, inside it at the
earliest one); the pendulum equation and the connection conditions of the retimed plan; the swing foot's own
trajectory (continuous, landing where and when the plan says); a direct evaluation of every candidate's margin.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pendulum_walk import CONFIG, MASS, PUSHED_STEP, SOLE, STRIDES, W

from rtgait.core.geometry.footsteps import Timing
from rtgait.core.geometry.halfplanes import halfplane_margin, polygon_halfplanes
from rtgait.core.geometry.support import signed_margin
from rtgait.core.laws.capturability import max_capturable_impulse, reach_along
from rtgait.core.laws.landing_choice import choose_step
from rtgait.core.laws.step_timing import remainder_options, single_support_options
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.pendulum.loop import run_pendulum_loop
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig, straight_walk
from rtgait.core.push import Push

LANDING = StepAdjustment(sole=SOLE)
TIMING = StepAdjustment(sole=SOLE, adapt_timing=True)
DT = 0.001


def _loop(adjust: StepAdjustment, pushes, dt: float):
    return run_pendulum_loop(
        CONFIG, STRIDES, SOLE, controller="adaptive", mass=MASS, dt=dt, pushes=pushes, step_adjustment=adjust
    )


def _mid_single_support() -> tuple[float, np.ndarray, OnlinePlanner]:
    planner = OnlinePlanner(CONFIG, STRIDES)
    planner.start(0.0)
    t_mid = planner.phase_start(2 * PUSHED_STEP - 1) + 0.5 * CONFIG.timing.single_support
    for t in np.arange(0.0, t_mid, 0.05):
        planner.sample(float(t))
    return t_mid, planner.sample(t_mid).dcm.copy(), planner


# ----- the pendulum: a push that only a sooner step catches ------------------------------------------------------
@pytest.mark.parametrize("dt", [0.005, 0.0025])
def test_a_push_no_landing_alone_catches_is_caught_by_stepping_sooner(dt):
    t_mid, dcm, planner = _mid_single_support()
    stance = planner.walk.footprint(PUSHED_STEP)
    u = np.array([0.0, -1.0])  # toward the swinging right foot: it can step out to 0.45 m from the stance foot
    reach = reach_along(SOLE.corners(stance), stance.position, u)
    remaining = 0.5 * CONFIG.timing.single_support
    common = dict(mass=MASS, omega=W, r_max=reach, l_max=LANDING.limits.max_width, step_time=CONFIG.timing.step_period,
                  min_remaining=LANDING.limits.min_time_to_touchdown, steps=1)  # fmt: skip
    nominal_bound = max_capturable_impulse(dcm - stance.position, u, remaining=remaining, **common)
    earliest = max(TIMING.limits.min_time_to_touchdown, TIMING.limits.min_single_support - remaining)
    early_bound = max_capturable_impulse(dcm - stance.position, u, remaining=earliest, **common)
    impulse = 34.0  # N s
    assert nominal_bound < impulse < early_bound, (nominal_bound, early_bound)
    push = Push(t_mid - 0.05, 0.1, tuple(impulse / 0.1 * u))

    landing_only = _loop(LANDING, [push], dt)
    assert landing_only.fell, "no landing in the stride box catches it at the nominal touch-down"
    assert all(d.single_support == d.nominal_single_support for d in landing_only.step_adjustments)

    retimed = _loop(TIMING, [push], dt)
    assert not retimed.fell and retimed.ended_at_rest
    sooner = [d for d in retimed.step_adjustments if d.single_support < d.nominal_single_support - 1e-6]
    assert sooner and sooner[0].step == PUSHED_STEP
    # The pushed step's single support as the plant lived it (the ticks in its phase) is the one chosen last.
    chosen = [d for d in retimed.step_adjustments if d.step == PUSHED_STEP][-1].single_support
    lived = np.count_nonzero(retimed.phase == 2 * PUSHED_STEP - 1) * dt
    assert lived == pytest.approx(chosen, abs=dt + 1e-9)
    assert chosen < CONFIG.timing.single_support - 0.05


# ----- the retimed plan ------------------------------------------------------------------------------------------
def _pushed_planner(adjust: StepAdjustment, push_velocity, fraction: float = 0.35):
    config = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=adjust
    )
    planner = OnlinePlanner(config, straight_walk(config, 8, 0.1))
    planner.start(0.0)
    t_push = planner.phase_start(5) + fraction * 0.7
    t = 0.0
    while t < t_push:
        s = planner.sample(t)
        planner.observe(t, s.cog[:2], s.cog_vel[:2])
        t += DT
    before = planner.sample(t)
    zmp = planner.current_plan.zmp
    zmp_before = zmp.evaluate(t)[0], zmp.evaluate(t, derivative=1)[0]
    measured = before.cog[:2], before.cog_vel[:2] + np.asarray(push_velocity)
    planner.observe(t, *measured)
    planner.replan_now(t)
    return planner, t, measured, zmp_before, before.right_foot


def test_the_retimed_plan_starts_at_the_measured_state_obeys_the_pendulum_and_lands_sooner():
    push = (0.0, -0.25)  # m/s, outward for the swinging right foot
    plain, *_ = _pushed_planner(LANDING, push)
    assert plain.step_adjustments[-1].emergency, "no landing alone keeps the ZMP inside"

    planner, t, (cog, vel), (zmp0, dzmp0), foot0 = _pushed_planner(TIMING, push)
    decision = planner.step_adjustments[-1]
    k = decision.step
    assert k == 3 and not decision.emergency
    assert decision.nominal_single_support == 0.7
    assert TIMING.limits.min_single_support <= decision.single_support < 0.7 - 1e-3
    # The chosen timing is the step's timing now: phases from its touch-down on moved sooner.
    assert planner.timeline.duration(2 * k - 1) == pytest.approx(decision.single_support, abs=1e-12)
    touchdown = planner.phase_start(2 * k)
    assert touchdown == pytest.approx(planner.phase_start(2 * k - 1) + decision.single_support, abs=1e-12)
    assert touchdown - t >= TIMING.limits.min_time_to_touchdown - 1e-9
    # It starts exactly at the measured state, the ZMP continuous in position and velocity.
    after = planner.sample(t)
    assert after.cog[:2] == pytest.approx(cog, abs=1e-12)
    assert after.cog_vel[:2] == pytest.approx(vel, abs=1e-12)
    plan = planner.current_plan
    assert plan.zmp.evaluate(t)[0] == pytest.approx(zmp0, abs=1e-12)
    assert plan.zmp.evaluate(t, derivative=1)[0] == pytest.approx(dzmp0, abs=1e-9)
    # It is a pendulum solution (closed form, and by finite differences of the COG) to the end of the walk.
    times = np.linspace(t, planner.end_time, 700)
    assert np.abs(plan.pendulum_residual(times)).max() < 1e-9
    h = 1e-4
    mid = np.linspace(t + 0.01, touchdown + 1.0, 200)
    c = [plan.evaluate(mid + s)[0] for s in (-h, 0.0, h)]
    acc = (c[0] - 2.0 * c[1] + c[2]) / h**2
    assert np.abs(plan.zmp.evaluate(mid) - (c[1] - acc / W**2)).max() < 1e-5
    # Its free segment ends at the new touch-down, on the stance foot, and stays on the stance sole.
    assert plan.zmp.breaks[1] == pytest.approx(touchdown, abs=1e-12)
    stance = planner.footprints()[k]
    assert plan.zmp.evaluate(touchdown)[0] == pytest.approx([stance.x, stance.y], abs=1e-9)
    free = plan.zmp.evaluate(np.linspace(t, touchdown, 400), side="left")
    assert signed_margin(free, SOLE.corners(stance)).min() >= -1e-9
    # The swing foot continues from where it was, without a jump (height included), and lands then and there.
    ticks = np.arange(t, touchdown + 0.05, DT)
    feet = np.array([planner.sample(float(u)).right_foot for u in ticks])
    assert np.abs(feet[0, :3] - foot0[:3]).max() < 1e-12
    assert np.abs(np.diff(feet[:, :3], axis=0)).max() < 3.0 * DT
    landed = feet[ticks >= touchdown]
    assert np.abs(landed[:, :2] - decision.landing).max() < 1e-9 and np.abs(landed[:, 2]).max() < 1e-12
    assert planner.sample(touchdown + 0.01).support == "double"


def test_without_a_shorter_timing_on_offer_the_decisions_are_those_of_landings_alone():
    """adapt_timing with nothing shorter to offer (the shortest single support is the nominal one) takes the same
    path as adapt_timing off: the same decisions, the same walk."""
    t_mid, _, _ = _mid_single_support()
    push = Push(t_mid - 0.05, 0.1, (0.0, -300.0))
    off = _loop(LANDING, [push], 0.005)
    none_shorter = _loop(StepAdjustment(SOLE, SteppingLimits(min_single_support=0.7), adapt_timing=True), [push], 0.005)
    assert off.step_adjustments == none_shorter.step_adjustments and len(off.step_adjustments) >= 2
    assert np.array_equal(off.cog, none_shorter.cog)


# ----- the batch against a direct evaluation -------------------------------------------------------------------
@pytest.mark.parametrize("required", [0.005, 0.5])  # some candidates enough; none (the largest margin then)
def test_the_batched_choice_is_the_direct_evaluation_of_every_candidate(required):
    rng = np.random.default_rng(8)
    adjust = StepAdjustment(sole=SOLE, adapt_timing=True, time_cost=0.4, required_margin=required)
    stance = OnlinePlanner(CONFIG, STRIDES).walk.footprint(1)
    halfplanes = polygon_halfplanes(SOLE.corners(stance))
    candidates = rng.uniform(-0.3, 0.3, (60, 2))
    nominal = np.array([0.05, -0.1])
    zmp = rng.normal(0.0, 0.02, (3, 9, 2)) + stance.position
    gain = rng.uniform(0.0, 0.3, (3, 9))
    time_left = np.array([0.35, 0.3, 0.45])  # nominal, sooner, later
    change = time_left - time_left[0]
    swing_from = (0.0, -0.2)
    d, landing, margin, enough = choose_step(
        adjust, candidates, tuple(nominal), zmp, gain, halfplanes, swing_from, time_left, change
    )
    # Directly: every reachable (timing, landing) pair's ZMP through the polygon, one at a time.
    pairs = []
    for i in range(3):
        for c, point in enumerate(candidates):
            if math.dist(point, swing_from) <= adjust.limits.max_swing_speed * time_left[i]:
                delta = point - nominal
                m = halfplane_margin(zmp[i] + gain[i][:, None] * delta, *halfplanes).min()
                pairs.append((delta @ delta + (adjust.time_cost * change[i]) ** 2, i, c, m))
    good = [p for p in pairs if p[3] >= required]
    if good:
        best = min(good)
    else:  # the largest margin, a later touch-down left out (the stance would wait with its ZMP outside)
        fallback = [p for p in pairs if change[p[1]] <= 0.0]
        top = max(p[3] for p in fallback)
        best = min(p for p in fallback if p[3] >= top - 1e-3)
    assert bool(good) == enough and (required < 0.1) == enough
    assert (d, tuple(landing)) == (best[1], tuple(candidates[best[2]]))
    assert margin == pytest.approx(best[3], abs=1e-12)


def test_when_no_candidate_is_enough_the_largest_margin_no_later_than_planned_is_taken():
    """The documented fallback on a case built by hand: one edge, ``x <= 0``, the ZMP of each timing a constant ahead
    of it, moved by half the landing's change. A later touch-down would give the largest margin, yet the choice is
    the largest among the nominal and sooner timings (a stance held longer with its ZMP outside only lets the fall
    grow), and of the landings within a millimetre of that margin the nearest to the nominal one."""
    adjust = StepAdjustment(sole=SOLE, adapt_timing=True)
    halfplanes = (np.array([[1.0, 0.0]]), np.array([0.0]))
    nominal = np.array([0.3, -0.2])
    moves = np.array([[-0.02, 0.0], [-0.02, 0.05], [-0.018, 0.0], [-0.01, 0.0], [0.0, 0.0], [0.01, 0.0]])
    candidates = nominal + moves
    time_left = np.array([0.3, 0.2, 0.4])  # nominal, sooner, later
    change = time_left - time_left[0]
    ahead = np.array([0.05, 0.03, 0.012])  # the ZMP's x with the nominal landing under each timing (m)
    zmp = np.zeros((3, 4, 2))
    zmp[:, :, 0] = ahead[:, None]
    gain = np.full((3, 4), 0.5)
    # The margins, -(ahead_d + 0.5 dx): at best -0.04 (nominal), -0.02 (sooner), -0.002 (later); all short of 5 mm.
    d, landing, margin, enough = choose_step(
        adjust, candidates, tuple(nominal), zmp, gain, halfplanes, tuple(nominal), time_left, change
    )
    nearer = nominal + moves[2]  # 0.018 m back
    assert not enough
    assert d == 1, f"timing {d} (change {change[d]:+.1f} s): not the sooner one, the best no later than planned"
    # -0.02 at 0.02 m back, -0.021 at 0.018 m back: within a millimetre, the nearer landing.
    assert tuple(landing) == pytest.approx(tuple(nearer), abs=1e-12)
    assert margin == pytest.approx(-(ahead[1] + 0.5 * -0.018), abs=1e-12)
    # The later timing alone beside the nominal one: still the nominal timing (margin -0.04, the same nearer
    # landing within its millimetre).
    keep = [0, 2]
    d, landing, margin, enough = choose_step(
        adjust, candidates, tuple(nominal), zmp[keep], gain[keep], halfplanes, tuple(nominal), time_left[keep],
        change[keep],
    )  # fmt: skip
    assert (d, enough) == (0, False) and tuple(landing) == pytest.approx(tuple(nearer), abs=1e-12)


def test_candidate_timings_stay_within_the_limits():
    adjust = StepAdjustment(SOLE, SteppingLimits(min_single_support=0.4), adapt_timing=True, durations=4)
    assert single_support_options(adjust, 0.7) == pytest.approx((0.4, 0.5, 0.6))
    assert single_support_options(adjust, 0.4) is None
    # 0.35 s into a 0.7 s single support: touch-down no sooner than 0.2 s from now (nor a 0.4 s single support).
    assert remainder_options(adjust, 0.35, 0.35) == pytest.approx((0.2, 0.25, 0.3))
    assert remainder_options(adjust, 0.1, 0.6) == pytest.approx((0.3, 0.4, 0.5))
    assert remainder_options(adjust, 0.55, 0.15) is None  # already within the last 0.2 s


def test_candidate_operators_of_double_support_starts_are_built_ahead():
    config = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=TIMING
    )
    planner = OnlinePlanner(config, straight_walk(config, 6, 0.1))
    planner.start(0.0)
    for layout in planner._layout_at.values():
        if layout.kinds[1] == "single":
            assert layout._variants, "the candidate timings of the step after each double-support start"


def test_the_auto_connection_keeps_its_uniform_timing():
    config = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="auto", sole=SOLE, feedback="measured", step_adjustment=TIMING
    )
    planner = OnlinePlanner(config, straight_walk(config, 8, 0.1))
    planner.start(0.0)
    t = planner.phase_start(5) + 0.25
    for u in np.arange(0.0, t, DT):
        planner.sample(float(u))
    s = planner.sample(t)
    planner.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, -0.25]))
    planner.replan_now(t)
    assert planner.step_adjustments and planner.timeline.uniform


@pytest.mark.parametrize(
    ("options", "match"),
    [({"durations": 1}, "durations"), ({"limits": SteppingLimits}, "limits"), ({"time_cost": -1.0}, "time_cost"),
     ({"adapt_timing": 1}, "adapt_timing"), ({"required_margin": -0.1}, "required_margin")],
)  # fmt: skip
def test_bad_timing_settings_are_refused_naming_the_key(options, match):
    with pytest.raises(ValueError, match=f"step_adjustment.{match}"):
        StepAdjustment(sole=SOLE, **options)


# ----- per-call overrides and on_failure="keep" --------------------------------------------------------------------
def _walked(config: PlannerConfig) -> tuple[OnlinePlanner, float]:
    """The planner walked (observing its own plan) to 35 % into step 3's single support, and that instant (s)."""
    planner = OnlinePlanner(config, straight_walk(config, 8, 0.1))
    planner.start(0.0)
    t = planner.phase_start(5) + 0.35 * 0.7
    for u in np.arange(0.0, t, DT):
        s = planner.sample(float(u))
        planner.observe(float(u), s.cog[:2], s.cog_vel[:2])
    return planner, t


def test_replan_now_overrides_feedback_and_step_adjustment_for_one_call():
    config = PlannerConfig(timing=Timing(0.7, 0.1), connection="quasi-real-time")  # planned, no adjustment
    planner, t = _walked(config)
    s = planner.sample(t)
    pushed = s.cog_vel[:2] + np.array([0.0, -0.25])
    planner.observe(t, s.cog[:2], pushed)
    planner.replan_now(t)  # the config's: from the plan itself, the observation ignored
    assert planner.sample(t).cog_vel[:2] == pytest.approx(s.cog_vel[:2], abs=1e-12)
    planner.replan_now(t, feedback="measured", step_adjustment=TIMING)
    assert planner.sample(t).cog_vel[:2] == pytest.approx(pushed, abs=1e-12), "from the measured state"
    assert planner.step_adjustment_count == 1 and not planner.step_adjustments[-1].emergency
    assert planner.config.step_adjustment is None and planner.timeline.duration(5) < 0.7
    # The other way round: a measured, adjusting planner told to do neither for one replan.
    measured = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=TIMING
    )
    other, t = _walked(measured)
    s = other.sample(t)
    other.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, -0.25]))
    other.replan_now(t, feedback="planned", step_adjustment=False)
    assert other.sample(t).cog_vel[:2] == pytest.approx(s.cog_vel[:2], abs=1e-12)
    assert other.step_adjustment_count == 0
    with pytest.raises(ValueError, match="feedback must be one of"):
        other.replan_now(t, feedback="estimated")
    with pytest.raises(ValueError, match="step_adjustment must be"):
        other.replan_now(t, step_adjustment=True)


def test_on_failure_keep_keeps_the_walk_as_planned():
    keep = StepAdjustment(sole=SOLE, on_failure="keep")
    config = PlannerConfig(
        timing=Timing(0.7, 0.1), connection="quasi-real-time", feedback="measured", step_adjustment=keep
    )
    planner, t = _walked(config)
    prints = planner.footprints(10)
    timeline = planner.timeline
    s = planner.sample(t)
    planner.observe(t, s.cog[:2], s.cog_vel[:2] + np.array([0.0, 0.6]))  # outward: no step can catch it
    planner.replan_now(t)
    decision = planner.step_adjustments[-1]
    assert decision.emergency and "kept as planned" in decision.reason
    assert decision.landing == decision.nominal
    assert planner.footprints(10) == prints and planner.timeline is timeline and planner.n_steps == 9
    assert planner.sample(t).cog_vel[:2] == pytest.approx(s.cog_vel[:2], abs=1e-12), "from the planned state"
