"""Simultaneous COG/ZMP planning (eqs. 13-16) and the per-pattern plan operator.

Every property is checked on the solved trajectory itself: the conditions of method.md section 4 and the
pendulum equation, evaluated with ``numpy.polynomial`` where the ZMP is concerned.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial import polynomial as npoly

from rtgait.core.connect import ConnectionSolver
from rtgait.core.footsteps import Timeline, Timing
from rtgait.core.lipm import CogTrajectory, omega
from rtgait.core.pattern import DEGREE, SEGMENT_WIDTH, PatternKey, PlanOperator
from rtgait.core.spline import PiecewisePolynomial

SETTINGS = settings(max_examples=40, deadline=None)


@st.composite
def connection_problems(draw):
    """Random timing, reference segments 2..m of any degree 0..5, current state and terminal COG (2 axes)."""
    m = draw(st.integers(2, 9))
    degree = draw(st.integers(1, 5))  # degree 0: see test_connection_with_piecewise_constant_reference
    first_degree = draw(st.sampled_from([2, 4]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    durations = rng.uniform(0.1, 1.2, m)
    reference = (
        rng.uniform(-0.5, 0.5, (m - 1, degree + 1, 2)) / durations[1:, None, None] ** np.arange(degree + 1)[:, None]
    )
    state = rng.uniform(-0.5, 0.5, (5, 2))  # p0, dp0, c0, dc0, c_end
    w = omega(draw(st.floats(0.4, 1.2)))
    t0 = draw(st.floats(-3.0, 30.0))
    return t0, durations, w, degree, first_degree, reference, state


def polyval_axes(coeffs: np.ndarray, tau: float, derivative: int = 0) -> np.ndarray:
    """Value of ascending coefficients ``(k, d)`` (or a derivative) at ``tau``, per axis, by numpy."""
    return np.array([npoly.polyval(tau, npoly.polyder(coeffs[:, a], derivative)) for a in range(coeffs.shape[1])])


def check_trajectory_is_a_pendulum_solution(cog: CogTrajectory, w: float) -> None:
    """The ODE on dense samples, COG position and velocity continuous at every junction."""
    breaks = cog.zmp.breaks
    for a, b in itertools.pairwise(breaks):
        times = np.linspace(a, b, 30)[1:-1]
        assert np.max(np.abs(cog.pendulum_residual(times))) < 1e-9
        pos, _, acc = cog.evaluate(b, side="left")
        assert np.max(np.abs(cog.zmp.evaluate(b, side="left") - (pos - acc / w**2))) < 1e-9
    for tj in breaks[1:-1]:
        left, right = cog.evaluate(tj, side="left"), cog.evaluate(tj, side="right")
        np.testing.assert_allclose(left[0], right[0], rtol=0, atol=1e-9)
        np.testing.assert_allclose(left[1], right[1], rtol=0, atol=1e-9)


@SETTINGS
@given(connection_problems())
def test_connected_plan_meets_every_condition(problem):
    t0, durations, w, degree, first_degree, reference, state = problem
    p0, dp0, c0, dc0, c_end = state
    solver = ConnectionSolver(durations, w, degree=degree, first_degree=first_degree)
    cog = solver.solve(t0, reference, p0, dp0, c0, dc0, c_end)
    T1 = durations[0]
    first = cog.zmp.coeffs[0]

    # Segment 1's ZMP is a polynomial of degree first_degree (padding above it is zero).
    assert np.all(first[first_degree + 1 :] == 0.0)
    # Starts at the current ZMP and ends at the start of reference segment 2 (eqs. 13-14).
    np.testing.assert_allclose(polyval_axes(first, 0.0), p0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(polyval_axes(first, T1), reference[0, 0], rtol=0, atol=1e-9)
    if first_degree == 4:  # the quartic also matches ZMP velocities at both ends
        np.testing.assert_allclose(polyval_axes(first, 0.0, 1), dp0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(polyval_axes(first, T1, 1), polyval_axes(reference[0], 0.0, 1), atol=1e-8)
    # The spline's own evaluation agrees with that at segment 1's ends.
    np.testing.assert_allclose(cog.zmp.evaluate(t0)[0], p0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.zmp.evaluate(t0 + T1, side="left")[0], reference[0, 0], rtol=0, atol=1e-9)
    # Segments 2..m are the reference, untouched.
    np.testing.assert_array_equal(cog.zmp.coeffs[1:, : degree + 1], reference)
    assert np.all(cog.zmp.coeffs[1:, degree + 1 :] == 0.0)
    # COG position and velocity at the start (eqs. 8, 15), position at the end.
    pos, vel, _ = cog.evaluate(t0)
    np.testing.assert_allclose(pos[0], c0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(vel[0], dc0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.evaluate(cog.zmp.t_end, side="left")[0][0], c_end, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.zmp.breaks, t0 + np.concatenate(([0.0], np.cumsum(durations))), atol=1e-12)
    check_trajectory_is_a_pendulum_solution(cog, w)


def test_quartic_connection_also_continues_the_zmp_velocity_and_the_quadratic_does_not():
    """With a non-zero current ZMP velocity, only the quartic variant can match it."""
    durations = np.array([0.2, 0.8, 0.2, 0.8])
    w = omega(0.8)
    reference = np.zeros((3, 4, 1))
    reference[:, 0, 0] = [0.1, 0.1, 0.2]
    state = dict(zmp=[0.0], zmp_vel=[0.4], cog=[0.02], cog_vel=[0.1], cog_end=[0.2])
    quartic = ConnectionSolver(durations, w, first_degree=4).solve(0.0, reference, **state)
    quadratic = ConnectionSolver(durations, w, first_degree=2).solve(0.0, reference, **state)
    assert quartic.zmp.evaluate(0.0, derivative=1)[0, 0] == pytest.approx(0.4, abs=1e-9)
    assert abs(quadratic.zmp.evaluate(0.0, derivative=1)[0, 0] - 0.4) > 1e-3
    for cog in (quartic, quadratic):
        assert cog.zmp.evaluate(0.0)[0, 0] == pytest.approx(0.0, abs=1e-12)
        assert cog.evaluate(0.0)[1][0, 0] == pytest.approx(0.1, abs=1e-12)


def test_connection_to_a_consistent_state_reproduces_the_reference():
    """Connecting from a plan's own initial state gives that plan back: the connected problem has one solution."""
    w = omega(0.8)
    durations = np.array([0.3, 0.7, 0.3, 0.7, 1.0])
    rng = np.random.default_rng(7)
    reference = rng.uniform(-0.2, 0.2, (4, 4, 1))
    solver = ConnectionSolver(durations, w, degree=3, first_degree=4)
    first = solver.solve(0.0, reference, [0.0], [0.0], [0.01], [0.05], [0.1])
    # Connect again from the first plan's own state at t = 0: the unique solution is the same plan.
    again = solver.solve(0.0, reference, first.zmp.evaluate(0.0)[0], first.zmp.evaluate(0.0, 1)[0],
                         first.evaluate(0.0)[0][0], first.evaluate(0.0)[1][0], [0.1])  # fmt: skip
    times = np.linspace(0.0, durations.sum(), 50)
    np.testing.assert_allclose(again.evaluate(times)[0], first.evaluate(times)[0], rtol=0, atol=1e-12)


def test_connection_with_piecewise_constant_reference():
    """Reference ZMP constant on each segment (degree 0, the classic footstep ZMP)."""
    w = omega(0.8)
    durations = np.array([0.2, 0.8, 0.2, 0.8])
    reference = np.array([0.1, 0.15, 0.2]).reshape(3, 1, 1)
    solver = ConnectionSolver(durations, w, degree=0, first_degree=4)
    cog = solver.solve(0.0, reference, [0.0], [0.0], [0.0], [0.05], [0.2])
    np.testing.assert_allclose(cog.zmp.evaluate(0.2, side="left")[0], [0.1], atol=1e-9)
    np.testing.assert_allclose(cog.evaluate(0.0)[1][0], [0.05], atol=1e-9)
    check_trajectory_is_a_pendulum_solution(cog, w)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        (dict(durations=np.array([0.5])), "at least 2 segments"),
        (dict(durations=np.array([0.5, 0.0])), "durations"),
        (dict(durations=np.array([0.5, math.nan])), "durations"),
        (dict(durations=np.array([0.5, 0.5]), first_degree=3), "first_degree"),
    ],
)
def test_connection_solver_rejects_bad_setup(kwargs, field):
    args = dict(w=3.0) | kwargs
    with pytest.raises(ValueError, match=field):
        ConnectionSolver(**args)


def test_connection_solver_rejects_bad_inputs():
    solver = ConnectionSolver(np.array([0.2, 0.8]), 3.0)
    good = np.zeros((1, 4, 2))
    with pytest.raises(ValueError, match="finite"):
        solver.solve(0.0, good, [math.nan, 0.0], [0, 0], [0, 0], [0, 0], [0, 0])
    with pytest.raises(ValueError, match="finite"):
        solver.solve(0.0, np.full((1, 4, 2), math.inf), [0, 0], [0, 0], [0, 0], [0, 0], [0, 0])
    with pytest.raises(ValueError, match="shape"):
        solver.solve(0.0, np.zeros((2, 4, 2)), [0, 0], [0, 0], [0, 0], [0, 0], [0, 0])


# ----- PlanOperator ---------------------------------------------------------------------------------------
def hermite_transfer(start: np.ndarray, end: np.ndarray, T: float) -> np.ndarray:
    """Cubic ``(4, d)`` with p(0)=start, p(T)=end, p'(0)=p'(T)=0, by solving the 4x4 Hermite system."""
    H = np.array([[1, 0, 0, 0], [1, T, T**2, T**3], [0, 1, 0, 0], [0, 1, 2 * T, 3 * T**2]], dtype=float)
    rhs = np.array([start, end, np.zeros_like(start), np.zeros_like(start)])
    return np.linalg.solve(H, rhs)


@st.composite
def pattern_problems(draw):
    """A window of a real walk's phases (as the online planner would plan it) and random numbers for it."""
    n_steps = draw(st.none() | st.integers(1, 8))
    timing = Timing(draw(st.floats(0.3, 1.0)), draw(st.floats(0.1, 0.5)), draw(st.floats(0.3, 1.5)),
                    draw(st.floats(0.3, 1.5)), draw(st.floats(0.3, 2.0)))  # fmt: skip
    timeline = Timeline(timing, n_steps)
    q = 2 * draw(st.integers(0, n_steps if n_steps is not None else 6))
    last = q + 2 * draw(st.integers(1, 4))
    if n_steps is not None and last >= 2 * n_steps:
        last = 2 * n_steps + 1
    phases = range(q, last + 1)
    kinds = tuple(timeline.kind(p) for p in phases)
    durations = tuple(timeline.duration(p) for p in phases)
    w = omega(draw(st.floats(0.5, 1.1)))
    first_degree = draw(st.sampled_from([2, 4]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n_anchors = 1 + sum(k in ("start", "double", "end") for k in kinds[1:])
    y = rng.uniform(-0.5, 0.5, (4 + n_anchors, 2))  # m and m/s: a humanoid's range
    return PatternKey(kinds, durations, w, first_degree), y


@SETTINGS
@given(pattern_problems())
def test_plan_operator_equals_connection_solver_on_the_cubic_reference(problem):
    key, y = problem
    op = PlanOperator(key)
    assert op.n_anchors == y.shape[0] - 4
    data = op.solve(y)
    m = len(key.kinds)
    assert data.shape == (m, SEGMENT_WIDTH, 2)

    # Build the reference ZMP of segments 2..m from the anchors, independently: hold an anchor in single
    # support and settling, Hermite-transfer to the next anchor in double support.
    anchors = y[4:]
    reference = []
    k = 0
    for kind, T in zip(key.kinds[1:], key.durations[1:], strict=True):
        if kind in ("start", "double", "end"):
            reference.append(hermite_transfer(anchors[k], anchors[k + 1], T))
            k += 1
        else:
            reference.append(np.vstack([anchors[k], np.zeros((3, 2))]))
    assert k == len(anchors) - 1
    reference = np.array(reference)
    solver = ConnectionSolver(np.array(key.durations), key.w, degree=3, first_degree=key.first_degree)
    direct = solver.solve(0.0, reference, y[0], y[1], y[2], y[3], anchors[-1])

    # Same ZMP coefficients, COG polynomial parts, V and W in every segment.
    coeffs = np.zeros((m, DEGREE + 1, 2))
    coeffs[:, : direct.zmp.coeffs.shape[1]] = direct.zmp.coeffs
    scale = 1.0 + np.max(np.abs(coeffs))
    np.testing.assert_allclose(data[:, : DEGREE + 1], coeffs, rtol=0, atol=1e-9 * scale)
    particular = np.zeros((m, DEGREE + 1, 2))
    particular[:, : direct.particular.shape[1]] = direct.particular
    np.testing.assert_allclose(data[:, DEGREE + 1 : 2 * (DEGREE + 1)], particular, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(data[:, -2], direct.V, rtol=0, atol=1e-9)
    np.testing.assert_allclose(data[:, -1], direct.W, rtol=0, atol=1e-9)

    # And as a trajectory: a pendulum solution whose end COG is over the last anchor.
    zmp = PiecewisePolynomial(0.0, np.array(key.durations), data[:, : DEGREE + 1])
    cog = CogTrajectory(zmp, data[:, -2], data[:, -1], key.w)
    check_trajectory_is_a_pendulum_solution(cog, key.w)
    np.testing.assert_allclose(cog.evaluate(zmp.t_end, side="left")[0][0], anchors[-1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.evaluate(0.0)[1][0], y[3], rtol=0, atol=1e-9)


def test_plan_operator_must_start_in_double_support():
    key = PatternKey(("single", "double", "single"), (0.8, 0.2, 0.8), 3.5, 4)
    with pytest.raises(ValueError, match="double-support"):
        PlanOperator(key)
