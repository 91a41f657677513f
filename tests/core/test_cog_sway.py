"""The COG's sway toward the feet per timing (:func:`rtgait.core.lipm.sway.cog_sway`), against the planner.

The truth is the planner's own plan: stepping in place by velocity command, the largest lateral distance of its COG
from the midline between the feet over the steady steps, as a share of half the stance. Then what the pendulum
says without planning: the COG stays between the feet, and a longer phase lets it sway farther.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.core.analysis.rollout import rollout
from rtgait.core.geometry.footsteps import SoleRect, Timing
from rtgait.core.lipm.sway import cog_sway
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.planner.sample import SampleColumns

SOLE = SoleRect(0.1, 0.05, 0.03, 0.03)
DT = 0.002


def planned_sway(cog_height: float, single: float, double: float) -> float:
    """The planner's COG sway stepping in place (module docstring), over six steps once the start has died out
    (its trace decays as ``exp(-w t)``: after 3 s, below 1e-4 of the stance)."""
    config = PlannerConfig(cog_height=cog_height, timing=Timing(single, double), step_width=0.2)
    planner = OnlinePlanner(config, None)
    planner.set_velocity(0.0, 0.0, 0.0)
    period = single + double
    first = max(3, math.ceil(3.0 / period))
    plan = rollout(planner, DT, SOLE, duration=config.timing.start + (first + 7) * period)
    times = np.asarray(plan.times)
    cog_y = plan.values[:, SampleColumns.cog][:, 1]
    left_y = plan.values[:, SampleColumns.left_foot][:, 1]
    right_y = plan.values[:, SampleColumns.right_foot][:, 1]
    steady = (times >= config.timing.start + first * period) & (times <= config.timing.start + (first + 6) * period)
    middle, half = 0.5 * (left_y + right_y), 0.5 * np.abs(left_y - right_y)
    return float(np.max(np.abs(cog_y - middle)[steady]) / np.median(half[steady]))


@pytest.mark.parametrize(
    ("cog_height", "single", "double"),
    [(0.64, 0.7, 0.1), (0.64, 0.8, 1.5), (0.84, 0.8, 0.2), (0.84, 1.5, 0.2), (0.84, 0.6, 0.3), (0.5, 0.6, 0.6)],
)
def test_the_sway_is_the_planner_s(cog_height, single, double):
    w = math.sqrt(9.81 / cog_height)
    # The plan's samples are DT apart (its peak good to (w DT)^2 / 8, 1e-5 of the stance), and it looks three steps
    # ahead (horizon_steps), not forever: its end condition reaches back as exp(-w 3T), below 1e-4 in these cases.
    assert cog_sway(w, single, double) == pytest.approx(planned_sway(cog_height, single, double), abs=2e-5)


def test_the_cog_stays_between_the_feet_and_sways_farther_with_longer_phases():
    w = math.sqrt(9.81 / 0.64)
    doubles = [cog_sway(w, 0.8, double) for double in (0.0, 0.1, 0.5, 1.0, 1.5, 3.0)]
    singles = [cog_sway(w, single, 0.2) for single in (0.3, 0.6, 1.0, 1.5, 3.0)]
    for series in (doubles, singles):
        assert all(0.0 < value < 1.0 for value in series)
        assert series == sorted(series) and len(set(series)) == len(series)
    # Without double support the ZMP jumps from foot to foot, a square wave of half-period Ts: the bounded solution
    # is c = a (1 - cosh(w (t - Ts/2)) / cosh(w Ts/2)) on the foot at +a (0 at the jumps), largest mid-step.
    assert cog_sway(w, 0.8, 0.0) == pytest.approx(1.0 - 1.0 / math.cosh(w * 0.8 / 2.0), abs=1e-6)


@pytest.mark.parametrize(
    ("args", "message"),
    [((0.0, 0.8, 0.2), "w must be"), ((3.9, 0.0, 0.2), "single_support"), ((3.9, 0.8, -0.1), "double_support"),
     ((3.9, math.nan, 0.2), "single_support")],
)  # fmt: skip
def test_bad_timings_are_refused_naming_the_field(args, message):
    with pytest.raises(ValueError, match=message):
        cog_sway(*args)
