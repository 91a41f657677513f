"""A touch-down on a tilted foothold re-anchors it on its surface: the plane's height where the foot landed.

On a ramp a foot measured ``d`` short of its foothold stands ``d tan(angle)`` lower than the foothold: kept at the
planned height, its re-anchored footprint (and the IK's target for the foot standing on it) hangs above the ramp
(or presses into it, landing long), and the foot is lifted off the ramp it touched."""

from __future__ import annotations

import math

import pytest

from rtgait.core.geometry.foot_tilt import surface_rise
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, Timing
from rtgait.core.planner.online import OnlinePlanner, PlannerConfig

SOLE = SoleRect(front=0.105, back=0.105, inner=0.065, outer=0.065)
CONFIG = PlannerConfig(
    cog_height=0.84, timing=Timing(0.7, 0.1, start=0.6, end=0.6, settle=0.8), step_width=0.2,
    connection="quasi-real-time",
)  # fmt: skip
RAMP = 0.2  # rad: up a ramp along +x, the footholds pitched toes up (pitch -RAMP)
RISE = 0.1 * math.tan(RAMP)  # m per 0.1 m step


def swinging_planner(strides) -> tuple[OnlinePlanner, float]:
    """A planner sampled up to 5 ms before its first swing's end; returns it and that time (s)."""
    planner = OnlinePlanner(CONFIG, strides)
    planner.start(0.0)
    t = planner.phase_start(1) + planner.timeline.duration(1) - 0.005
    for k in range(round(t / 0.01) + 1):
        planner.sample_values(min(k * 0.01, t))
    return planner, t


@pytest.mark.parametrize(("dx", "dy"), [(-0.03, 0.01), (0.02, -0.01)])
def test_a_touch_down_on_a_ramp_foothold_takes_the_ramp_s_height_where_it_landed(dx, dy):
    planner, t = swinging_planner([Stride(0.1, CONFIG.step_width, 0.0, RISE, -RAMP)] * 3)
    planned, after = planner.footprints()[2:4]
    assert planner.touchdown(t, planned.side, planned.x + dx, planned.y + dy, planned.yaw) == 2
    anchored = planner.footprints()[2]
    assert (anchored.x, anchored.y) == pytest.approx((planned.x + dx, planned.y + dy), abs=1e-12)
    assert anchored.z == pytest.approx(planned.z + dx * math.tan(RAMP), abs=1e-12)  # across the ramp: no change
    assert (anchored.pitch, anchored.roll) == (planned.pitch, planned.roll)
    kept = planner.footprints()[3]  # on sloped ground the later footholds stay where they were placed
    assert (kept.x, kept.y, kept.z) == pytest.approx((after.x, after.y, after.z), abs=1e-12)


def test_a_touch_down_on_a_raised_level_foothold_keeps_its_height():
    planner, t = swinging_planner([Stride(0.1, CONFIG.step_width, 0.0, 0.05, 0.0)] * 3)  # treads: level, raised
    planned = planner.footprints()[2]
    planner.touchdown(t, planned.side, planned.x - 0.03, planned.y, planned.yaw)
    assert planner.footprints()[2].z == planned.z


def test_surface_rise_follows_the_foothold_s_plane():
    up = Footstep(0.0, 0.0, 0.0, "left", 0.1, -RAMP, 0.0)  # toes up: the ramp rises along +x
    assert surface_rise(up, 0.05, 0.3) == pytest.approx(0.05 * math.tan(RAMP))
    turned = Footstep(0.0, 0.0, math.pi / 2, "left", 0.1, -RAMP, 0.0)  # heading +y: it rises along +y
    assert surface_rise(turned, 0.3, 0.05) == pytest.approx(0.05 * math.tan(RAMP))
    rolled = Footstep(0.0, 0.0, 0.0, "left", 0.1, 0.0, RAMP)  # rolled, its left side up: it rises along +y
    assert surface_rise(rolled, 0.0, 0.05) == pytest.approx(0.05 * math.tan(RAMP))
    assert surface_rise(Footstep(0.0, 0.0, 0.3, "left", 0.1), 0.2, 0.2) == 0.0  # a tread: level
