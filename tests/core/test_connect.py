"""Simultaneous COG/ZMP planning (eqs. 13-16) and the per-pattern plan operator.

Every property is checked on the solved trajectory itself: the conditions of method.md section 4 and the
pendulum equation, evaluated with ``numpy.polynomial`` where the ZMP is concerned. The plan operator's fast
build is also compared with the dense formulation it replaced (:func:`reference_operator`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial import polynomial as npoly

from rtgait.core.geometry.footsteps import Timeline, Timing
from rtgait.core.lipm.closed_form import CogTrajectory, omega, particular_matrix
from rtgait.core.lipm.connect import ConnectionSolver, rest_bump
from rtgait.core.lipm.pattern import DEGREE, SEGMENT_WIDTH, PatternKey, PlanOperator, plan_operator_matrices
from rtgait.core.lipm.spline import PiecewisePolynomial

MOVING = ("start", "double", "end")

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
    terminal_rest = draw(st.booleans())  # w T_m >= 2.86 * 0.1 > MIN_REST_W_T: long enough to stop
    return t0, durations, w, degree, first_degree, reference, state, terminal_rest


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
    t0, durations, w, degree, first_degree, reference, state, terminal_rest = problem
    p0, dp0, c0, dc0, c_end = state
    solver = ConnectionSolver(durations, w, degree=degree, first_degree=first_degree, terminal_rest=terminal_rest)
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
    # Segments 2..m are the reference, untouched; with terminal rest the last one gets alpha times the bump.
    coeffs = cog.zmp.coeffs.copy()
    if terminal_rest:
        coeffs[-1, :5] -= rest_bump(durations[-1])[:, None] * rest_amplitude(solver, reference, state)
    np.testing.assert_array_equal(coeffs[1:-1, : degree + 1], reference[:-1])
    np.testing.assert_allclose(coeffs[-1, : degree + 1], reference[-1], rtol=1e-12, atol=1e-9)
    assert np.all(np.abs(coeffs[1:, degree + 1 :]) <= 1e-9 * (1.0 + np.abs(cog.zmp.coeffs[1:, degree + 1 :])))
    # COG position and velocity at the start (eqs. 8, 15), position (and velocity, at rest) at the end.
    pos, vel, _ = cog.evaluate(t0)
    np.testing.assert_allclose(pos[0], c0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(vel[0], dc0, rtol=0, atol=1e-9)
    pos_end, vel_end, _ = cog.evaluate(cog.zmp.t_end, side="left")
    np.testing.assert_allclose(pos_end[0], c_end, rtol=0, atol=1e-9)
    if terminal_rest:
        np.testing.assert_allclose(vel_end[0], 0.0, rtol=0, atol=1e-9)
        # The bump leaves the ZMP position and velocity where segment m begins and ends untouched.
        for tj in cog.zmp.breaks[-2:]:
            for derivative in (0, 1):
                expected = polyval_axes(reference[-1], tj - cog.zmp.breaks[-2], derivative)
                got = cog.zmp.evaluate(tj, derivative, side="left" if tj == cog.zmp.t_end else "right")[0]
                np.testing.assert_allclose(got, expected, rtol=0, atol=1e-8)
    np.testing.assert_allclose(cog.zmp.breaks, t0 + np.concatenate(([0.0], np.cumsum(durations))), atol=1e-12)
    check_trajectory_is_a_pendulum_solution(cog, w)


def rest_amplitude(solver: ConnectionSolver, reference: np.ndarray, state: np.ndarray) -> np.ndarray:
    """``alpha`` (m, per axis) straight from the solved unknowns: their last entry."""
    p0, dp0, c0, dc0, c_end = state
    x = solver.inputs(reference, p0, dp0, c0, dc0, c_end)
    return (solver.operator @ x)[-1]


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


def reference_zmp(kinds: tuple[str, ...], durations, anchors: np.ndarray) -> np.ndarray:
    """Reference ZMP of segments 2..m, ``(m - 1, 4, d)``, from the anchors ``(K, d)``, independently of the code
    under test: hold an anchor in single support and settling, Hermite-transfer to the next one otherwise."""
    reference = []
    k = 0
    for kind, T in zip(kinds[1:], durations[1:], strict=True):
        if kind in MOVING:
            reference.append(hermite_transfer(anchors[k], anchors[k + 1], T))
            k += 1
        else:
            reference.append(np.vstack([anchors[k], np.zeros((3, anchors.shape[1]))]))
    assert k == len(anchors) - 1
    return np.array(reference)


def reference_operator(key: PatternKey) -> np.ndarray:
    """``G`` the slow way, as :class:`PlanOperator` was built before its fast build: the reference ZMP as a
    linear map of ``y``, the dense :class:`ConnectionSolver` operator (with ``terminal_rest`` when the plan ends
    in 'settle'), then the stored layout ``[a, A = Q a, V, W]`` per segment. Unit columns stand for the inputs."""
    durations = np.asarray(key.durations, dtype=float)
    n_cols = 4 + 1 + sum(kind in MOVING for kind in key.kinds[1:])
    unit = np.eye(n_cols)
    reference = reference_zmp(key.kinds, durations, unit[4:])
    solver = ConnectionSolver(durations, key.w, degree=3, first_degree=key.first_degree,
                              terminal_rest=key.kinds[-1] == "settle")  # fmt: skip
    unknowns = solver.operator @ solver.inputs(reference, *unit[:4], unit[-1])
    cog = solver.trajectory(0.0, unknowns, reference)
    a = np.zeros((durations.size, DEGREE + 1, n_cols))
    a[:, : cog.zmp.coeffs.shape[1]] = cog.zmp.coeffs
    A = np.einsum("ik,jkc->jic", particular_matrix(DEGREE, key.w), a)
    return np.concatenate([a, A, cog.V[:, None], cog.W[:, None]], axis=1).reshape(-1, n_cols)


def plan_trajectory(op: PlanOperator, y: np.ndarray, t0: float = 0.0) -> CogTrajectory:
    data = op.solve(y)
    zmp = PiecewisePolynomial(t0, op.durations, data[:, : DEGREE + 1])
    return CogTrajectory(zmp, data[:, -2], data[:, -1], op.key.w)


def check_connected_plan(cog: CogTrajectory, key: PatternKey, y: np.ndarray) -> None:
    """Every condition of a connected plan, on the trajectory: ZMP at both ends of segment 1 (velocities too for
    the quartic), COG state at the start, pendulum and continuity everywhere, the end over the last anchor (at
    rest if the plan ends in 'settle'), each reference segment where the anchors say."""
    t0, t1, t_end = cog.zmp.t0, cog.zmp.breaks[1], cog.zmp.t_end
    np.testing.assert_allclose(cog.zmp.evaluate(t0)[0], y[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.zmp.evaluate(t1, side="left")[0], y[4], rtol=0, atol=1e-9)
    if key.first_degree == 4:
        np.testing.assert_allclose(cog.zmp.evaluate(t0, 1)[0], y[1], rtol=0, atol=1e-9)
        np.testing.assert_allclose(cog.zmp.evaluate(t1, 1, side="left")[0], 0.0, rtol=0, atol=1e-8)
    pos, vel, _ = cog.evaluate(t0)
    np.testing.assert_allclose(pos[0], y[2], rtol=0, atol=1e-9)
    np.testing.assert_allclose(vel[0], y[3], rtol=0, atol=1e-9)
    check_trajectory_is_a_pendulum_solution(cog, key.w)
    pos, vel, acc = cog.evaluate(t_end, side="left")
    np.testing.assert_allclose(pos[0], y[-1], rtol=0, atol=1e-9)
    if key.kinds[-1] == "settle":
        np.testing.assert_allclose(vel[0], 0.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(acc[0], 0.0, rtol=0, atol=1e-8)
    reference = reference_zmp(key.kinds, key.durations, y[4:])
    for j, breaks in enumerate(itertools.pairwise(cog.zmp.breaks[1:]), start=1):
        for t in breaks:
            expected = polyval_axes(reference[j - 1], t - breaks[0])  # the rest bump vanishes at both ends
            got = cog.zmp.evaluate(t, side="left" if t == breaks[1] else "right")[0]
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)


@st.composite
def pattern_problems(draw):
    """A window of a real walk's phases as the online planner plans it, from the start of any phase but the
    settle or from inside it (the first segment is then the phase's remainder, at least 0.1 s), and random
    numbers for it."""
    n_steps = draw(st.none() | st.integers(1, 8))
    timing = Timing(draw(st.floats(0.3, 1.0)), draw(st.floats(0.1, 0.5)), draw(st.floats(0.3, 1.5)),
                    draw(st.floats(0.3, 1.5)), draw(st.floats(0.3, 2.0)))  # fmt: skip
    timeline = Timeline(timing, n_steps)
    q = draw(st.integers(0, 2 * n_steps if n_steps is not None else 12))
    last = q + draw(st.integers(1, 8))
    if n_steps is not None and last >= 2 * n_steps:
        last = 2 * n_steps + 1
    phases = range(q, last + 1)
    kinds = tuple(timeline.kind(p) for p in phases)
    durations = [timeline.duration(p) for p in phases]
    if draw(st.booleans()):
        durations[0] = draw(st.floats(0.1, durations[0]))
    w = omega(draw(st.floats(0.5, 1.1)))
    first_degree = draw(st.sampled_from([2, 4]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n_anchors = 1 + sum(k in MOVING for k in kinds[1:])
    y = rng.uniform(-0.5, 0.5, (4 + n_anchors, 2))  # m and m/s: a humanoid's range
    return PatternKey(kinds, tuple(durations), w, first_degree), y


@SETTINGS
@given(pattern_problems())
def test_plan_operator_equals_connection_solver_on_the_cubic_reference(problem):
    key, y = problem
    op = PlanOperator(key)
    assert op.n_anchors == y.shape[0] - 4
    data = op.solve(y)
    m = len(key.kinds)
    assert data.shape == (m, SEGMENT_WIDTH, 2)

    anchors = y[4:]
    reference = reference_zmp(key.kinds, key.durations, anchors)
    rest = key.kinds[-1] == "settle"
    solver = ConnectionSolver(np.array(key.durations), key.w, degree=3, first_degree=key.first_degree,
                              terminal_rest=rest)  # fmt: skip
    direct = solver.solve(0.0, reference, y[0], y[1], y[2], y[3], anchors[-1])

    # Same ZMP coefficients, COG polynomial parts, V and W in every segment.
    coeffs = np.zeros((m, DEGREE + 1, 2))
    coeffs[:, : direct.zmp.coeffs.shape[1]] = direct.zmp.coeffs
    scale = 1.0 + np.max(np.abs(coeffs))
    np.testing.assert_allclose(data[:, : DEGREE + 1], coeffs, rtol=0, atol=1e-9 * scale)
    particular = np.zeros((m, DEGREE + 1, 2))
    particular[:, : direct.particular.shape[1]] = direct.particular
    np.testing.assert_allclose(data[:, DEGREE + 1 : 2 * (DEGREE + 1)], particular, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(data[:, -2], direct.V, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(data[:, -1], direct.W, rtol=0, atol=1e-9 * scale)

    # And as a trajectory: every condition of the connection, whatever the first segment's kind.
    check_connected_plan(plan_trajectory(op, y), key, y)


def agreement(first_duration: float) -> float:
    """How closely (relative to the largest entry) two correct builds of ``G`` can agree. Both lose digits to the
    free segment's monomials: coefficients ~1/T_1^4 times an amplitude ~1/T_1, whose COG response is a small
    difference of large particular parts. For T_1 >= 0.2 s the two builds agree to ~3e-12 (over 1200 random
    keys); at 0.1 s to ~1.5e-11. Against a 50-digit solution both are off by as much as they differ."""
    return 1e-11 * max(1.0, (0.2 / first_duration) ** 5)


@settings(max_examples=80, deadline=None)
@given(pattern_problems())
def test_fast_build_equals_the_dense_formulation(problem):
    """G as built now against the dense solve it replaced, entry by entry."""
    key, _ = problem
    G = PlanOperator(key).G
    expected = reference_operator(key)
    assert G.shape == expected.shape
    assert np.max(np.abs(G - expected)) <= agreement(key.durations[0]) * np.max(np.abs(expected))


HORIZON_3_STEPS = PatternKey(("double", "single", "double", "single", "double", "single", "double"),
                             (0.1, 0.7, 0.1, 0.7, 0.1, 0.7, 0.1), 3.5, 4)  # fmt: skip


@pytest.mark.parametrize("first_degree", [4, 2])
@pytest.mark.parametrize(
    ("kinds", "durations"),
    [
        (HORIZON_3_STEPS.kinds, HORIZON_3_STEPS.durations),
        (("start", "single", "double", "single", "double", "single", "double"), (1.0, 0.8, 0.2, 0.8, 0.2, 0.8, 0.2)),
        (("double", "single", "double", "single", "end", "settle"), (0.2, 0.8, 0.2, 0.8, 1.0, 2.0)),
        (("double", "single", "double", "single", "double", "single", "double"), (1.5, 0.8, 1.5, 0.8, 1.5, 0.8, 1.5)),
    ],
)
def test_fast_build_equals_the_dense_formulation_on_the_paper_timings(kinds, durations, first_degree):
    key = PatternKey(kinds, durations, omega(0.8), first_degree)
    expected = reference_operator(key)
    scale = np.max(np.abs(expected))
    np.testing.assert_allclose(PlanOperator(key).G, expected, rtol=0, atol=agreement(durations[0]) * scale)


def test_operators_for_several_first_durations_equal_single_builds():
    first = [0.05, 0.1, 0.13, 0.4]
    operators = PlanOperator.for_first_durations(HORIZON_3_STEPS, first)
    assert [op.key.durations[0] for op in operators] == first
    for op, T1 in zip(operators, first, strict=True):
        single = PlanOperator(PatternKey(HORIZON_3_STEPS.kinds, (T1, *HORIZON_3_STEPS.durations[1:]), 3.5, 4))
        assert op.key == single.key
        np.testing.assert_array_equal(op.durations, single.durations)
        assert (op.n_segments, op.n_anchors) == (single.n_segments, single.n_anchors)
        np.testing.assert_allclose(op.G, single.G, rtol=0, atol=1e-13 * np.max(np.abs(single.G)))
    batch = plan_operator_matrices(HORIZON_3_STEPS.kinds, np.full((2, 7), 0.5), 3.5, 4)
    assert batch.shape == (2, 7 * SEGMENT_WIDTH, 4 + 4)
    with pytest.raises(ValueError, match="first_durations"):
        PlanOperator.for_first_durations(HORIZON_3_STEPS, [])
    with pytest.raises(ValueError, match="durations"):
        PlanOperator.for_first_durations(HORIZON_3_STEPS, [0.1, -0.1])


# ----- a first segment of any kind: the remainder of the phase under way ------------------------------------
WALK_KINDS = ("double", "single", "double", "single", "double", "single", "double")
WALK_DURATIONS = (0.2, 0.8, 0.2, 0.8, 0.2, 0.8, 0.2)
ENDING_KINDS = ("double", "single", "double", "single", "end", "settle")
ENDING_DURATIONS = (0.2, 0.8, 0.2, 0.8, 1.0, 0.6)


def walk_inputs(n_anchors: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    state = rng.uniform(-0.1, 0.1, (4, 2))
    anchors = np.cumsum(rng.uniform([0.0, -0.2], [0.3, 0.2], (n_anchors, 2)), axis=0)
    return np.vstack([state, anchors])


@pytest.mark.parametrize("first_degree", [4, 2])
@pytest.mark.parametrize("ending", [False, True], ids=["walking", "ending"])
@pytest.mark.parametrize(("inside", "fraction"), [(1, 0.37), (1, 0.93), (0, 0.45)], ids=["single", "late", "double"])
def test_plan_from_a_state_inside_a_phase_reproduces_the_plan_it_lies_on(inside, fraction, ending, first_degree):
    """Replan at an instant inside phase ``inside`` of an existing plan (its single support, or its free double
    support entered midway), from the state of that plan there and with the same anchors: the unique connected
    plan is the existing one, on the rest of that phase and on every later segment."""
    kinds, durations = (ENDING_KINDS, ENDING_DURATIONS) if ending else (WALK_KINDS, WALK_DURATIONS)
    w = omega(0.8)
    old_key = PatternKey(kinds, durations, w, first_degree)
    y = walk_inputs(PlanOperator(old_key).n_anchors, seed=11)
    old_op = PlanOperator(old_key)
    old = plan_trajectory(old_op, y)
    phase_start, phase_end = old.zmp.breaks[inside], old.zmp.breaks[inside + 1]
    t_star = phase_start + fraction * (phase_end - phase_start)

    new_key = PatternKey(kinds[inside:], (phase_end - t_star, *durations[inside + 1 :]), w, first_degree)
    new_op = PlanOperator(new_key)
    assert new_op.n_anchors == old_op.n_anchors  # anchor_0 is where the phase under way ends, in both
    pos, vel, _ = old.evaluate(t_star)
    state = np.vstack([old.zmp.evaluate(t_star), old.zmp.evaluate(t_star, 1), pos, vel])
    new_y = np.vstack([state, y[4:]])
    new = plan_trajectory(new_op, new_y, t0=t_star)
    check_connected_plan(new, new_key, new_y)

    # Later segments: the same numbers.
    old_data, new_data = old_op.solve(y), new_op.solve(new_y)
    scale = 1.0 + np.max(np.abs(old_data))
    np.testing.assert_allclose(new_data[1:], old_data[inside + 1 :], rtol=0, atol=1e-9 * scale)
    # The remainder of the phase: the same functions of time. (For the 56 ms remainder ("late") the quartic's
    # monomials, ~1/T^4, carry round-off of a few nm into the ZMP: see ``agreement``.)
    times = np.linspace(t_star, phase_end, 25)
    atol = 1e-9 if phase_end - t_star >= 0.1 else 1e-8
    np.testing.assert_allclose(new.zmp.evaluate(times), old.zmp.evaluate(times, side="left"), rtol=0, atol=atol)
    for got, expected in zip(new.evaluate(times), old.evaluate(times, side="left"), strict=True):
        np.testing.assert_allclose(got, expected, rtol=0, atol=atol)


@pytest.mark.parametrize("first_degree", [4, 2])
@pytest.mark.parametrize("ending", [False, True], ids=["walking", "ending"])
def test_plan_from_inside_a_single_support_meets_every_connection_condition(ending, first_degree):
    """From a state off any plan (a push in the middle of a step): ZMP at both ends of the remainder, COG state at
    the start, continuity, end conditions; the double support after the remainder goes to anchor_1."""
    kinds = ("single", "double", "single", "end", "settle") if ending else ("single", "double", "single", "double")
    durations = (0.33, 0.2, 0.8, 1.0, 0.5) if ending else (0.33, 0.2, 0.8, 0.2)
    key = PatternKey(kinds, durations, omega(0.8), first_degree)
    op = PlanOperator(key)
    assert op.n_anchors == 3
    y = walk_inputs(3, seed=4)
    y[1] = [0.3, -0.2]  # the ZMP moving (a measured state)
    y[3] = [0.4, 0.3]
    cog = plan_trajectory(op, y, t0=2.0)
    check_connected_plan(cog, key, y)
    # Anchor bookkeeping, read off the ZMP: the remainder ends on anchor_0 (the stance foot), the double support
    # carries it to anchor_1, the single support holds anchor_1, the last phase ends on anchor_2.
    breaks = cog.zmp.breaks
    for t, anchor in [(breaks[1], 0), (breaks[2], 1), (breaks[3], 1), (breaks[-1], 2)]:
        np.testing.assert_allclose(cog.zmp.evaluate(t, side="left")[0], y[4 + anchor], rtol=0, atol=1e-9)


@pytest.mark.parametrize("first", ["start", "single", "double", "end"])
def test_plan_operator_accepts_any_first_kind(first):
    kinds = (first, "single", "double", "single") if first != "end" else ("end", "settle")
    key = PatternKey(kinds, (0.3,) * len(kinds), 3.5, 4)
    op = PlanOperator(key)
    assert op.n_segments == len(kinds)
    assert op.n_anchors == 1 + sum(kind in MOVING for kind in kinds[1:])
    assert op.G.shape == (len(kinds) * SEGMENT_WIDTH, 4 + op.n_anchors)


@pytest.mark.parametrize(
    ("key", "field"),
    [
        (PatternKey(("settle",), (0.5,), 3.5, 4), "at least 2 segments"),
        (PatternKey(("double", "walking"), (0.2, 0.8), 3.5, 4), "kinds"),
        (PatternKey(("double", "single"), (0.2,), 3.5, 4), "durations"),
        (PatternKey(("double", "single"), (0.2, math.nan), 3.5, 4), "durations"),
        (PatternKey(("double", "single"), (0.0, 0.8), 3.5, 4), "durations"),
        (PatternKey(("double", "single"), (0.2, 0.8), math.inf, 4), "w"),
        (PatternKey(("double", "single"), (0.2, 0.8), 3.5, 3), "first_degree"),
        (PatternKey(("end", "settle"), (1.0, 0.01), 3.5, 4), "settle"),
    ],
)
def test_plan_operator_rejects_impossible_patterns(key, field):
    with pytest.raises(ValueError, match=field):
        PlanOperator(key)
