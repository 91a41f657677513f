"""The DCM feedback law against independent truth: the pendulum integrated in closed form or by scipy, the nearest
point of a polygon by brute force, and the steady states and poles that the error equations predict."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.spatial import ConvexHull

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.polygon import project_to_polygon
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.laws.feedback import DcmFeedback, DcmFeedbackGains
from rtgait.core.lipm.closed_form import omega

W = omega(0.8)  # 1/s, a COM 0.8 m high
BIG = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # counter-clockwise, never reached
FOOT = np.array([[-0.10, -0.07], [0.13, -0.07], [0.13, 0.07], [-0.10, 0.07]])  # one sole around the origin (m)
SETTINGS = settings(max_examples=60, deadline=None)


def pendulum_step(c: np.ndarray, cd: np.ndarray, p: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact solution of ``c'' = w^2 (c - p)`` over ``dt`` with ``p`` held (the ZMP of one control tick)."""
    x = c - p
    ch, sh = math.cosh(W * dt), math.sinh(W * dt)
    return p + x * ch + cd * sh / W, x * W * sh + cd * ch


def closed_loop(
    feedback: DcmFeedback | None,
    dcm_error: tuple[float, float],
    seconds: float,
    dt: float,
    polygon: np.ndarray = BIG,
    zmp_bias: tuple[float, float] = (0.0, 0.0),
    reference: tuple[float, float] = (0.0, 0.0),
) -> dict[str, np.ndarray]:
    """A COM at rest on ``reference`` (its ZMP and DCM), pushed so that its DCM is off by ``dcm_error``, under the
    feedback (``None``: open loop, ``p = p_ref``), with the robot realising the command plus ``zmp_bias``."""
    ref = np.asarray(reference, dtype=float)
    c, cd = ref.copy(), W * np.asarray(dcm_error, dtype=float)  # xi - xi_ref = c' / w
    errors, saturated, integrals = [], [], []
    for _ in range(round(seconds / dt) + 1):
        xi = c + cd / W
        errors.append(xi - ref)
        if feedback is None:
            p, flag = ref, False
        else:
            out = feedback.update(ref, ref, xi, polygon, dt)
            p, flag = np.asarray(out.zmp), out.saturated
            integrals.append(feedback.integral)
        saturated.append(flag)
        c, cd = pendulum_step(c, cd, p + np.asarray(zmp_bias), dt)
    t = dt * np.arange(len(errors))
    return {"t": t, "e": np.array(errors), "saturated": np.array(saturated), "integral": np.array(integrals)}


# ----- convergence under ideal ZMP tracking ----------------------------------------------------------------------
@pytest.mark.parametrize(("k_p", "dt"), [(2.0, 0.001), (3.0, 0.001), (5.0, 0.005)])
def test_dcm_error_decays_at_rate_kp(k_p: float, dt: float):
    e0 = np.array([0.03, -0.02])
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=k_p, k_i=0.0))
    run = closed_loop(feedback, tuple(e0), 3.0, dt)
    expected = np.exp(-k_p * run["t"])[:, None] * e0
    # Holding the command over a tick raises the rate by about (w + k_p) dt / 2 relative (0.3-2 %), which moves
    # e0 e^{-k_p t} by at most that times max(x e^{-x}) = 1/e of e0; twice that is allowed.
    assert np.max(np.abs(run["e"] - expected)) < (W + k_p) * dt / math.e * np.max(np.abs(e0))
    rate = -np.log(run["e"][-1] / e0) / run["t"][-1]
    np.testing.assert_allclose(rate, k_p, rtol=(W + k_p) * dt)
    assert not run["saturated"].any()


def test_dcm_error_decays_along_a_moving_reference_integrated_by_scipy():
    """A swaying ZMP reference with its exact bounded DCM; the robot is the pendulum integrated by solve_ivp. By
    linearity, the difference between a run with an initial DCM error and one without decays as ``e^{-k_p t}``."""
    k_p, dt, amp, freq = 2.5, 0.005, np.array([0.03, 0.08]), 2.0 * math.pi * 0.6

    def p_ref(t: float) -> np.ndarray:
        return amp * math.sin(freq * t)

    def xi_ref(t: float) -> np.ndarray:
        # The bounded solution of xi' = w (xi - p) for p = A sin(f t).
        scale = amp / (W**2 + freq**2)
        return scale * (W**2 * math.sin(freq * t) + W * freq * math.cos(freq * t))

    def run(e0: np.ndarray) -> np.ndarray:
        feedback = DcmFeedback(W, DcmFeedbackGains(k_p=k_p, k_i=0.0), dt=dt)
        # The reference COM is a sin(f t) with a = A w^2 / (w^2 + f^2); a DCM error e0 is a COM velocity w e0.
        c = np.zeros(2)
        cd = amp * W**2 / (W**2 + freq**2) * freq + W * e0
        state = np.concatenate([c, cd])
        errors = []
        for k in range(int(2.0 / dt)):
            t = k * dt
            xi = state[:2] + state[2:] / W
            errors.append(xi - xi_ref(t))
            p = np.asarray(feedback.update(p_ref(t), xi_ref(t), xi, BIG).zmp)
            sol = solve_ivp(
                lambda _t, s, p=p: np.concatenate([s[2:], W**2 * (s[:2] - p)]),
                (t, t + dt),
                state,
                rtol=1e-11,
                atol=1e-13,
            )
            state = sol.y[:, -1]
        return np.array(errors)

    e0 = np.array([0.02, -0.015])
    difference = run(e0) - run(np.zeros(2))
    t = dt * np.arange(len(difference))
    assert np.max(np.abs(difference - np.exp(-k_p * t)[:, None] * e0)) < 0.01 * np.max(np.abs(e0))


def test_without_proportional_gain_the_error_stays_and_open_loop_diverges():
    e0 = np.array([0.01, 0.005])
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=0.0, k_i=0.0))
    out = feedback.update(np.zeros(2), np.zeros(2), e0, BIG, 0.001)
    np.testing.assert_allclose(out.zmp, e0, atol=1e-15)  # p_cmd = p_ref + e: the ZMP sits on the DCM
    held = closed_loop(DcmFeedback(W, DcmFeedbackGains(k_p=0.0, k_i=0.0)), tuple(e0), 2.0, 0.001)
    np.testing.assert_allclose(held["e"], np.broadcast_to(e0, held["e"].shape), rtol=1e-9)
    free = closed_loop(None, tuple(e0), 1.0, 0.001)  # p = p_ref: xi' = w (xi - p) grows as e^{w t}
    np.testing.assert_allclose(free["e"], np.exp(W * free["t"])[:, None] * e0, rtol=1e-9)
    assert not DcmFeedbackGains(k_p=0.0, k_i=0.0).is_stable


# ----- saturation: projection onto the support polygon -----------------------------------------------------------
def brute_force_nearest(point: np.ndarray, polygon: np.ndarray, samples: int = 4000) -> tuple[np.ndarray, float]:
    """Nearest of ``samples`` points on each edge, and the spacing of those samples (m)."""
    start, end = polygon, np.roll(polygon, -1, axis=0)
    s = np.linspace(0.0, 1.0, samples)[:, None, None]
    boundary = (start[None] + s * (end - start)[None]).reshape(-1, 2)
    spacing = float(np.max(np.linalg.norm(end - start, axis=1))) / (samples - 1)
    return boundary[np.argmin(np.linalg.norm(boundary - point, axis=1))], spacing


def random_polygon(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    points = rng.normal(scale=rng.uniform(0.05, 0.3), size=(int(rng.integers(3, 12)), 2)) + rng.normal(size=2) * 0.1
    return points[ConvexHull(points).vertices]  # scipy orders 2-D hull vertices counter-clockwise


@SETTINGS
@given(st.integers(0, 10_000), st.floats(-0.8, 0.8), st.floats(-0.8, 0.8))
def test_commanded_zmp_is_the_nearest_point_of_the_polygon(seed: int, x: float, y: float):
    polygon = random_polygon(seed)
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=2.0, k_i=0.0))
    ref = polygon.mean(axis=0)
    out = feedback.update(ref, ref, np.array([x, y]), polygon, 0.001)
    wanted = np.asarray(out.zmp_unsaturated)
    np.testing.assert_allclose(wanted, ref + (1.0 + 2.0 / W) * (np.array([x, y]) - ref), atol=1e-15)
    assert signed_margin(np.asarray(out.zmp), polygon)[0] >= -1e-12
    inside = signed_margin(wanted, polygon)[0] >= 0.0
    assert out.saturated == (not inside)
    if inside:
        assert out.zmp == out.zmp_unsaturated
    else:
        nearest, spacing = brute_force_nearest(wanted, polygon)
        np.testing.assert_allclose(out.zmp, nearest, atol=spacing)
        # And no boundary point is nearer than the answer (the brute force is only an approximation of it).
        assert np.linalg.norm(wanted - out.zmp) <= np.linalg.norm(wanted - nearest) + 1e-12


@SETTINGS
@given(st.integers(0, 10_000))
def test_vectorised_projection_matches_brute_force(seed: int):
    polygon = random_polygon(seed)
    points = np.random.default_rng(seed + 1).uniform(-1.0, 1.0, size=(40, 2))
    projected = project_to_polygon(points, polygon)
    assert projected.shape == points.shape
    for point, answer in zip(points, projected, strict=True):
        if signed_margin(point, polygon)[0] >= 0.0:
            np.testing.assert_array_equal(answer, point)
        else:
            nearest, spacing = brute_force_nearest(point, polygon)
            np.testing.assert_allclose(answer, nearest, atol=spacing)
    np.testing.assert_allclose(project_to_polygon(points[0], polygon), projected[0])


def test_real_support_polygons_are_accepted_and_a_mutated_polygon_is_seen():
    sole = SoleRect(front=0.13, back=0.10, inner=0.07, outer=0.07)
    double = support_polygon([Footstep(0.0, 0.095, 0.3, "left"), Footstep(0.1, -0.095, -0.2, "right")], sole)
    single = support_polygon([Footstep(0.0, 0.095, 0.3, "left")], sole)
    feedback = DcmFeedback(W, dt=0.001)
    far = np.array([2.0, 2.0])
    for polygon in (double, single):
        out = feedback.update(polygon.mean(axis=0), polygon.mean(axis=0), far, polygon)
        np.testing.assert_allclose(out.zmp, project_to_polygon(np.asarray(out.zmp_unsaturated), polygon), atol=1e-15)
    # The polygon is cached between ticks; changing the array in place must not leave a stale one.
    polygon = FOOT.copy()
    first = feedback.update(np.zeros(2), np.zeros(2), far, polygon).zmp
    polygon += 0.5
    second = feedback.update(np.zeros(2), np.zeros(2), far, polygon).zmp
    np.testing.assert_allclose(first, (0.13, 0.07))
    np.testing.assert_allclose(second, (0.63, 0.57))


# ----- integral action and anti-windup ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("k_i", "leak"),
    [(0.0, None), (1.0, None), (1.0 / 3.0, 15.0), (2.0, 5.0)],
)
def test_integral_action_against_a_constant_zmp_bias(k_i: float, leak: float | None):
    """The robot realises ``p_cmd + d``. Then ``e' = -k_p e - k_i I - w d`` with ``I' = e - I / T``, whose steady
    state is ``e = -w d / (k_p + k_i T)``: ``-w d / k_p`` without integral, zero with a pure integral."""
    k_p, d = 2.0, np.array([0.01, -0.006])
    gains = DcmFeedbackGains(k_p=k_p, k_i=k_i, integrator_time_constant=leak)
    run = closed_loop(DcmFeedback(W, gains), (0.0, 0.0), 60.0, 0.005, zmp_bias=tuple(d))
    if k_i == 0.0:
        expected = -W * d / k_p
    elif leak is None:
        expected = np.zeros(2)
    else:
        expected = -W * d / (k_p + k_i * leak)
    np.testing.assert_allclose(run["e"][-1], expected, atol=1e-6)
    if k_i > 0.0:
        assert np.all(np.abs(run["e"][-1]) < 0.5 * np.abs(W * d / k_p))  # better than proportional alone


def test_integrator_does_not_wind_up_while_saturated():
    dt, k_i = 0.005, 1.0
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=2.0, k_i=k_i, integrator_time_constant=None), dt=dt)
    zero = np.zeros(2)
    small = np.array([0.01, 0.005])  # inside the sole: the law is unsaturated and integrates
    for _ in range(200):
        assert not feedback.update(zero, zero, small, FOOT).saturated
    charged = np.array(feedback.integral)
    np.testing.assert_allclose(charged, 200 * dt * small, rtol=1e-12)
    far = np.array([0.5, 0.3])  # 30 s with the command on the boundary: a naive integral would gain 15 m s
    for _ in range(6000):
        assert feedback.update(zero, zero, far, FOOT).saturated
    np.testing.assert_array_equal(feedback.integral, charged)
    # Back at the reference, the command is just the small integral term: no wound-up excursion.
    back = feedback.update(zero, zero, zero, FOOT)
    np.testing.assert_allclose(back.zmp, k_i / W * charged, atol=1e-15)
    # With a leak the frozen integral decays instead, as exp(-t / T).
    leaky = DcmFeedback(W, DcmFeedbackGains(k_p=2.0, k_i=k_i, integrator_time_constant=10.0), dt=dt)
    for _ in range(200):
        leaky.update(zero, zero, small, FOOT)
    charged = np.array(leaky.integral)
    for _ in range(2000):
        leaky.update(zero, zero, far, FOOT)
    np.testing.assert_allclose(leaky.integral, charged * math.exp(-10.0 / 10.0), rtol=1e-9)
    leaky.reset()
    assert leaky.integral == (0.0, 0.0)


def test_capturability_inside_recovers_outside_does_not():
    """With the ZMP bounded by the sole, a DCM inside it is brought back by the ankle alone (here through a
    saturated command), while one just outside escapes whatever the ZMP does."""
    gains = DcmFeedbackGains(k_p=3.0, k_i=0.0)
    inside = closed_loop(DcmFeedback(W, gains), (0.12, 0.0), 4.0, 0.002, polygon=FOOT)
    assert inside["saturated"].any()
    assert np.max(np.abs(inside["e"][-1])) < 1e-4
    corner = closed_loop(DcmFeedback(W, gains), (0.12, 0.06), 4.0, 0.002, polygon=FOOT)
    assert corner["saturated"].any() and np.max(np.abs(corner["e"][-1])) < 1e-4
    outside = closed_loop(DcmFeedback(W, gains), (0.135, 0.0), 1.0, 0.002, polygon=FOOT)
    margin = signed_margin(outside["e"], FOOT)  # the reference sits at the origin, so e is the DCM itself
    assert outside["saturated"].all()
    assert np.all(np.diff(margin) < 0.0) and margin[-1] < -0.01


# ----- stability condition ---------------------------------------------------------------------------------------
def test_default_gains_are_stable_and_match_the_error_equations():
    gains = DcmFeedbackGains()
    assert 1.0 <= gains.k_p <= 5.0 and gains.k_i >= 0.0 and gains.is_stable
    T = gains.integrator_time_constant
    assert T is not None
    # e' = -k_p e - k_i I, I' = e - I / T, as a matrix, independently of the library's pole formula.
    A = np.array([[-gains.k_p, -gains.k_i], [1.0, -1.0 / T]])
    eigenvalues = np.sort_complex(np.linalg.eigvals(A))
    np.testing.assert_allclose(np.sort_complex(np.array(gains.error_poles())), eigenvalues, atol=1e-12)
    assert np.all(eigenvalues.real < 0.0)
    dt, e0 = 0.001, np.array([0.02, -0.01])
    run = closed_loop(DcmFeedback(W, gains), tuple(e0), 8.0, dt)
    for k in (500, 2000, 8000):
        truth = np.array([expm(A * k * dt) @ np.array([e, 0.0]) for e in e0])  # (e, I) per axis
        np.testing.assert_allclose(run["e"][k], truth[:, 0], atol=0.004 * np.max(np.abs(e0)))
        # The library's integral enters the next tick: the one stored after tick k is the integral at k + 1.
        np.testing.assert_allclose(run["integral"][k - 1], truth[:, 1], atol=0.004 * np.max(np.abs(e0)))
    assert np.max(np.abs(run["e"][-1])) < 0.03 * np.max(np.abs(e0))


def test_pole_formula_and_stability_flag_over_gains():
    for k_p, k_i, T in [(2.0, 0.0, None), (2.0, 1.0, None), (0.0, 1.0, 20.0), (0.0, 0.0, 20.0), (5.0, 10.0, 10.0)]:
        gains = DcmFeedbackGains(k_p=k_p, k_i=k_i, integrator_time_constant=T)
        leak = 0.0 if T is None else 1.0 / T
        roots = np.roots([1.0, k_p + leak, k_i + k_p * leak])
        np.testing.assert_allclose(np.sort_complex(np.array(gains.error_poles())), np.sort_complex(roots), atol=1e-9)
        decays = k_p > 0.0 or bool(np.all(roots.real < 0.0))
        assert gains.is_stable == decays


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("k_p", -0.5),
        ("k_p", math.nan),
        ("k_p", 25.0),
        ("k_i", -1.0),
        ("k_i", math.inf),
        ("integrator_time_constant", 0.0),
        ("integrator_time_constant", math.nan),
        ("com_admittance", -0.1),
        ("com_offset_time_constant", None),
        ("max_com_offset", -0.01),
        ("max_zmp_speed", 0.0),
        ("max_zmp_speed", math.inf),
        ("k_p", True),
        ("k_p", "2"),
    ],
)
def test_invalid_gains_raise_naming_the_field(field: str, value: object):
    with pytest.raises(ValueError, match=field):
        DcmFeedbackGains(**{field: value})


def test_invalid_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="w must be"):
        DcmFeedback(0.0)
    with pytest.raises(ValueError, match="dt must be"):
        DcmFeedback(W, dt=-0.001)
    feedback = DcmFeedback(W)
    zero = np.zeros(2)
    with pytest.raises(ValueError, match="dt must be given"):
        feedback.update(zero, zero, zero, FOOT)
    with pytest.raises(ValueError, match="dt must be"):
        feedback.update(zero, zero, zero, FOOT, math.nan)
    with pytest.raises(ValueError, match="dcm must be finite"):
        feedback.update(zero, zero, np.array([0.0, math.nan]), FOOT, 0.001)
    with pytest.raises(ValueError, match="zmp_measured must be finite"):
        feedback.update(zero, zero, zero, FOOT, 0.001, np.array([math.inf, 0.0]))
    with pytest.raises(ValueError, match="dcm_ref must be a pair"):
        feedback.update(zero, np.zeros(3), zero, FOOT, 0.001)
    with pytest.raises(ValueError, match="counter-clockwise"):
        feedback.update(zero, zero, zero, FOOT[::-1], 0.001)
    with pytest.raises(ValueError, match="convex"):
        feedback.update(zero, zero, zero, np.array([[0, 0], [1, 0], [0.2, 0.2], [0, 1]]), 0.001)
    star = np.array([[math.cos(a), math.sin(a)] for a in 4.0 * math.pi / 5.0 * np.arange(5)])  # winds twice
    e, f = np.roll(star, -1, 0) - star, np.roll(star, -2, 0) - np.roll(star, -1, 0)
    assert np.all(e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0] > 0.0)  # every turn is to the left, yet it is no polygon
    with pytest.raises(ValueError, match="winding once"):
        feedback.update(zero, zero, zero, star, 0.001)
    with pytest.raises(ValueError, match="k >= 3"):
        feedback.update(zero, zero, zero, FOOT[:2], 0.001)
    with pytest.raises(ValueError, match="finite"):
        feedback.update(zero, zero, zero, np.where(FOOT > 0.1, math.nan, FOOT), 0.001)


# ----- ZMP speed limit -------------------------------------------------------------------------------------------
def test_zmp_speed_limit_bounds_the_command_and_freezes_the_integral():
    dt, speed = 0.001, 0.5
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=2.0, k_i=1.0, max_zmp_speed=speed), dt=dt)
    zero, step = np.zeros(2), np.array([0.03, 0.04])  # a 5 cm jump of the measured DCM
    offsets, flags = [np.zeros(2)], []
    for _ in range(300):
        out = feedback.update(zero, zero, step, BIG)
        offsets.append(np.asarray(out.zmp))
        flags.append(out.saturated)
        if out.saturated:
            wanted = np.asarray(out.zmp_unsaturated)
    moves = np.linalg.norm(np.diff(offsets, axis=0), axis=1)
    assert np.all(moves <= speed * dt * (1.0 + 1e-12))
    limited = int(np.sum(flags))
    # The jump of (1 + k_p / w) * 5 cm takes that long at 0.5 m/s, and the command keeps its direction meanwhile.
    assert limited == math.ceil((1.0 + 2.0 / W) * 0.05 / (speed * dt)) - 1
    np.testing.assert_allclose(offsets[limited] / np.linalg.norm(offsets[limited]), step / 0.05, atol=1e-12)
    assert not any(flags[limited + 1 :])
    assert out.zmp == out.zmp_unsaturated  # once caught up, the command is the law's again
    np.testing.assert_allclose(offsets[limited + 1], wanted, atol=1e-15)  # reached the target it aimed at


# ----- COM correction --------------------------------------------------------------------------------------------
def test_com_offset_opposes_the_zmp_error_leaks_and_is_clamped():
    """``p = c - c''/w^2``: a COM pulled back (negative velocity step, hence a negative acceleration) raises the
    ZMP, so a ZMP measured below the command must give a negative offset velocity, of ``A (p_cmd - p_meas)``."""
    dt, A, T_c = 0.001, 1.5, 10.0
    gains = DcmFeedbackGains(k_p=2.0, k_i=0.0, com_admittance=A, com_offset_time_constant=T_c, max_com_offset=0.03)
    feedback = DcmFeedback(W, gains, dt=dt)
    zero = np.zeros(2)
    low = np.array([-0.02, 0.01])  # measured ZMP: 2 cm behind and 1 cm left of the command (which is p_ref here)
    out = feedback.update(zero, zero, zero, FOOT, zmp_measured=low)
    np.testing.assert_allclose(out.com_offset_vel, A * low, rtol=1e-3)  # -A (p_cmd - p_meas) = A p_meas
    np.testing.assert_allclose(out.com_offset, np.asarray(out.com_offset_vel) * dt, rtol=1e-12)
    # The ZMP of the pendulum whose COM follows the offset from rest: over the tick of the velocity step,
    # p = c - c''/w^2 averages c - (v_1 - 0) / (w^2 dt): it moves toward the command, against the error.
    mean_zmp = np.asarray(out.com_offset) / 2.0 - np.asarray(out.com_offset_vel) / (W**2 * dt)
    assert np.all(np.sign(mean_zmp) == -np.sign(low))
    # Held error: the offset grows to its clamp and stays there.
    for _ in range(40_000):
        out = feedback.update(zero, zero, zero, FOOT, zmp_measured=low)
    np.testing.assert_allclose(out.com_offset, (-0.03, 0.03))  # unclamped it would settle at A T_c p_meas
    np.testing.assert_allclose(out.com_offset_vel, (0.0, 0.0), atol=1e-12)
    # No error: it leaks back to zero as exp(-t / T_c).
    start = np.array(feedback.com_offset)
    for _ in range(5000):
        out = feedback.update(zero, zero, zero, FOOT, zmp_measured=zero)
    np.testing.assert_allclose(out.com_offset, start * math.exp(-5.0 / T_c), rtol=1e-9)


def test_com_offset_without_measured_zmp_follows_the_dcm_law():
    """Without a measured ZMP the robot is taken to realise ``p_ref``, so the error is the law's own correction."""
    dt, A = 0.001, 1.0
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=2.0, k_i=0.0, com_admittance=A), dt=dt)
    e = np.array([0.01, -0.004])
    out = feedback.update(np.zeros(2), np.zeros(2), e, FOOT)
    np.testing.assert_allclose(out.com_offset_vel, -A * (1.0 + 2.0 / W) * e, rtol=1e-3)
    off = DcmFeedback(W, DcmFeedbackGains(), dt=dt).update(np.zeros(2), np.zeros(2), e, FOOT, zmp_measured=-e)
    assert off.com_offset == (0.0, 0.0)  # the default admittance is off


def test_points_on_or_just_inside_the_boundary_are_not_saturated():
    feedback = DcmFeedback(W, DcmFeedbackGains(k_p=0.0, k_i=0.0), dt=0.001)  # p_cmd = the measured DCM
    zero = np.zeros(2)
    for point in [(0.13, 0.0), (0.13, 0.07), (-0.10, -0.07), (0.13 - 1e-7, 0.07 - 1e-7), (0.0, -0.07 + 1e-7)]:
        out = feedback.update(zero, zero, np.array(point), FOOT)
        assert not out.saturated and out.zmp == point
    out = feedback.update(zero, zero, np.array([0.13 + 1e-7, 0.0]), FOOT)
    assert out.saturated
    np.testing.assert_allclose(out.zmp, (0.13, 0.0), atol=1e-15)
