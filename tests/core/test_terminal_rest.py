"""The walk ends at rest: a plan whose last phase is ``"settle"`` brings the COG to a stop over the last anchor.

The settle segment's ZMP is the anchor plus ``alpha tau^2 (T - tau)^2 / T^4`` (``rtgait.core.lipm.connect.rest_bump``)
with one more condition, ``c'(t_end) = 0``. Checked here on the trajectory itself, whatever the settle time: COG
position, velocity and acceleration at the end, the pendulum equation on the settle segment, and the ZMP's
position and velocity continuous where the settle phase begins.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import polynomial as npoly

from rtgait.core.geometry.footsteps import Stride, Timing
from rtgait.core.lipm.closed_form import CogTrajectory, omega
from rtgait.core.lipm.connect import MIN_REST_W_T, ConnectionSolver, rest_bump
from rtgait.core.lipm.pattern import DEGREE, PatternKey, PlanOperator
from rtgait.core.lipm.spline import PiecewisePolynomial

W = omega(0.8)
SETTLE_TIMES = (0.1, 0.3, 2.0)

# Windows of walks as the planner plans them near the end: from a double-support start, and from the middle of
# a single support or of the final double support (a mid-phase replan: first segment = the phase's remainder).
ENDINGS = {
    "three steps to go": (("double", "single", "double", "single", "double", "single", "end", "settle"),
                          (0.2, 0.8, 0.2, 0.8, 0.2, 0.8, 1.0)),
    "last step": (("double", "single", "end", "settle"), (0.1, 0.7, 1.0)),
    "final double support": (("end", "settle"), (1.0,)),
    "inside the last single support": (("single", "end", "settle"), (0.35, 0.8)),
    "inside the final double support": (("end", "settle"), (0.4,)),
    "short end phase": (("double", "single", "end", "settle"), (0.2, 0.8, 0.2)),
}  # fmt: skip


def plan_of(kinds, durations, first_degree: int, y: np.ndarray) -> CogTrajectory:
    op = PlanOperator(PatternKey(kinds, durations, W, first_degree))
    data = op.solve(y)
    zmp = PiecewisePolynomial(0.0, op.durations, data[:, : DEGREE + 1])
    return CogTrajectory(zmp, data[:, -2], data[:, -1], W)


def random_inputs(n_anchors: int, seed: int) -> np.ndarray:
    """``y`` with a moving COG and ZMP and anchors a few steps apart (m, m/s)."""
    rng = np.random.default_rng(seed)
    state = rng.uniform(-0.3, 0.3, (4, 2))
    anchors = np.cumsum(rng.uniform(-0.2, 0.3, (n_anchors, 2)), axis=0)
    return np.vstack([state, anchors])


CASES = [
    pytest.param(kinds, (*head, settle), first_degree, id=f"{name}-{settle}s-q{first_degree}")
    for name, (kinds, head) in ENDINGS.items()
    for settle in SETTLE_TIMES
    for first_degree in (4, 2)
]


@pytest.mark.parametrize(("kinds", "durations", "first_degree"), CASES)
def test_plan_ending_in_settle_stops_over_the_last_anchor(kinds, durations, first_degree):
    n_anchors = 1 + sum(kind in ("start", "double", "end") for kind in kinds[1:])
    y = random_inputs(n_anchors, seed=len(kinds) + int(100 * durations[-1]))
    cog = plan_of(kinds, durations, first_degree, y)
    t_end, t_settle = cog.zmp.t_end, cog.zmp.breaks[-2]
    pos, vel, acc = cog.evaluate(t_end, side="left")
    np.testing.assert_allclose(pos[0], y[-1], rtol=0, atol=1e-9)
    assert np.max(np.abs(vel)) < 1e-9
    assert np.max(np.abs(acc)) < 1e-9
    # The ZMP ends at the anchor, at rest: so the pendulum stays at rest afterwards.
    np.testing.assert_allclose(cog.zmp.evaluate(t_end, side="left")[0], y[-1], rtol=0, atol=1e-12)
    assert np.max(np.abs(cog.zmp.evaluate(t_end, 1, side="left"))) < 1e-9

    # (b) p = c - c''/w^2 on the settle segment, to round-off: relative to the terms the closed form adds up
    # (random states with a short settle ask for big bumps, hence big cancelling V, W and A).
    times = np.linspace(t_settle, t_end, 101)
    T = durations[-1]
    terms = np.abs(cog.V[-1]) * np.cosh(W * T) + np.abs(cog.W[-1]) * np.sinh(W * T)
    terms = terms + np.abs(cog.particular[-1]).T @ T ** np.arange(DEGREE + 1)
    assert np.all(np.max(np.abs(cog.pendulum_residual(times)), axis=0) < 1e-14 * (1.0 + terms))

    # (c) ZMP position and velocity continuous where the settle phase begins (left vs right limit), and the
    # settle ZMP is the anchor plus a multiple of the bump: it vanishes with its derivative at both ends. (Only
    # the quadratic first segment, by design, leaves the ZMP velocity free at its own end.)
    quadratic_before_settle = first_degree == 2 and len(kinds) == 2
    for derivative in (0,) if quadratic_before_settle else (0, 1):
        left = cog.zmp.evaluate(t_settle, derivative, side="left")
        right = cog.zmp.evaluate(t_settle, derivative, side="right")
        np.testing.assert_allclose(left, right, rtol=0, atol=1e-10)
    settle_coeffs = cog.zmp.coeffs[-1]
    np.testing.assert_allclose(settle_coeffs[0], y[-1], rtol=0, atol=1e-15)
    alpha = settle_coeffs[4] * durations[-1] ** 4
    np.testing.assert_allclose(settle_coeffs[1:], rest_bump(durations[-1])[1:, None] * alpha, rtol=1e-12, atol=1e-12)
    # COG position and velocity continuous too.
    for tj in cog.zmp.breaks[1:-1]:
        left, right = cog.evaluate(tj, side="left"), cog.evaluate(tj, side="right")
        np.testing.assert_allclose(left[0], right[0], rtol=0, atol=1e-10)
        np.testing.assert_allclose(left[1], right[1], rtol=0, atol=1e-10)


def test_the_old_terminal_condition_left_the_cog_moving_and_the_bump_is_what_changed():
    """Same walk end with and without the rest condition (a last phase that holds the anchor but is not
    'settle'): without it, 0.3 s of settling leaves the COG moving at several cm/s; with it the COG stops, the
    reference segments are untouched and the settle segment's ZMP differs by the bump only (the free first
    segment differs too: the whole plan adapts)."""
    kinds_rest = ("double", "single", "end", "settle")
    kinds_free = ("double", "single", "end", "single")  # 'single' holds the anchor like 'settle', no rest
    durations = (0.2, 0.8, 1.0, 0.3)
    y = random_inputs(2, seed=3)
    rest = plan_of(kinds_rest, durations, 4, y)
    free = plan_of(kinds_free, durations, 4, y)
    t_end = rest.zmp.t_end
    assert np.max(np.abs(free.evaluate(t_end, side="left")[1])) > 0.01
    assert np.max(np.abs(rest.evaluate(t_end, side="left")[1])) < 1e-9
    np.testing.assert_array_equal(rest.zmp.coeffs[1:-1], free.zmp.coeffs[1:-1])
    difference = rest.zmp.coeffs[-1] - free.zmp.coeffs[-1]
    alpha = difference[4] * durations[-1] ** 4
    np.testing.assert_allclose(difference, rest_bump(durations[-1])[:, None] * alpha, rtol=1e-12, atol=1e-12)


def test_connection_solver_option_brings_the_cog_to_rest():
    """The dense reference formulation (one more unknown column, one more row) does the same for any reference."""
    durations = np.array([0.2, 0.8, 0.2, 0.5])
    rng = np.random.default_rng(5)
    reference = rng.uniform(-0.2, 0.2, (3, 4, 2))
    c_end = reference[-1, 0] + reference[-1, 1] * 0.5 + reference[-1, 2] * 0.25 + reference[-1, 3] * 0.125
    solver = ConnectionSolver(durations, W, degree=3, first_degree=4, terminal_rest=True)
    assert solver.n_unknowns == 5 + 2 * 4 + 1
    cog = solver.solve(0.0, reference, [0.0, 0.1], [0.2, 0.0], [0.01, 0.05], [0.1, -0.2], c_end)
    pos, vel, acc = cog.evaluate(cog.zmp.t_end, side="left")
    np.testing.assert_allclose(pos[0], c_end, rtol=0, atol=1e-9)
    assert np.max(np.abs(vel)) < 1e-9
    # The reference ends at c_end here, so the acceleration vanishes too.
    assert np.max(np.abs(acc)) < 1e-9
    # The last segment's ZMP is its reference plus alpha times the bump, by numpy.polynomial.
    last = cog.zmp.coeffs[-1]
    bump = npoly.polymul(npoly.polymul([0.0, 1.0], [0.0, 1.0]), npoly.polymul([0.5, -1.0], [0.5, -1.0])) / 0.5**4
    alpha = (last[4] / bump[4])[None]
    np.testing.assert_allclose(last[:4] - reference[-1], bump[:4, None] * alpha, rtol=0, atol=1e-10)


def test_settle_too_short_to_stop_is_refused():
    shortest = MIN_REST_W_T / W
    PlanOperator(PatternKey(("end", "settle"), (1.0, 1.001 * shortest), W, 4))
    with pytest.raises(ValueError, match="settle"):
        PlanOperator(PatternKey(("end", "settle"), (1.0, 0.99 * shortest), W, 4))
    with pytest.raises(ValueError, match="settle"):
        ConnectionSolver(np.array([1.0, 0.5 * shortest]), W, terminal_rest=True)
    # Without the rest condition a short last segment is fine, as before.
    ConnectionSolver(np.array([1.0, 0.5 * shortest]), W)


WALKS = {
    "straight": [Stride(0.2, 0.19)] * 3 + [Stride(0.0, 0.19)],
    "in place": [Stride(0.0, 0.19)] * 3,
    "turning": [Stride(0.1, 0.19, 0.25)] * 3 + [Stride(0.0, 0.19, 0.0)],
    "sideways": [Stride(0.0, 0.25), Stride(0.0, 0.19)] * 2,
}


@pytest.mark.parametrize("settle", SETTLE_TIMES)
@pytest.mark.parametrize("walk", sorted(WALKS))
def test_online_walk_ends_at_rest_over_the_feet(settle, walk):
    # Imported here: the tests above exercise the operator alone and need nothing of the planner.
    from rtgait.core.planner.online import OnlinePlanner, PlannerConfig

    config = PlannerConfig(timing=Timing(0.8, 0.2, settle=settle))
    planner = OnlinePlanner(config, WALKS[walk])
    planner.start(0.0)
    t = 0.0
    while t < planner.end_time:  # one sample per 50 ms: every replan happens on the way
        planner.sample(t)
        t += 0.05
    end = planner.sample(planner.end_time)
    assert np.max(np.abs(end.cog_vel[:2])) < 1e-9
    assert np.max(np.abs(end.cog_acc[:2])) < 1e-9
    a, b = planner.footprints()[-2:]
    np.testing.assert_allclose(end.cog[:2], [0.5 * (a.x + b.x), 0.5 * (a.y + b.y)], rtol=0, atol=1e-9)
    np.testing.assert_allclose(end.zmp, end.cog[:2], rtol=0, atol=1e-9)
