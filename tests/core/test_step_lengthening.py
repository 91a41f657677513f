"""Step timing adaptation that holds a stance longer (``StepAdjustment.max_single_support``).

A push toward the stance foot's outside moves the capture point away from where the swing foot may land (the feet
never cross), so no landing catches it; what can is the ankle, the centre of pressure at the sole's outer edge,
given time. Independent truths: the pendulum plant integrated in closed form (:mod:`rtgait.core.pendulum.loop`) and
the stance sole's own capturability bound (the DCM must not pass the outer edge, ``J < m w (edge - dcm)``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pendulum_walk import CONFIG, MASS, PUSHED_STEP, SOLE, STRIDES, W

from rtgait.core.laws.step_timing import remainder_options, single_support_options
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.pendulum.loop import run_pendulum_loop
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push

LANDING = StepAdjustment(sole=SOLE)
SHORTER = StepAdjustment(sole=SOLE, adapt_timing=True)
LONGER = StepAdjustment(SOLE, SteppingLimits(max_single_support=1.4), adapt_timing=True)


def _loop(adjust: StepAdjustment, impulse: float, dt: float):
    planner = OnlinePlanner(CONFIG, STRIDES)
    planner.start(0.0)
    t_mid = planner.phase_start(2 * PUSHED_STEP - 1) + 0.5 * CONFIG.timing.single_support
    push = Push(t_mid - 0.05, 0.1, (0.0, impulse / 0.1))  # +y: the left stance foot's outside
    return run_pendulum_loop(
        CONFIG, STRIDES, SOLE, controller="adaptive", mass=MASS, dt=dt, pushes=[push], step_adjustment=adjust
    )


def _ankle_bound() -> float:
    """The largest outward impulse (N s) after which the planned DCM at mid single support stays inside the stance
    sole's outer edge: ``m w (y_edge - y_dcm)``, the pendulum's own plan sampled there."""
    planner = OnlinePlanner(CONFIG, STRIDES)
    planner.start(0.0)
    t_mid = planner.phase_start(2 * PUSHED_STEP - 1) + 0.5 * CONFIG.timing.single_support
    for t in np.arange(0.0, t_mid, 0.05):
        planner.sample(float(t))
    dcm = planner.sample(t_mid).dcm
    stance = planner.walk.footprint(PUSHED_STEP)
    assert stance.side == "left" and stance.yaw == 0.0
    return MASS * W * (stance.y + SOLE.outer - dcm[1])


@pytest.mark.parametrize("dt", [0.005, 0.0025])
def test_an_outward_push_no_landing_catches_is_caught_by_holding_the_stance_longer(dt):
    bound = _ankle_bound()
    impulse = 0.96 * bound  # inside the sole's bound, beyond what the nominal timing leaves the ankle
    landing_only, shorter_only = _loop(LANDING, impulse, dt), _loop(SHORTER, impulse, dt)
    assert landing_only.fell and shorter_only.fell

    held = _loop(LONGER, impulse, dt)
    assert not held.fell and held.ended_at_rest
    longer = [d for d in held.step_adjustments if d.single_support > d.nominal_single_support + 1e-6]
    assert longer and longer[0].step == PUSHED_STEP and "later" in longer[0].reason
    # The pushed step's single support as the plant lived it is the one chosen last, within the limit.
    chosen = [d for d in held.step_adjustments if d.step == PUSHED_STEP][-1].single_support
    lived = np.count_nonzero(held.phase == 2 * PUSHED_STEP - 1) * dt
    assert lived == pytest.approx(chosen, abs=dt + 1e-9)
    assert CONFIG.timing.single_support + 0.05 < chosen <= LONGER.limits.max_single_support + 1e-9


def test_no_timing_catches_a_push_beyond_the_soles_bound():
    assert _loop(LONGER, 1.1 * _ankle_bound(), 0.005).fell


def test_candidate_timings_reach_the_longest_single_support():
    limits = SteppingLimits(min_single_support=0.4, max_single_support=1.0)
    adjust = StepAdjustment(SOLE, limits, adapt_timing=True, durations=4)
    assert single_support_options(adjust, 0.7) == pytest.approx((0.4, 0.5, 0.6, 0.8, 0.9, 1.0))
    assert single_support_options(adjust, 1.0) == pytest.approx((0.4, 0.6, 0.8))  # nothing longer
    assert single_support_options(adjust, 0.4) == pytest.approx((0.6, 0.8, 1.0))  # nothing shorter
    # 0.35 s into a 0.7 s single support: no sooner than 0.2 s from now, no later than 1.0 s from its start.
    assert remainder_options(adjust, 0.35, 0.35) == pytest.approx((0.2, 0.25, 0.3, 0.45, 0.55, 0.65))
    assert remainder_options(adjust, 0.55, 0.15) == pytest.approx((0.25, 0.35, 0.45))
    assert single_support_options(StepAdjustment(sole=SOLE, adapt_timing=True), 0.7) == pytest.approx((0.4, 0.5, 0.6))


@pytest.mark.parametrize("value", [0.3, 0.4, 11.0, math.nan, True, "1"])
def test_a_longest_single_support_not_above_the_shortest_is_refused(value):
    with pytest.raises(ValueError, match=r"stepping\.max_single_support"):
        SteppingLimits(max_single_support=value)


def test_the_stepping_table_carries_the_longest_single_support():
    limits = SteppingLimits.from_table({"min_single_support": 0.5, "max_single_support": 1.2})
    assert limits.adjustment(SOLE).limits.max_single_support == 1.2
    assert SteppingLimits.from_table({}).adjustment(SOLE).limits.max_single_support is None
