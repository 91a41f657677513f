"""ZMP splines, the closed-form pendulum solution (eqs. 3, 5-7) and the boundary-value problem (eqs. 8-12).

Truth used here never comes from the code under test: the pendulum ODE itself, polynomial algebra done with
``numpy.polynomial``, finite differences, and numerical integration with ``scipy.integrate.solve_ivp``.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial import polynomial as npoly
from scipy.integrate import solve_ivp

from rtgait.core.lipm.bvp import BoundaryValueSolver, bvp_matrix, component_propagators
from rtgait.core.lipm.closed_form import GRAVITY, CogTrajectory, omega, particular_matrix
from rtgait.core.lipm.spline import PiecewisePolynomial, evaluate_polynomials

SETTINGS = settings(max_examples=40, deadline=None)


# ----- strategies and independent helpers -------------------------------------------------------------------
@st.composite
def spline_problems(draw, max_segments: int = 12, max_duration: float = 1.0, min_degree: int = 1,
                    min_duration: float = 0.05):  # fmt: skip
    """A random ZMP spline (degree min_degree..5, 1..max_segments segments, two axes), ``w`` and end positions.

    Degree 0 is left to :func:`test_bvp_with_piecewise_constant_zmp` (known failure, see there).
    """
    m = draw(st.integers(1, max_segments))
    degree = draw(st.integers(min_degree, 5))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    durations = rng.uniform(min_duration, max_duration, m)
    # Coefficients scaled so that each term stays O(1) m over its segment.
    coeffs = rng.uniform(-1.0, 1.0, (m, degree + 1, 2)) / durations[:, None, None] ** np.arange(degree + 1)[:, None]
    t0 = draw(st.floats(-5.0, 5.0))
    cog_height = draw(st.floats(0.3, 1.2))
    c_start = rng.uniform(-1.0, 1.0, 2)
    c_end = rng.uniform(-1.0, 1.0, 2)
    zmp = PiecewisePolynomial(t0, durations, coeffs)
    return zmp, omega(cog_height), c_start, c_end


def zmp_direct(zmp: PiecewisePolynomial, t: float, segment: int, derivative: int = 0) -> np.ndarray:
    """ZMP (or a derivative) of one segment at absolute ``t`` by numpy.polynomial, per axis."""
    breaks = np.concatenate(([zmp.t0], zmp.t0 + np.cumsum(zmp.durations)))
    tau = t - breaks[segment]
    return np.array(
        [
            npoly.polyval(tau, npoly.polyder(zmp.coeffs[segment, :, axis], derivative))
            for axis in range(zmp.coeffs.shape[2])
        ]
    )


def segment_times(zmp: PiecewisePolynomial, per_segment: int = 25, margin: float = 0.0) -> list[np.ndarray]:
    """Sample times strictly inside each segment (``margin`` s away from its ends)."""
    breaks = np.concatenate(([zmp.t0], zmp.t0 + np.cumsum(zmp.durations)))
    return [np.linspace(a + margin, b - margin, per_segment)[1:-1] for a, b in itertools.pairwise(breaks)]


# ----- the spline itself ----------------------------------------------------------------------------------
@SETTINGS
@given(spline_problems())
def test_spline_evaluation_matches_numpy_polynomials(problem):
    zmp, _, _, _ = problem
    for j, times in enumerate(segment_times(zmp)):
        for derivative in (0, 1, 2):
            got = zmp.evaluate(times, derivative)
            expected = np.array([zmp_direct(zmp, t, j, derivative) for t in times])
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-9)


@SETTINGS
@given(spline_problems(max_segments=6))
def test_spline_left_and_right_limits_at_breaks(problem):
    zmp, _, _, _ = problem
    breaks = zmp.t0 + np.concatenate(([0.0], np.cumsum(zmp.durations)))
    for j in range(1, zmp.durations.size):
        left = zmp.evaluate(breaks[j], side="left")[0]
        right = zmp.evaluate(breaks[j], side="right")[0]
        # Left limit: end of segment j - 1 (sum of its coefficients times T^i); right limit: start of segment j.
        expected_left = np.array([npoly.polyval(zmp.durations[j - 1], zmp.coeffs[j - 1, :, a]) for a in range(2)])
        np.testing.assert_allclose(left, expected_left, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(right, zmp.coeffs[j, 0], rtol=1e-12, atol=1e-12)


def test_spline_geometry_and_clamping():
    zmp = PiecewisePolynomial(2.0, np.array([0.5, 1.5]), np.array([[[1.0], [2.0]], [[3.0], [0.0]]]))
    np.testing.assert_allclose(zmp.breaks, [2.0, 2.5, 4.0])
    assert zmp.t_end == pytest.approx(4.0)
    assert zmp.degree == 1
    # Outside the covered interval the spline holds its end values.
    assert zmp.evaluate(1.0)[0, 0] == pytest.approx(1.0)
    assert zmp.evaluate(10.0)[0, 0] == pytest.approx(3.0)


@pytest.mark.parametrize(
    ("durations", "coeffs"),
    [
        ([1.0, 0.0], np.zeros((2, 2))),
        ([1.0, -0.5], np.zeros((2, 2))),
        ([math.nan], np.zeros((1, 2))),
        ([math.inf], np.zeros((1, 2))),
        ([], np.zeros((0, 2))),
        ([1.0], np.array([[math.nan, 0.0]])),
        ([1.0, 1.0], np.zeros((3, 2))),
    ],
)
def test_spline_rejects_bad_input(durations, coeffs):
    with pytest.raises(ValueError, match=r"durations|coeffs"):
        PiecewisePolynomial(0.0, np.array(durations, dtype=float), coeffs)


# ----- particular solution (eqs. 6-7) and omega -------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 8), st.floats(0.5, 10.0), st.integers(0, 2**32 - 1))
def test_particular_matrix_solves_the_pendulum_equation_for_polynomials(degree, w, seed):
    a = np.random.default_rng(seed).uniform(-1.0, 1.0, degree + 1)
    A = particular_matrix(degree, w) @ a
    # Substitute c = sum A_i tau^i into p = c - c''/w^2 and compare coefficients with the ZMP polynomial.
    substituted = npoly.polysub(A, npoly.polyder(A, 2) / w**2)
    scale = 1.0 + np.max(np.abs(A))  # the back-substitution adds terms up to (2k)!/w^2k in size
    np.testing.assert_allclose(np.pad(substituted, (0, degree + 1 - substituted.size)), a, rtol=0, atol=1e-14 * scale)
    # The two top coefficients carry over unchanged (eq. 6).
    assert A[degree] == a[degree]
    if degree >= 1:
        assert A[degree - 1] == a[degree - 1]


def test_particular_matrix_rejects_negative_degree_and_is_read_only():
    with pytest.raises(ValueError, match="degree"):
        particular_matrix(-1, 3.0)
    Q = particular_matrix(3, 3.0)
    with pytest.raises(ValueError):
        Q[0, 0] = 2.0


def test_omega_is_sqrt_g_over_height():
    assert omega(0.8) == pytest.approx(math.sqrt(9.81 / 0.8))
    assert omega(1.0, gravity=1.62) == pytest.approx(math.sqrt(1.62))
    assert pytest.approx(9.81) == GRAVITY


@pytest.mark.parametrize(("height", "gravity", "field"), [(0.0, 9.81, "cog_height"), (-1.0, 9.81, "cog_height"),
                                                          (math.nan, 9.81, "cog_height"), (0.8, 0.0, "gravity"),
                                                          (0.8, math.inf, "gravity")])  # fmt: skip
def test_omega_rejects_bad_input(height, gravity, field):
    with pytest.raises(ValueError, match=field):
        omega(height, gravity)


# ----- the boundary-value problem ---------------------------------------------------------------------------
def check_bvp_solution(zmp: PiecewisePolynomial, w: float, c_start, c_end, cog: CogTrajectory) -> None:
    """Everything that defines the BVP's solution (it is unique): ODE, continuity, both end positions."""
    # The pendulum equation p = c - c''/w^2 on dense samples of every segment, with the ZMP evaluated
    # independently of the spline class.
    for j, times in enumerate(segment_times(zmp, per_segment=40)):
        pos, _, acc = cog.evaluate(times)
        p = np.array([zmp_direct(zmp, t, j) for t in times])
        assert np.max(np.abs(p - (pos - acc / w**2))) < 1e-9
        assert np.max(np.abs(cog.pendulum_residual(times))) < 1e-9

    # Position and velocity continuous at every junction (left and right limits).
    breaks = zmp.t0 + np.concatenate(([0.0], np.cumsum(zmp.durations)))
    for tj in breaks[1:-1]:
        left = cog.evaluate(tj, side="left")
        right = cog.evaluate(tj, side="right")
        np.testing.assert_allclose(left[0], right[0], rtol=0, atol=1e-9)
        np.testing.assert_allclose(left[1], right[1], rtol=0, atol=1e-9)
        # The pendulum equation also holds at the left limit (ZMP of the segment that ends there).
        p_left = zmp.evaluate(tj, side="left")
        assert np.max(np.abs(p_left - (left[0] - left[2] / w**2))) < 1e-9

    # End conditions.
    np.testing.assert_allclose(cog.evaluate(zmp.t0)[0][0], c_start, rtol=0, atol=1e-9)
    np.testing.assert_allclose(cog.evaluate(zmp.t_end, side="left")[0][0], c_end, rtol=0, atol=1e-9)


@SETTINGS
@given(spline_problems())
def test_bvp_solution_satisfies_pendulum_equation_continuity_and_ends(problem):
    zmp, w, c_start, c_end = problem
    check_bvp_solution(zmp, w, c_start, c_end, BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end))


@pytest.mark.parametrize("m", [1, 3])
def test_bvp_with_piecewise_constant_zmp(m):
    """The classic footstep ZMP: constant on every segment. method.md allows any degree n_j >= 0."""
    w = omega(0.8)
    zmp = PiecewisePolynomial(0.0, np.full(m, 0.6), np.linspace(-0.1, 0.1, m).reshape(m, 1, 1))
    c_start, c_end = np.array([0.0]), np.array([0.05])
    check_bvp_solution(zmp, w, c_start, c_end, BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end))


@SETTINGS
@given(spline_problems(max_segments=5, min_duration=0.2))
def test_cog_derivatives_match_finite_differences(problem):
    # Segments of at least 0.2 s: shorter quintic segments have particular coefficients (eq. 7 multiplies by
    # (i+1)(i+2)/w^2 per step) whose round-off, divided by h, swamps a finite difference.
    zmp, w, c_start, c_end = problem
    cog = BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end)
    h = 1e-6
    for times in segment_times(zmp, per_segment=12, margin=3 * h):
        pos_p, vel_p, _ = cog.evaluate(times + h)
        pos_m, vel_m, _ = cog.evaluate(times - h)
        _, vel, acc = cog.evaluate(times)
        scale = 1.0 + np.max(np.abs(pos_p))
        np.testing.assert_allclose(vel, (pos_p - pos_m) / (2 * h), rtol=0, atol=2e-6 * scale)
        np.testing.assert_allclose(acc, (vel_p - vel_m) / (2 * h), rtol=0, atol=2e-5 * scale)


@SETTINGS
@given(spline_problems())
def test_closed_form_agrees_with_numerical_integration_of_the_ode(problem):
    """On each segment, integrate c'' = w^2 (c - p) from the closed form's state at the segment start."""
    zmp, w, c_start, c_end = problem
    cog = BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end)
    breaks = zmp.t0 + np.concatenate(([0.0], np.cumsum(zmp.durations)))
    for j in range(zmp.durations.size):
        a, b = breaks[j], breaks[j + 1]
        pos0, vel0, _ = cog.evaluate(a, side="right")
        times = np.linspace(a, b, 9)

        def rhs(t, y, j=j):
            p = zmp_direct(zmp, t, j)
            return np.concatenate([y[2:], w**2 * (y[:2] - p)])

        sol = solve_ivp(rhs, (a, b), np.concatenate([pos0[0], vel0[0]]), method="DOP853", t_eval=times,
                        rtol=1e-12, atol=1e-13)  # fmt: skip
        assert sol.success
        pos, vel, _ = cog.evaluate(times[:-1])
        pos_end, vel_end, _ = cog.evaluate(b, side="left")
        pos = np.vstack([pos, pos_end])
        vel = np.vstack([vel, vel_end])
        np.testing.assert_allclose(sol.y[:2].T, pos, rtol=0, atol=1e-8)
        np.testing.assert_allclose(sol.y[2:].T, vel, rtol=0, atol=1e-7)


@SETTINGS
@given(spline_problems(max_segments=5, max_duration=0.5))
def test_bvp_matches_an_independent_shooting_solution(problem):
    """Solve the same two-point problem by shooting with solve_ivp: c is affine in the unknown c'(t0)."""
    zmp, w, c_start, c_end = problem
    cog = BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end)
    breaks = zmp.t0 + np.concatenate(([0.0], np.cumsum(zmp.durations)))

    def shoot(v0: np.ndarray) -> list[np.ndarray]:
        """States ``[c, c']`` at every break, integrating segment by segment through the ZMP jumps."""
        y = np.concatenate([c_start, v0])
        states = [y]
        for j in range(zmp.durations.size):
            sol = solve_ivp(lambda t, y, j=j: np.concatenate([y[2:], w**2 * (y[:2] - zmp_direct(zmp, t, j))]),
                            (breaks[j], breaks[j + 1]), y, method="DOP853", rtol=1e-12, atol=1e-14)  # fmt: skip
            y = sol.y[:, -1]
            states.append(y)
        return states

    zero = shoot(np.zeros(2))
    unit = shoot(np.ones(2))
    slope = unit[-1][:2] - zero[-1][:2]  # d c(T) / d c'(t0), per axis (axes are independent)
    v0 = (c_end - zero[-1][:2]) / slope
    states = shoot(v0)
    _, vel0, _ = cog.evaluate(zmp.t0)
    np.testing.assert_allclose(vel0[0], v0, rtol=1e-7, atol=1e-7)
    for tj, y in zip(breaks, states, strict=True):
        pos, vel, _ = cog.evaluate(tj, side="left")
        np.testing.assert_allclose(pos[0], y[:2], rtol=0, atol=1e-7)
        np.testing.assert_allclose(vel[0], y[2:], rtol=0, atol=1e-6)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.01, 2.0), min_size=1, max_size=12), st.floats(1.0, 6.0))
def test_bvp_matrix_is_invertible_for_positive_durations(durations, w):
    M = bvp_matrix(np.array(durations), w)
    assert M.shape == (2 * len(durations), 2 * len(durations))
    assert np.linalg.matrix_rank(M) == M.shape[0]


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.01, 3.0), min_size=1, max_size=12), st.floats(1.0, 6.0), st.integers(0, 2**32 - 1))
def test_component_propagators_are_the_two_first_order_recursions(durations, w, seed):
    durations = np.array(durations)
    m = durations.size
    forward, backward = component_propagators(durations, w)
    assert forward.shape == backward.shape == (m, m)
    assert np.all(np.triu(forward, 1) == 0.0) and np.all(np.tril(backward, -1) == 0.0)
    kept = np.concatenate([forward[np.tril_indices(m)], backward[np.triu_indices(m)]])
    assert np.all((kept > 0.0) & (kept <= 1.0))
    # S_0 = e_0, S_{j+1} = e^{-w T_j} S_j + e_{j+1}; U_{m-1} = e^{-w T_{m-1}} d_{m-1}, U_j = e^{-w T_j} (U_{j+1} + d_j).
    e, d = np.random.default_rng(seed).uniform(-1.0, 1.0, (2, m))
    S, U = np.empty(m), np.empty(m)
    S[0] = e[0]
    for j in range(m - 1):
        S[j + 1] = math.exp(-w * durations[j]) * S[j] + e[j + 1]
    U[-1] = math.exp(-w * durations[-1]) * d[-1]
    for j in range(m - 2, -1, -1):
        U[j] = math.exp(-w * durations[j]) * (U[j + 1] + d[j])
    np.testing.assert_allclose(forward @ e, S, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(backward @ d, U, rtol=1e-13, atol=1e-15)
    # A leading batch axis gives each timing its own matrices (the sums of w T in another order: round-off only).
    batched = component_propagators(np.stack([durations, 2.0 * durations]), w)
    np.testing.assert_allclose(batched[0][0], forward, rtol=1e-13, atol=0)
    np.testing.assert_allclose(batched[1][1], component_propagators(2.0 * durations, w)[1], rtol=1e-13, atol=0)


@SETTINGS
@given(spline_problems())
def test_bvp_solved_by_divergent_and_convergent_sweeps_equals_the_dense_solve(problem):
    """Eqs. 8-12 rewritten in xi = c + c'/w and zeta = c - c'/w: two sweeps and a 2 x 2 system for the unknown
    zeta(t_0) and xi(t_m), with (xi + zeta)/2 = c at both ends. Same V, W as the factored dense matrix."""
    zmp, w, c_start, c_end = problem
    cog = BoundaryValueSolver(zmp.durations, w).solve(zmp, c_start, c_end)
    A = cog.particular
    zeros = np.zeros(zmp.durations.size)
    start = A[:, 0], evaluate_polynomials(A, zeros, 1)
    end = evaluate_polynomials(A, zmp.durations, 0), evaluate_polynomials(A, zmp.durations, 1)
    xi_start, zeta_start = start[0] + start[1] / w, start[0] - start[1] / w
    xi_end, zeta_end = end[0] + end[1] / w, end[0] - end[1] / w
    forward, backward = component_propagators(zmp.durations, w)
    decay = math.exp(-w * zmp.durations[-1])

    def sweeps(zeta0: np.ndarray, xi_final: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        jumps = np.vstack([zeta0 - zeta_start[0], zeta_end[:-1] - zeta_start[1:]])
        defects = np.vstack([xi_start[1:] - xi_end[:-1], xi_final - xi_end[-1]])
        return forward @ jumps, backward @ defects

    def ends(zeta0: np.ndarray, xi_final: np.ndarray) -> np.ndarray:
        S, U = sweeps(zeta0, xi_final)
        c0 = 0.5 * (U[0] + xi_start[0] + zeta0)
        c1 = 0.5 * (xi_final + S[-1] * decay + zeta_end[-1])
        return np.array([c0, c1])

    # The end positions are affine in (zeta0, xi_final), per axis: solve for them from three evaluations.
    zero, one = np.zeros(2), np.ones(2)
    base = ends(zero, zero)
    by_zeta, by_xi = ends(one, zero) - base, ends(zero, one) - base
    target = np.array([c_start, c_end]) - base
    det = by_zeta[0] * by_xi[1] - by_xi[0] * by_zeta[1]
    zeta0 = (target[0] * by_xi[1] - by_xi[0] * target[1]) / det
    xi_final = (by_zeta[0] * target[1] - target[0] * by_zeta[1]) / det
    S, U = sweeps(zeta0, xi_final)
    scale = 1.0 + np.max(np.abs(cog.V)) + np.max(np.abs(cog.W))
    np.testing.assert_allclose(0.5 * (U + S), cog.V, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(0.5 * (U - S), cog.W, rtol=0, atol=1e-10 * scale)


def test_solver_reuses_its_factorisation_for_different_splines():
    durations = np.array([0.2, 0.8, 0.2, 0.8])
    w = omega(0.8)
    solver = BoundaryValueSolver(durations, w)
    rng = np.random.default_rng(1)
    for _ in range(3):
        zmp = PiecewisePolynomial(0.0, durations, rng.uniform(-0.2, 0.2, (4, 4, 2)))
        cog = solver.solve(zmp, np.array([0.0, 0.1]), np.array([0.3, -0.1]))
        assert isinstance(cog, CogTrajectory)
        fresh = BoundaryValueSolver(durations, w).solve(zmp, np.array([0.0, 0.1]), np.array([0.3, -0.1]))
        np.testing.assert_array_equal(cog.V, fresh.V)
        np.testing.assert_array_equal(cog.W, fresh.W)


def test_constant_zmp_gives_the_textbook_cosh_solution():
    """Single segment, constant ZMP p: c(t) = p + ((c1 - p) sinh(w t) + (c0 - p) sinh(w (T - t))) / sinh(w T)."""
    w, T, p, c0, c1 = omega(0.8), 1.3, 0.1, -0.05, 0.2
    zmp = PiecewisePolynomial(0.0, np.array([T]), np.array([[[p], [0.0]]]))  # degree 1 with a zero slope
    cog = BoundaryValueSolver(np.array([T]), w).solve(zmp, np.array([c0]), np.array([c1]))
    t = np.linspace(0.0, T, 11)
    expected = p + ((c1 - p) * np.sinh(w * t) + (c0 - p) * np.sinh(w * (T - t))) / np.sinh(w * T)
    np.testing.assert_allclose(cog.evaluate(t)[0][:, 0], expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("durations", [[0.5, 0.0], [0.5, -0.1], [math.nan], [math.inf, 1.0], []])
def test_solver_rejects_bad_durations(durations):
    with pytest.raises(ValueError, match="durations"):
        BoundaryValueSolver(np.array(durations, dtype=float), 3.0)


def test_solver_rejects_mismatched_spline_and_non_finite_ends():
    solver = BoundaryValueSolver(np.array([0.5, 0.5]), 3.0)
    other = PiecewisePolynomial(0.0, np.array([0.5, 0.7]), np.zeros((2, 2, 1)))
    with pytest.raises(ValueError, match="durations"):
        solver.solve(other, np.zeros(1), np.zeros(1))
    good = PiecewisePolynomial(0.0, np.array([0.5, 0.5]), np.zeros((2, 2, 1)))
    with pytest.raises(ValueError):
        solver.solve(good, np.array([math.nan]), np.zeros(1))
    with pytest.raises(ValueError):
        solver.solve(good, np.zeros(1), np.array([math.inf]))
