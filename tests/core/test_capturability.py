"""N-step capturability bounds (Koolen et al. 2012) and the largest survivable push, checked against the paper's
recurrence, the closed-form limit and brute-force simulation with the LIPM plant."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.support import support_polygon
from rtgait.core.laws.capturability import (
    capture_bound,
    capture_bound_limit,
    max_capturable_impulse,
    push_capture_bound,
    reach_along,
    steps_to_capture,
)
from rtgait.core.lipm.closed_form import GRAVITY
from rtgait.core.pendulum.plant import LipmPlant

ZC, MASS = 0.8, 60.0
W = math.sqrt(GRAVITY / ZC)
SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
SETTINGS = settings(max_examples=40, deadline=None)
params = st.fixed_dictionaries(
    {
        "r_max": st.floats(0.0, 0.2),
        "l_max": st.floats(0.01, 1.0),
        "step_time": st.floats(0.05, 1.5),
        "omega": st.floats(1.0, 10.0),
    }
)


# ----- the bounds -----------------------------------------------------------------------------------------
@SETTINGS
@given(params)
def test_bounds_follow_the_recurrence_increase_and_converge_to_the_closed_form_limit(p):
    r, length, a = p["r_max"], p["l_max"], math.exp(-p["omega"] * p["step_time"])
    recurrence = [r]  # d_0
    for _ in range(399):
        recurrence.append((recurrence[-1] + length - r) * a + r)  # the paper's recurrence
    bounds = capture_bound(np.arange(400), **p)
    np.testing.assert_allclose(bounds, recurrence, rtol=1e-12, atol=1e-15)
    for n in (0, 1, 7):
        assert capture_bound(n, **p) == pytest.approx(recurrence[n], rel=1e-12)
    increments = np.diff(bounds)
    assert np.all(increments >= 0.0)
    resolvable = length * a ** np.arange(1, 400) > 1e-12 * bounds[-1]  # d_N - d_{N-1} = l a^N above round-off
    assert np.all(increments[resolvable] > 0.0)
    # The limit is the recurrence's fixed point d = (d + l - r) a + r, i.e. d = r + l a / (1 - a).
    limit = r + length * a / (1.0 - a)
    assert limit == pytest.approx((limit + length - r) * a + r, rel=1e-12)
    assert capture_bound_limit(**p) == pytest.approx(limit, rel=1e-12)
    assert capture_bound(np.inf, **p) == pytest.approx(limit, rel=1e-12)
    assert np.all(bounds < limit * (1 + 1e-12))
    # d_inf - d_N = l a^{N+1} / (1 - a): geometric convergence at the rate a.
    np.testing.assert_allclose(limit - bounds[:20], length * a ** np.arange(1, 21) / (1 - a), rtol=1e-6, atol=1e-14)


def test_bounds_broadcast_and_validate():
    out = capture_bound([[0], [1], [2]], r_max=[0.05, 0.1], l_max=0.4, step_time=0.3, omega=W)
    assert out.shape == (3, 2)
    np.testing.assert_allclose(out[1], np.array([0.05, 0.1]) + 0.4 * math.exp(-W * 0.3))
    for bad in [dict(r_max=-0.1), dict(l_max=math.nan), dict(step_time=0.0), dict(omega=-1.0)]:
        kwargs = {"r_max": 0.1, "l_max": 0.4, "step_time": 0.3, "omega": W, **bad}
        with pytest.raises(ValueError, match=next(iter(bad))):
            capture_bound(1, **kwargs)
    for steps in (-1, 1.5, math.nan):
        with pytest.raises(ValueError, match="steps"):
            capture_bound(steps, r_max=0.1, l_max=0.4, step_time=0.3, omega=W)


@SETTINGS
@given(params, st.floats(0.0, 1.0))
def test_steps_to_capture_is_the_fewest_steps_whose_bound_holds(p, fraction):
    limit = capture_bound_limit(**p)
    d = fraction * 1.2 * limit
    n = steps_to_capture(d, **p)
    if d >= limit:
        assert n == math.inf
        return
    assert d <= capture_bound(n, **p)
    assert n == 0 or d > capture_bound(n - 1, **p)


def test_steps_to_capture_at_the_bounds_exactly():
    p = {"r_max": 0.1, "l_max": 0.4, "step_time": 0.3, "omega": W}
    bounds = capture_bound(np.arange(8), **p)
    np.testing.assert_array_equal(steps_to_capture(bounds, **p), np.arange(8))
    np.testing.assert_array_equal(steps_to_capture(bounds + 1e-9, **p), np.arange(1, 9))
    assert steps_to_capture(capture_bound_limit(**p), **p) == math.inf
    assert steps_to_capture(0.2, **{**p, "l_max": 0.0}) == math.inf
    assert steps_to_capture(0.1, **{**p, "l_max": 0.0}) == 0


def test_push_bound_equals_the_n_step_bound_when_the_first_step_takes_a_whole_step_time():
    p = {"r_max": 0.1, "l_max": 0.4, "step_time": 0.3, "omega": W}
    n = np.arange(6)
    np.testing.assert_allclose(push_capture_bound(n, first_landing=0.3, **p), capture_bound(n, **p), rtol=1e-14)
    later = push_capture_bound(n, first_landing=0.45, **p)
    assert later[0] == pytest.approx(0.1)
    assert np.all(later[1:] < capture_bound(n[1:], **p))
    # Landing at once: the whole step length is available before the DCM recedes.
    assert push_capture_bound(1, first_landing=0.0, **p) == pytest.approx(0.5)


def test_reach_along_a_sole():
    foot = support_polygon([Footstep(0.3, -0.1, 0.0, "right")], SOLE)
    ankle = (0.3, -0.1)
    assert reach_along(foot, ankle, (1.0, 0.0)) == pytest.approx(SOLE.front)
    assert reach_along(foot, ankle, (-2.0, 0.0)) == pytest.approx(SOLE.back)
    assert reach_along(foot, ankle, (0.0, 1.0)) == pytest.approx(SOLE.inner)
    assert reach_along(foot, ankle, (1.0, 1.0)) == pytest.approx(math.hypot(0.07, 0.07))
    with pytest.raises(ValueError, match="inside"):
        reach_along(foot, (1.0, 0.0), (1.0, 0.0))


# ----- brute force: push the plant, step, see whether it comes to rest --------------------------------------
def rect_foot(ankle):
    return support_polygon([Footstep(float(ankle[0]), float(ankle[1]), 0.0, "right")], SOLE)


def disc_foot(radius, sides=48):
    """A regular polygon around the disc of ``radius``: every ZMP within ``radius`` of the centre is available."""
    angle = 2.0 * np.pi * (np.arange(sides) + 0.5) / sides
    ring = radius / math.cos(math.pi / sides) * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    return lambda ankle: ring + ankle


def push_and_step(offset, impulse, foot_at, l_max, landings, horizon=3.0, dt=0.002):
    """Push at t = 0 a pendulum whose DCM is ``offset`` from the stance ankle (at the origin), then follow the
    capture-point strategy: command the ZMP on the DCM (the plant holds it at the nearest point of the foot when
    the DCM is outside) and, at each landing time, put the next ankle ``l_max`` toward the DCM (or on it, when
    nearer). Returns (came to rest over the last foot, fell on the way)."""
    ankle = np.zeros(2)
    cog = np.array([0.01, -0.005])  # any COM with the right DCM: only the DCM decides capturability
    plant = LipmPlant(ZC, MASS, cog=cog, cog_vel=W * (np.asarray(offset) - cog))
    plant.apply_impulse(impulse)
    polygon = foot_at(ankle)
    fell = False
    ends = [*landings, (landings[-1] if landings else 0.0) + horizon]
    for k, t_end in enumerate(ends):
        while plant.time < t_end - 1e-12:
            plant.step(min(dt, t_end - plant.time), plant.dcm, polygon)
            fell = fell or plant.fallen(polygon)
        if k < len(landings):
            gap = plant.dcm - ankle
            ankle = ankle + gap * min(1.0, l_max / np.linalg.norm(gap))
            polygon = foot_at(ankle)
    return plant.at_rest(polygon), fell


CASE = {"mass": MASS, "omega": W, "l_max": 0.4, "step_time": 0.3, "remaining": 0.15, "min_remaining": 0.25}
TAU_1 = 0.25  # max(remaining, min_remaining): the swing foot cannot be re-aimed in less
CASE_B = {"l_max": CASE["l_max"], "step_time": CASE["step_time"], "omega": W}


@pytest.mark.parametrize(
    ("offset", "direction", "r_max"),
    [((0.03, 0.0), (1.0, 0.0), SOLE.front), ((0.03, 0.0), (-1.0, 0.0), SOLE.back)],
)
def test_one_step_bound_on_a_rectangular_sole_against_simulation(offset, direction, r_max):
    """Push along the sole's axis with the DCM on it: the 1-D case, where r_max is the sole's reach (exact)."""
    assert reach_along(rect_foot((0.0, 0.0)), (0.0, 0.0), direction) == pytest.approx(r_max)
    J = max_capturable_impulse(offset, direction, r_max=r_max, **CASE)
    assert J > 0.0
    u = np.asarray(direction)
    for factor, captured in [(0.98, True), (1.02, False)]:
        rest, fell = push_and_step(offset, factor * J * u, rect_foot, CASE["l_max"], [TAU_1])
        assert (rest, fell) == (captured, not captured), factor
    for later in (0.05, 0.15):  # waiting longer before stepping does not save it
        assert push_and_step(offset, 1.02 * J * u, rect_foot, CASE["l_max"], [TAU_1 + later]) == (False, True)


@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, 1.0), (-0.6, 0.8), (-1.0, -1.0)])
def test_one_step_bound_in_two_dimensions_against_simulation(direction):
    """Round foot, the planned DCM off the push line: the capturable region is a disc."""
    offset, r_max = (0.03, -0.04), 0.08
    J = max_capturable_impulse(offset, direction, r_max=r_max, **CASE)
    u = np.asarray(direction) / np.linalg.norm(direction)
    xi = np.asarray(offset) + J / (MASS * W) * u
    assert np.linalg.norm(xi) == pytest.approx(push_capture_bound(1, first_landing=TAU_1, r_max=r_max, **CASE_B))
    for factor, captured in [(0.98, True), (1.02, False)]:
        rest, fell = push_and_step(offset, factor * J * u, disc_foot(r_max), CASE["l_max"], [TAU_1])
        assert (rest, fell) == (captured, not captured), factor


def test_two_step_and_zero_step_bounds_against_simulation():
    offset, direction, r_max = (0.02, 0.01), (1.0, 0.0), 0.08
    foot = disc_foot(r_max)
    u = np.asarray(direction)
    J0, J1, J2 = (max_capturable_impulse(offset, direction, r_max=r_max, steps=n, **CASE) for n in (0, 1, 2))
    assert 0.0 < J0 < J1 < J2
    landings2 = [TAU_1, TAU_1 + CASE["step_time"]]
    assert push_and_step(offset, 0.98 * J2 * u, foot, CASE["l_max"], landings2) == (True, False)
    assert push_and_step(offset, 1.02 * J2 * u, foot, CASE["l_max"], landings2) == (False, True)
    beyond_one = 0.5 * (J1 + J2)  # needs the second step
    assert push_and_step(offset, beyond_one * u, foot, CASE["l_max"], [TAU_1]) == (False, True)
    assert push_and_step(offset, beyond_one * u, foot, CASE["l_max"], landings2) == (True, False)
    assert push_and_step(offset, 0.98 * J0 * u, foot, CASE["l_max"], []) == (True, False)
    assert push_and_step(offset, 1.02 * J0 * u, foot, CASE["l_max"], []) == (False, True)


def test_max_impulse_edge_cases():
    kwargs = {"r_max": 0.1, **CASE}
    several = max_capturable_impulse((0.0, 0.0), [(1.0, 0.0), (0.0, -3.0)], **kwargs)
    assert several.shape == (2,)
    np.testing.assert_allclose(several, several[0])  # centred DCM, round model: the same in every direction
    bound = push_capture_bound(1, first_landing=TAU_1, r_max=0.1, **CASE_B)
    assert several[0] == pytest.approx(MASS * W * bound)
    assert max_capturable_impulse((bound + 0.01, 0.0), (1.0, 0.0), **kwargs) == 0.0  # already beyond saving
    # remaining above min_remaining: the first landing is later, the tolerable push smaller.
    assert max_capturable_impulse((0.0, 0.0), (1.0, 0.0), **{**kwargs, "remaining": 0.4}) < several[0]
    with pytest.raises(ValueError, match="zero"):
        max_capturable_impulse((0.0, 0.0), (0.0, 0.0), **kwargs)
    with pytest.raises(ValueError, match="dcm_offset"):
        max_capturable_impulse((0.0, math.nan), (1.0, 0.0), **kwargs)
