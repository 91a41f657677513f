"""The measurement taken into the feet's frame off the flat floor (rtgait.control.foot_frame).

A walk up a ramp (footholds 2 cm higher every 0.1 m, pitched with it) and the same walk on the flat floor. The
estimator has both soles ``OFFSET`` behind the IK's targets (a foot that settled back after its landing, or an
estimated frame drifting from the plan's); the swing foot touches down on time ``SHORT`` behind its target as seen
from the standing foot. Up the ramp the landing is re-anchored ``SHORT`` behind, where it touched (re-anchored at its
estimated pose, the IK, which keeps the targets' difference between the feet, would move it ``OFFSET`` further back);
on the flat floor the measurement is kept as it is."""

from __future__ import annotations

import math

import pytest

from rtgait.control.controller import ControllerOptions, make_controller
from rtgait.control.foot_control import split_zmp
from rtgait.control.foot_frame import feet_offset, translated
from rtgait.core.geometry.footsteps import Stride
from rtgait.estimation.state import Landing, Measurement
from tests.synthetic_robot import CONFIG, DT, INFO, SOLE, WEIGHT, foot_state

RAMP = 0.2  # rad: up a ramp along +x, the footholds pitched toes up
OFFSET = 0.006  # m: both soles estimated behind the IK's targets
SHORT = 0.004  # m: the swing foot touches this far behind its target, seen from the standing foot


def measured(t, values, support, shift=0.0, landings=()) -> Measurement:
    """The robot on the plan, every position estimated ``shift`` (m) along x from it."""
    left, right = values.left_foot, values.right_foot
    split = split_zmp((values.zmp_x, values.zmp_y), left, right, SOLE, support)
    fl = split.left_ratio * WEIGHT
    m = Measurement(
        t, values.cog, (values.cog_vx, values.cog_vy, values.cog_vz), (values.dcm_x, values.dcm_y),
        (values.zmp_x, values.zmp_y), WEIGHT,
        foot_state(left, fl, split.left_cop, support != "right"),
        foot_state(right, WEIGHT - fl, split.right_cop, support != "left"), tuple(landings), 0,
    )  # fmt: skip
    return translated(m, shift, 0.0)


def touch_down(strides):
    """Walk on the plan to 5 ms before the first swing's end, then land it as the module docstring says. Returns the
    planned and the re-anchored footprint F[2], and the touch-down tick's targets."""
    options = ControllerOptions(measurement_filter=0.0, dcm_bias=False, foot=None)
    ctl = make_controller("adaptive", CONFIG, strides, SOLE, INFO, dt=DT, options=options)
    ctl.start(0.0)
    planner = ctl.planner
    side = planner.footprints()[0].side  # F[0] lifts off first and lands on F[2]
    end = planner.phase_start(1) + planner.timeline.duration(1)
    t = 0.0
    while t < end - 0.005:
        values, support, _ = planner.sample_values(t)
        ctl.tick(t, measured(t, values, support))
        t += DT
    planned = planner.footprints()[2]
    landing = Landing(t, side, planned.x - SHORT, planned.y, planned.z, planned.yaw, 0.0, 0.0, 80.0)  # true pose
    values, support, _ = planner.sample_values(t)
    out = ctl.tick(t, measured(t, values, support, -OFFSET, [landing]))  # the landing too estimated OFFSET back
    assert [e.detail for e in out.events if e.kind == "landing"] == ["on time"]
    assert any(e.kind == "touchdown" for e in out.events)
    return planned, planner.footprints()[2]


def test_up_a_ramp_a_landing_is_re_anchored_where_it_touched_seen_from_the_standing_foot():
    planned, anchored = touch_down([Stride(0.1, CONFIG.step_width, 0.0, 0.1 * math.tan(RAMP), -RAMP)] * 3)
    assert anchored.x == pytest.approx(planned.x - SHORT, abs=1e-9)
    assert anchored.y == pytest.approx(planned.y, abs=1e-9)
    assert anchored.z == pytest.approx(planned.z - SHORT * math.tan(RAMP), abs=1e-9)  # on the ramp there


def test_on_the_flat_floor_a_landing_is_re_anchored_where_it_was_estimated():
    planned, anchored = touch_down([Stride(0.1, CONFIG.step_width, 0.0)] * 3)
    assert anchored.x == pytest.approx(planned.x - SHORT - OFFSET, abs=1e-9)


def test_the_offset_follows_the_load_from_one_foot_to_the_other():
    values_left, values_right = (0.1, 0.1, 0.0, 0.0), (0.3, -0.1, 0.0, 0.0)
    for share in (0.0, 0.25, 1.0):
        m = Measurement(
            0.0, (0.2, 0.0, 0.8), (0.0, 0.0, 0.0), (0.2, 0.0), (0.2, 0.0), WEIGHT,
            foot_state((0.09, 0.1, 0.0, 0.0), share * WEIGHT, (0.09, 0.1), share > 0.0),
            foot_state((0.33, -0.1, 0.0, 0.0), (1 - share) * WEIGHT, (0.33, -0.1), share < 1.0), (), 0,
        )  # fmt: skip
        dx, dy = feet_offset(m, values_left, values_right)
        assert (dx, dy) == pytest.approx((share * 0.01 + (1 - share) * -0.03, 0.0), abs=1e-12)
        moved = translated(m, dx, dy)
        assert moved.com[0] - m.com[0] == moved.zmp[0] - m.zmp[0] == pytest.approx(dx, abs=1e-15)
        assert moved.left.pose[0] - m.left.pose[0] == pytest.approx(dx, abs=1e-15)
        assert moved.com_vel == m.com_vel and moved.left.force == m.left.force
    unloaded = m._replace(left=m.left._replace(loaded=False), right=m.right._replace(loaded=False))
    assert feet_offset(unloaded, values_left, values_right) == (0.0, 0.0)
