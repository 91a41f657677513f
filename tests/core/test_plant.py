"""The point-mass LIPM plant: exact integration, the real ZMP, pushes, falls and rest, against independent truth."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.polygon import clip_to_polygon
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.lipm.closed_form import GRAVITY
from rtgait.core.pendulum.plant import DEFAULT_MAX_LEAN, LipmPlant, push_force, push_impulse
from rtgait.core.push import PUSH_SPEED_LIMIT, Push

ZC, MASS = 0.8, 50.0
W = math.sqrt(GRAVITY / ZC)
SOLE = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
RIGHT = Footstep(0.0, 0.0, 0.0, "right")
DOUBLE = support_polygon([Footstep(0.05, 0.19, 0.3, "left"), RIGHT], SOLE)  # yawed left foot: a 6-gon


# ----- exact integration ----------------------------------------------------------------------------------
def reference_motion(state0, pieces):
    """Integrate c'' = w^2 (c - p) + f / m with solve_ivp, piece by piece (p and f constant on each piece)."""
    state = np.array(state0, dtype=float)
    for duration, zmp, force in pieces:

        def rhs(_t, s, zmp=zmp, force=force):
            return np.concatenate([s[2:], W**2 * (s[:2] - zmp) + force / MASS])

        sol = solve_ivp(rhs, (0.0, duration), state, method="DOP853", rtol=1e-13, atol=1e-15)
        state = sol.y[:, -1]
    return state


def test_exact_integration_matches_solve_ivp():
    rng = np.random.default_rng(1)
    dt, ticks = 0.01, 60
    pushes = [Push(0.1337, 0.0571, (80.0, -30.0)), Push(0.15, 0.2, (-20.0, 40.0))]  # overlap, off the tick grid
    plant = LipmPlant(ZC, MASS, cog=(0.02, 0.01), cog_vel=(0.1, -0.05), pushes=pushes)
    state = [0.02, 0.01, 0.1, -0.05]
    for k in range(ticks):
        command = rng.uniform([-0.2, -0.15], [0.3, 0.35])  # some inside the polygon, some clipped
        force = rng.uniform(-15.0, 15.0, 2) if k % 3 == 0 else np.zeros(2)
        zmp = plant.step(dt, command, DOUBLE, force)
        assert signed_margin(zmp, DOUBLE)[0] >= -1e-12
        t0 = k * dt
        # The reference splits the tick at the push boundaries itself.
        cuts = sorted({t0, t0 + dt, *(b for p in pushes for b in (p.start, p.end) if t0 < b < t0 + dt)})
        pieces = [(b - a, zmp, force + push_force(pushes, 0.5 * (a + b))) for a, b in itertools.pairwise(cuts)]
        state = reference_motion(state, pieces)
        got = np.concatenate([plant.cog, plant.cog_vel])
        np.testing.assert_allclose(got, state, rtol=1e-9, atol=1e-11)
    assert plant.time == pytest.approx(ticks * dt, abs=1e-12)
    np.testing.assert_allclose(plant.dcm, plant.cog + plant.cog_vel / W, rtol=1e-15)


# ----- the real ZMP: nearest point of the support polygon ------------------------------------------------
def brute_force_nearest(point, polygon, per_edge=4000):
    """Nearest of many points spread along the boundary (the point itself when inside)."""
    if signed_margin(point, polygon)[0] >= 0.0:
        return np.asarray(point, dtype=float)
    s = np.linspace(0.0, 1.0, per_edge)[:, None, None]
    boundary = (polygon + s * (np.roll(polygon, -1, axis=0) - polygon)).reshape(-1, 2)
    return boundary[np.argmin(np.linalg.norm(boundary - point, axis=1))]


def test_zmp_clip_equals_brute_force_nearest_point():
    rng = np.random.default_rng(2)
    points = np.vstack([rng.uniform([-0.5, -0.5], [0.6, 0.7], (150, 2)), DOUBLE, 0.5 * (DOUBLE + DOUBLE[[1]])])
    plant = LipmPlant(ZC, MASS)
    for point in points:
        clipped = clip_to_polygon(point, DOUBLE)
        np.testing.assert_allclose(clipped, brute_force_nearest(point, DOUBLE), atol=1e-4)
        distance = -min(signed_margin(point, DOUBLE)[0], 0.0)
        # Exact: a point of the polygon at the polygon's distance is the nearest point (unique, by convexity).
        assert np.linalg.norm(clipped - point) == pytest.approx(distance, abs=1e-12)
        assert signed_margin(clipped, DOUBLE)[0] >= -1e-12
        if distance == 0.0:
            np.testing.assert_array_equal(clipped, point)
        plant.set_state(point, (0.0, 0.0))
        assert plant.distance_to_polygon(DOUBLE) == pytest.approx(distance, abs=1e-12)
        np.testing.assert_array_equal(plant.step(1e-3, point, DOUBLE), clipped)


def test_point_and_line_contacts_and_bad_polygons():
    np.testing.assert_array_equal(clip_to_polygon((1.0, 2.0), np.array([[0.5, 0.5]])), [0.5, 0.5])
    np.testing.assert_allclose(clip_to_polygon((0.5, 2.0), np.array([[0.0, 0.0], [1.0, 0.0]])), [0.5, 0.0])
    np.testing.assert_allclose(clip_to_polygon((3.0, -1.0), np.array([[0.0, 0.0], [1.0, 0.0]])), [1.0, 0.0])
    plant = LipmPlant(ZC, MASS)
    with pytest.raises(ValueError, match="no foot on the ground"):
        plant.step(0.01, (0.0, 0.0), np.zeros((0, 2)))
    with pytest.raises(ValueError, match="no foot on the ground"):
        plant.step(0.01, (0.0, 0.0), None)
    with pytest.raises(ValueError, match="counter-clockwise"):
        plant.step(0.01, (0.0, 0.0), DOUBLE[::-1])
    with pytest.raises(ValueError, match="convex"):
        plant.step(0.01, (0.0, 0.0), np.array([[0.0, 0.0], [1.0, 0.0], [0.2, 0.2], [0.0, 1.0]]))
    with pytest.raises(ValueError, match="finite"):
        plant.step(0.01, (math.nan, 0.0), DOUBLE)
    with pytest.raises(ValueError, match="dt"):
        plant.step(0.0, (0.0, 0.0), DOUBLE)
    with pytest.raises(ValueError, match="mass"):
        LipmPlant(ZC, -1.0)
    with pytest.raises(ValueError, match="cog_height"):
        LipmPlant(-ZC, MASS)


# ----- pushes ---------------------------------------------------------------------------------------------
def test_push_starting_and_ending_mid_tick_delivers_its_exact_impulse():
    """Two plants, same ZMP, one pushed: their difference d obeys d'' = w^2 d + f / m from rest, whatever the ZMP,
    so right after the push d' = F sinh(w T) / (m w) and d = F (cosh(w T) - 1) / (m w^2), then d is homogeneous.
    (m d' -> F T as w T -> 0: the impulse; the w-terms are the pendulum acting while the push lasts.)"""
    dt = 0.01
    push = Push(start=0.1234, duration=0.0567, force=(120.0, -45.0))
    pushed = LipmPlant(ZC, MASS, cog=(0.01, 0.0), cog_vel=(0.2, 0.05), pushes=[push])
    free = LipmPlant(ZC, MASS, cog=(0.01, 0.0), cog_vel=(0.2, 0.05))
    force, T = np.array(push.force[:2]), push.duration
    d_end = force * (math.cosh(W * T) - 1.0) / (MASS * W**2)
    v_end = force * math.sinh(W * T) / (MASS * W)
    checked = 0
    for _ in range(40):
        command = (0.02 + 0.2 * free.time, 0.0)  # both stay inside the foot: the same real ZMP
        np.testing.assert_array_equal(pushed.step(dt, command, DOUBLE), free.step(dt, command, DOUBLE))
        s = pushed.time - push.end
        if s >= 0.0:
            d = d_end * math.cosh(W * s) + v_end * math.sinh(W * s) / W
            v = d_end * W * math.sinh(W * s) + v_end * math.cosh(W * s)
            np.testing.assert_allclose(pushed.cog - free.cog, d, rtol=1e-9, atol=1e-15)
            np.testing.assert_allclose(MASS * (pushed.cog_vel - free.cog_vel), MASS * v, rtol=1e-9, atol=1e-13)
            checked += 1
    assert checked > 10
    # The check can fail: spreading the same impulse evenly over the ticks it touches (a naive integrator) is off
    # by far more than the tolerance above.
    ticks = [(k * dt, (k + 1) * dt) for k in range(12, 19)]
    naive = np.zeros(2)
    naive_v = np.zeros(2)
    for a, b in ticks:
        f = push_impulse([push], a, b) / dt
        naive, naive_v = (
            (naive + f / (MASS * W**2)) * math.cosh(W * dt) + naive_v / W * math.sinh(W * dt) - f / (MASS * W**2),
            (naive + f / (MASS * W**2)) * W * math.sinh(W * dt) + naive_v * math.cosh(W * dt),
        )
    s = ticks[-1][1] - push.end
    exact_v = d_end * W * math.sinh(W * s) + v_end * math.cosh(W * s)
    assert np.max(np.abs(naive_v - exact_v) / np.abs(exact_v)) > 1e-6


def test_push_force_and_impulse_helpers():
    pushes = [Push(0.5, 0.1, (10.0, 0.0)), Push(0.55, 0.1, (0.0, -4.0))]
    np.testing.assert_array_equal(push_force(pushes, 0.5), [10.0, 0.0])  # [start, end)
    np.testing.assert_array_equal(push_force(pushes, 0.57), [10.0, -4.0])
    np.testing.assert_array_equal(push_force(pushes, 0.6), [0.0, -4.0])
    np.testing.assert_array_equal(push_force(pushes, 0.65), [0.0, 0.0])
    dt = 0.003  # not a divisor of any boundary: most ticks overlap a push only partly
    total = sum(push_impulse(pushes, k * dt, (k + 1) * dt) for k in range(400))
    np.testing.assert_allclose(total, np.add(pushes[0].impulse, pushes[1].impulse)[:2], rtol=1e-12)
    np.testing.assert_allclose(pushes[1].impulse, [0.0, -0.4, 0.0], rtol=1e-12)


def test_push_validation():
    for bad in [
        dict(start=math.nan, duration=0.1, force=(1.0, 0.0)),
        dict(start=0.0, duration=0.0, force=(1.0, 0.0)),
        dict(start=0.0, duration=-0.1, force=(1.0, 0.0)),
        dict(start=0.0, duration=0.1, force=(1.0, math.inf)),
        dict(start=0.0, duration=0.1, force=(1.0,)),
        dict(start=0.0, duration=0.1, force=(1.0, 0.0, 0.0, 0.0)),
        dict(start=0.0, duration=0.1, force=(1.0, 0.0), body=""),
    ]:
        with pytest.raises(ValueError, match="push"):
            Push(**bad)
    assert Push(0.0, 0.1, (1, 2)).force == (1.0, 2.0, 0.0)  # a horizontal force: fz = 0
    plant = LipmPlant(ZC, MASS)
    with pytest.raises(ValueError, match="horizontal"):
        plant.add_push(Push(0.0, 0.1, (1.0, 0.0, 5.0)))
    with pytest.raises(ValueError, match="only body"):
        plant.add_push(Push(0.0, 0.1, (1.0, 0.0), body="pelvis"))
    limit = PUSH_SPEED_LIMIT * MASS * math.sqrt(GRAVITY * ZC)
    assert plant.max_impulse == pytest.approx(limit)
    plant.add_push(Push(0.0, 0.5, (0.99 * limit / 0.5, 0.0)))
    with pytest.raises(ValueError, match="exceeds"):
        plant.add_push(Push(0.0, 0.5, (0.0, 1.01 * limit / 0.5)))
    with pytest.raises(ValueError, match="exceeds"):
        plant.apply_impulse((1.01 * limit, 0.0))
    plant.apply_impulse((MASS * 0.3, 0.0))
    assert plant.cog_vel[0] == pytest.approx(0.3)
    assert plant.dcm[0] == pytest.approx(0.3 / W)


# ----- falls and rest -------------------------------------------------------------------------------------
@pytest.mark.parametrize("fall_distance", [None, 0.1])
def test_fall_detected_when_a_diverging_pendulum_crosses_the_distance(fall_distance):
    """ZMP held at the ankle, COM 2 cm ahead at rest: c(t) = 0.02 cosh(w t), which leaves the sole's front edge
    (0.13 m) and is farther than the fall distance from it after t* = acosh((0.13 + D) / 0.02) / w."""
    foot = support_polygon([RIGHT], SOLE)
    plant = LipmPlant(ZC, MASS, cog=(0.02, 0.0), fall_distance=fall_distance)
    D = ZC * math.tan(DEFAULT_MAX_LEAN) if fall_distance is None else fall_distance
    assert plant.fall_distance == pytest.approx(D)
    t_star = math.acosh((SOLE.front + D) / 0.02) / W
    dt = 0.005
    while not plant.fallen(foot):
        assert plant.time < t_star + 1e-9
        plant.step(dt, (0.0, 0.0), foot)
        assert plant.time < 10.0
    assert t_star <= plant.time < t_star + dt
    assert not plant.at_rest(foot)


def test_dcm_on_the_zmp_converges_to_rest():
    """With the ZMP held on the DCM, xi' = w (xi - p) = 0: the DCM stays put and c - p decays like e^{-w t}."""
    foot = support_polygon([RIGHT], SOLE)
    p = np.array([0.03, -0.01])
    c0 = np.array([0.08, 0.02])
    plant = LipmPlant(ZC, MASS, cog=c0, cog_vel=W * (p - c0))
    np.testing.assert_allclose(plant.dcm, p, atol=1e-15)
    assert not plant.at_rest(foot)  # moving at 0.2 m/s
    dt = 0.001
    for _ in range(3000):
        plant.step(dt, p, foot)
        # The DCM is the pendulum's unstable mode: round-off in it grows like e^{w t}, and nothing else may move it.
        assert np.max(np.abs(plant.dcm - p)) <= 1e-15 * math.exp(W * plant.time)
    np.testing.assert_allclose(plant.cog - p, (c0 - p) * math.exp(-W * plant.time), rtol=1e-9, atol=1e-10)
    assert plant.at_rest(foot)
    assert not plant.fallen(foot)


def test_at_rest_needs_the_dcm_inside_the_polygon():
    foot = support_polygon([RIGHT], SOLE)
    still_outside = LipmPlant(ZC, MASS, cog=(SOLE.front + 0.001, 0.0))  # not moving, but it will fall
    assert not still_outside.at_rest(foot)
    over_the_edge = LipmPlant(ZC, MASS, cog=(SOLE.front, 0.0), cog_vel=(0.005 * W, 0.0))  # slow, DCM 5 mm past the toe
    assert np.linalg.norm(over_the_edge.cog_vel) < 0.02
    assert over_the_edge.at_rest(foot, speed_tol=0.02, margin=-0.01)
    assert not over_the_edge.at_rest(foot, speed_tol=0.02)
    inside = LipmPlant(ZC, MASS, cog=(0.05, 0.0), cog_vel=(0.004, 0.0))
    assert inside.at_rest(foot)
    assert not inside.at_rest(foot, speed_tol=0.001)
    assert not inside.at_rest(foot, margin=0.1)  # the DCM is 0.07 m from the sole's side edges
