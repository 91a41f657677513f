"""The pendulum-level closed loop against independent truth: the pendulum's own closed-form responses, the
capturability bounds, the sole's geometry and the open-loop rollout of the same walk."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pendulum_walk import CONFIG, MASS, PUSHED_STEP, SOLE, STRIDES, ZC, W

from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.support import SUPPORT_CODES, signed_margin, support_polygon
from rtgait.core.laws.capturability import max_capturable_impulse
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.pendulum.loop import run_pendulum_loop
from rtgait.core.pendulum.plant import DEFAULT_MAX_LEAN
from rtgait.core.planner.levels import CONTROLLER_LEVELS, DEFAULT_REPLAN_DCM_ERROR, level_config
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push
from rtgait.scenario.loading import load_scenario

DT = 0.005


def run(controller: str, pushes=(), dt: float = DT, **options):
    return run_pendulum_loop(CONFIG, STRIDES, SOLE, controller=controller, mass=MASS, dt=dt, pushes=pushes, **options)


def mid_single_support() -> tuple[float, np.ndarray, np.ndarray]:
    """Middle of the pushed step's single support (s), the plan's DCM there and the stance ankle (m), from the
    planner alone."""
    planner = OnlinePlanner(CONFIG, STRIDES)
    planner.start(0.0)
    t_mid = planner.phase_start(2 * PUSHED_STEP - 1) + 0.5 * CONFIG.timing.single_support
    for t in np.arange(0.0, t_mid, 0.05):  # the planner must be sampled at least once per step
        planner.sample(float(t))
    sample = planner.sample(t_mid)
    assert sample.support == "left"
    return t_mid, sample.dcm.copy(), planner.walk.footprint(PUSHED_STEP).position


def forward_push(t_mid: float, impulse: float) -> Push:
    """A 0.1 s push forward (+x) of ``impulse`` N s, centred on ``t_mid``: centred, it moves the DCM like the
    impulse at ``t_mid`` to within 0.5 % (sinh(w T/2) / (w T/2))."""
    return Push(t_mid - 0.05, 0.1, (impulse / 0.1, 0.0))


def contact_polygon(footprints, phase: int) -> np.ndarray:
    """The support polygon of phase ``phase`` from the footprints (independent of the loop's cache)."""
    if phase % 2 == 1 and phase < 2 * (len(footprints) - 2):  # single support of step (phase + 1) / 2
        return support_polygon([footprints[(phase + 1) // 2]], SOLE)
    i = min(phase // 2, len(footprints) - 2)
    return support_polygon([footprints[i], footprints[i + 1]], SOLE)


# ----- (a) open loop on the unpushed walk: the same pendulum as the plan ------------------------------------------
@pytest.fixture(scope="module")
def fig8_runs():
    scenario = load_scenario("fig8")
    common = dict(mass=MASS, dt=0.001, changes=scenario.changes)
    config, strides, sole = scenario.planner_config(), scenario.strides(), scenario.sole
    return scenario, {c: run_pendulum_loop(config, strides, sole, controller=c, **common) for c in CONTROLLER_LEVELS}


def test_open_loop_reproduces_the_plan_until_the_pendulum_diverges(fig8_runs):
    _, runs = fig8_runs
    result = runs["open-loop"]
    # Started on the plan and commanded its ZMP, the plant is the plan's own pendulum: the planner's closed form and
    # the plant's exact integration agree to well below a micrometre while round-off has not grown yet.
    early = result.times < 6.0
    assert result.cog_tracking_error[early].max() < 1e-6
    assert result.zmp_tracking_error_rms == 0.0
    # Then the point mass's instability shows: the DCM deviation grows exactly like e^{w t} (the unstable mode of
    # the pendulum, from a seed at round-off level), and fig8 (12.7 s) is long enough for it to fall, unpushed.
    deviation = np.hypot(*(result.dcm - result.dcm_planned).T)
    growing = (deviation > 1e-5) & (deviation < 1e-2)
    assert growing.sum() > 100
    rate = np.polyfit(result.times[growing], np.log(deviation[growing]), 1)[0]
    assert rate == pytest.approx(W, rel=1e-3)
    seed = deviation[growing] * np.exp(-W * result.times[growing])
    assert seed.max() < 1e-13  # what grew was round-off, not a modelling error
    assert result.fell and result.fall_time > 8.0


def test_feedback_walks_fig8_on_the_plan_to_rest(fig8_runs):
    _, runs = fig8_runs
    for controller in ("stabilized", "adaptive"):
        result = runs[controller]
        assert not result.fell and result.ended_at_rest
        assert result.steps_completed == result.steps_planned == 11
        assert result.step_adjustment_count == 0
        assert result.cog_tracking_error.max() < 1e-6
        assert result.zmp_tracking_error_rms < 1e-9  # nothing to correct but round-off
        assert result.tick_time < 1e-3  # real-time capable at 1 kHz with a wide margin (about 10-20 us here)


def test_the_loop_walks_the_footprints_and_changes_of_the_rollout(fig8_runs):
    scenario, runs = fig8_runs
    planner = OnlinePlanner(scenario.planner_config(), scenario.strides())
    walked = rollout(planner, scenario.dt, scenario.sole, scenario.changes)
    for controller in CONTROLLER_LEVELS:
        footprints = runs[controller].footprints
        assert len(footprints) == len(walked.footprints)
        for ours, theirs in zip(footprints, walked.footprints, strict=True):
            assert (ours.x, ours.y, ours.yaw, ours.side) == pytest.approx((theirs.x, theirs.y, theirs.yaw, theirs.side))


def test_short_walk_open_loop_ends_at_rest():
    result = run("open-loop", dt=0.002)
    assert not result.fell and result.ended_at_rest
    assert result.steps_completed == result.steps_planned == 5
    assert result.cog_tracking_error.max() < 1e-4


# ----- (b) capturability: inside the one-step bound, and far beyond any bound ----------------------------------
def test_push_inside_one_step_bound_is_recovered_by_stepping():
    t_mid, dcm, ankle = mid_single_support()
    adjust = StepAdjustment(sole=SOLE)  # the adaptive level's default limits
    bound = max_capturable_impulse(
        dcm - ankle, (1.0, 0.0), mass=MASS, omega=W, r_max=SOLE.front, l_max=adjust.limits.max_length,
        step_time=CONFIG.timing.step_period, remaining=0.5 * CONFIG.timing.single_support,
        min_remaining=adjust.limits.min_time_to_touchdown, steps=1,
    )  # fmt: skip
    assert 30.0 < bound < 50.0  # N s: a DCM shift of 0.15-0.25 m for 57 kg
    push = forward_push(t_mid, 0.8 * bound)
    adaptive = run("adaptive", [push])
    assert not adaptive.fell and adaptive.ended_at_rest
    assert adaptive.step_adjustment_count >= 1
    moved = adaptive.step_adjustments[0]
    assert moved.step in (PUSHED_STEP, PUSHED_STEP + 1)
    assert moved.landing[0] > moved.nominal[0] + 0.05  # it stepped forward, with the push
    # The ankle alone cannot: the same push topples the stabilized pendulum, whose steps stay where planned.
    stabilized = run("stabilized", [push])
    assert stabilized.fell and stabilized.step_adjustment_count == 0


def test_push_beyond_every_capture_bound_topples_every_controller():
    t_mid, dcm, ankle = mid_single_support()
    adjust = StepAdjustment(sole=SOLE)
    # The most generous reading of the limits: the ZMP anywhere within the sole's farthest corner, a step anywhere
    # within the stride box's farthest corner, no double support, and as many steps as wanted; the planner's swing
    # cannot land before its planned time, nor steps come faster than T_s + T_dbl.
    generous = max_capturable_impulse(
        dcm - ankle, (1.0, 0.0), mass=MASS, omega=W, r_max=math.hypot(SOLE.front, SOLE.inner),
        l_max=math.hypot(adjust.limits.max_length, adjust.limits.max_width), step_time=CONFIG.timing.step_period,
        remaining=0.5 * CONFIG.timing.single_support, steps=math.inf,
    )  # fmt: skip
    push = forward_push(t_mid, 1.5 * generous)
    for controller in CONTROLLER_LEVELS:
        result = run(controller, [push])
        assert result.fell and not result.ended_at_rest, controller
        assert result.fall_time < t_mid + 2.0
        assert result.steps_completed < result.steps_planned


# ----- (c), (d): what each level adds ---------------------------------------------------------------------------
def test_open_loop_falls_from_a_moderate_push_that_adaptive_survives():
    t_mid, _, _ = mid_single_support()
    push = forward_push(t_mid, 12.0)  # a DCM shift of 60 mm: beyond the replan threshold
    assert 12.0 / (MASS * W) > DEFAULT_REPLAN_DCM_ERROR
    assert not run("open-loop").fell  # unpushed it walks to the end (test_short_walk_open_loop_ends_at_rest)
    open_loop = run("open-loop", [push])
    assert open_loop.fell and open_loop.steps_completed < 5
    adaptive = run("adaptive", [push])
    assert not adaptive.fell and adaptive.ended_at_rest
    assert any(plan.reason == "dcm-error" for plan in adaptive.plans)


def test_stabilized_recovers_a_small_push_that_open_loop_cannot():
    # Physics: without feedback, any DCM error grows as e^{w t} (xi' = w (xi - p) with p fixed by the plan), so
    # however small the push the open-loop pendulum falls before the walk ends; DCM feedback makes the error decay.
    t_mid, _, _ = mid_single_support()
    push = Push(t_mid - 0.05, 0.1, (0.0, -30.0))  # 3 N s sideways, away from the swing foot: 15 mm of DCM
    open_loop = run("open-loop", [push])
    assert open_loop.fell
    stabilized = run("stabilized", [push])
    assert not stabilized.fell and stabilized.ended_at_rest
    assert stabilized.steps_completed == stabilized.steps_planned == 5
    assert stabilized.step_adjustment_count == 0
    error = np.hypot(*(stabilized.dcm - stabilized.dcm_planned).T)
    assert error.max() == pytest.approx(3.0 / (MASS * W), rel=0.1)  # the push's DCM shift, then it decays
    assert error[-1] < 1e-3


# ----- (e) the push's impulse, and the plant's physics within the loop ------------------------------------------
def test_delivered_impulse_equals_force_times_duration():
    # Off the tick grid on purpose. Open loop, the real ZMP is the same with and without the push (the plan's,
    # inside the polygon), so the difference of the two runs is the pendulum's response to the force pulse alone:
    # e'' = w^2 e + F/m on [ts, te], whose closed form is below.
    ts, duration, force = 2.0123, 0.0977, np.array([40.0, -25.0])
    te = ts + duration
    pushed = run("open-loop", [Push(ts, duration, tuple(force))])
    plain = run("open-loop")
    n = pushed.ticks  # the pushed run ends earlier: it falls
    window = (pushed.times > ts) & (pushed.times < te + 0.3)
    assert window.sum() > 50
    assert not (pushed.saturated[window].any() or plain.saturated[:n][window].any())
    t = pushed.times[window][:, None]
    k = force / MASS
    inside = t < te
    shape = np.where(inside, np.cosh(W * (t - ts)) - 1.0, np.cosh(W * (t - ts)) - np.cosh(W * (t - te)))
    rate = np.where(inside, np.sinh(W * (t - ts)), np.sinh(W * (t - ts)) - np.sinh(W * (t - te)))
    offset = pushed.cog[window] - plain.cog[:n][window]
    np.testing.assert_allclose(offset, k / W**2 * shape, atol=1e-10, rtol=0)
    np.testing.assert_allclose(pushed.cog_vel[window] - plain.cog_vel[:n][window], k / W * rate, atol=1e-10, rtol=0)
    (entry,) = pushed.summary()["pushes"]
    assert entry["impulse"] == pytest.approx([*(force * duration), 0.0], rel=1e-12)
    assert entry["impulse_norm"] == pytest.approx(float(np.hypot(*force)) * duration, rel=1e-12)


def test_the_zmp_stays_on_the_stance_sole_and_saturates_on_its_edge():
    t_mid, _, _ = mid_single_support()
    result = run("stabilized", [forward_push(t_mid, 30.0)])
    stance = result.footprints[PUSHED_STEP]
    phase = result.phase == 2 * PUSHED_STEP - 1
    real = result.zmp_real[phase]
    finite = np.isfinite(real[:, 0])
    real = real[finite]
    # The HRP-2-like sole around an unturned left foot: x in [-0.10, +0.13], y in [-0.07, +0.07] of the ankle.
    assert np.all(real[:, 0] >= stance.x - SOLE.back - 1e-12) and np.all(real[:, 0] <= stance.x + SOLE.front + 1e-12)
    assert np.all(np.abs(real[:, 1] - stance.y) <= SOLE.inner + 1e-12)
    saturated = result.saturated[phase][finite]
    assert saturated.sum() > 10  # the push saturated the feedback law: the ZMP sat on the sole's front edge
    np.testing.assert_allclose(real[saturated, 0], stance.x + SOLE.front, atol=1e-12)
    np.testing.assert_array_equal(real, result.zmp_command[phase][finite])  # the feedback's command is feasible


def test_fell_means_the_com_beyond_the_fall_distance_from_the_support_polygon():
    t_mid, _, _ = mid_single_support()
    result = run("stabilized", [forward_push(t_mid, 60.0)])
    assert result.fell and result.fall_time == result.times[-1]
    limit = ZC * math.tan(DEFAULT_MAX_LEAN)
    distances = [
        -float(signed_margin(result.cog[i], contact_polygon(result.footprints, int(result.phase[i])))[0])
        for i in (-2, -1)
    ]
    assert distances[0] <= limit < distances[1]
    assert math.isnan(result.zmp_command[-1, 0])


# ----- configuration and bookkeeping ------------------------------------------------------------------------------
def test_level_config_sets_only_what_the_level_adds():
    base = dataclasses.replace(CONFIG, horizon_steps=4, feedback="measured", replan_dcm_error=0.01)
    for level in ("open-loop", "stabilized"):
        config = level_config(base, level, SOLE)
        assert (config.feedback, config.replan_dcm_error, config.step_adjustment) == ("planned", None, None)
        assert config.horizon_steps == 4
    adaptive = level_config(base, "adaptive", SOLE)
    assert adaptive.feedback == "measured" and adaptive.replan_dcm_error == DEFAULT_REPLAN_DCM_ERROR
    assert adaptive.step_adjustment == StepAdjustment(sole=SOLE) and adaptive.horizon_steps == 4
    custom = StepAdjustment(SOLE, SteppingLimits(max_length=0.2))
    assert level_config(base, "adaptive", SOLE, step_adjustment=custom).step_adjustment is custom
    with pytest.raises(ValueError, match="controller"):
        level_config(base, "magic", SOLE)  # type: ignore[arg-type]


def test_arrays_and_summary_are_consistent():
    result = run("adaptive", dt=0.004)
    k = result.ticks
    for name in ("cog_planned", "dcm_planned", "zmp_planned", "zmp_reference", "zmp_command", "zmp_real", "cog",
                 "cog_vel", "dcm"):  # fmt: skip
        assert getattr(result, name).shape == (k, 2), name
    np.testing.assert_allclose(result.times, np.arange(k) * 0.004)
    assert result.times[-1] <= result.walk_end + 0.5 + 1e-9 < result.times[-1] + 0.004
    np.testing.assert_allclose(result.dcm, result.cog + result.cog_vel / W)
    assert set(np.unique(result.support)) == set(SUPPORT_CODES.values())
    summary = result.summary()
    assert summary["model"] == "lipm" and summary["controller"] == "adaptive"
    assert summary["fell"] is False and summary["fall_time"] is None and summary["ended_at_rest"] is True
    assert summary["steps_planned"] == 5 and summary["step_adjustments"] == 0 and summary["pushes"] == []
    assert summary["real_time_factor"] > 1.0


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="controller"):
        run("magic")
    with pytest.raises(ValueError, match="dt"):
        run("stabilized", dt=0.2)  # longer than the 0.1 s double support
    with pytest.raises(ValueError, match="duration"):
        run_pendulum_loop(CONFIG, None, SOLE, controller="stabilized")  # a walk by command has no end


def test_a_walk_by_command_runs_for_the_duration_given():
    result = run_pendulum_loop(CONFIG, None, SOLE, controller="adaptive", dt=DT, duration=3.0)
    assert not result.fell
    assert result.times[-1] == pytest.approx(3.0)
