"""Multibody check: finite differences, the ZMP of known motions, and the walking motion against its plan."""

from __future__ import annotations

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from rtgait.robot.dynamics import check_motion, finite_differences, multibody_check  # noqa: E402

GRAVITY = 9.81


def _screw_velocity(model) -> np.ndarray:
    """A velocity of every joint and a constant body twist of the base (a screw motion), shape ``(nv,)``."""
    velocity = np.zeros(model.nv)
    velocity[:6] = [0.3, -0.1, 0.05, 0.2, -0.4, 0.7]
    velocity[6:] = np.linspace(-0.2, 0.2, model.nv - 6)
    return velocity


def test_finite_differences_are_exact_for_constant_velocities(talos):
    # Joints moving at constant speed and the base moving with a constant body twist (a screw motion): the
    # configuration-space differences are exact, so v is that velocity and a is zero.
    model = talos.model
    dt = 0.01
    velocity = _screw_velocity(model)
    q = np.array([pin.integrate(model, talos.q_half_sitting, velocity * k * dt) for k in range(20)])
    v, a = finite_differences(model, q, dt)
    np.testing.assert_allclose(v, np.tile(velocity, (20, 1)), atol=1e-9)
    np.testing.assert_allclose(a, 0.0, atol=1e-6)
    with pytest.raises(ValueError, match="q must have shape"):
        finite_differences(model, q[:2], dt)
    with pytest.raises(ValueError, match="dt must be"):
        finite_differences(model, q, 0.0)


def test_static_posture_zmp_is_the_cog_projection(talos):
    # Any posture held still: no momentum, and the ZMP is right under the COG.
    q = talos.q_half_sitting.copy()
    q[7:] += np.linspace(-0.1, 0.1, talos.model.nq - 7)
    q[:3] = [0.3, -0.2, 1.0]
    times = np.arange(10) * 0.005
    check = multibody_check(talos.model, times, np.tile(q, (10, 1)))
    data = talos.model.createData()
    com = pin.centerOfMass(talos.model, data, q)
    np.testing.assert_allclose(check.zmp, np.tile(com[:2], (10, 1)), atol=1e-12)
    np.testing.assert_allclose(check.angular_momentum, 0.0, atol=1e-12)
    np.testing.assert_allclose(check.vertical_force, talos.mass * GRAVITY, rtol=1e-12)


def _translating_body(talos, ticks: int, dt: float):
    """Every joint locked, the whole robot translating along sines: times (s), configurations, COG (m), its
    acceleration (m/s^2) and the ZMP (m) in closed form. No angular momentum, so the ZMP is the point-mass one,
    p = c - c_z c''_xy / (g + c''_z)."""
    times = np.arange(ticks) * dt
    w = 2.0 * np.pi * np.array([0.5, 0.8, 1.1])
    amplitude = np.array([0.05, 0.04, 0.01])
    shift = amplitude * np.sin(w * times[:, None])
    q = np.tile(talos.q_half_sitting, (len(times), 1))
    q[:, :3] += shift
    cog = talos.cog_half_sitting + shift
    acc = -amplitude * w**2 * np.sin(w * times[:, None])
    expected = cog[:, :2] - cog[:, 2:3] * acc[:, :2] / (GRAVITY + acc[:, 2:3])
    return times, q, cog, acc, expected


def test_translating_body_zmp_follows_the_pendulum(talos):
    times, q, cog, acc, expected = _translating_body(talos, 1500, 0.002)
    check = multibody_check(talos.model, times, q)
    inner = slice(1, -1)  # the end ticks use one-sided differences
    np.testing.assert_allclose(check.cog, cog, atol=1e-12)
    np.testing.assert_allclose(check.cog_acc[inner], acc[inner], atol=1e-4)
    np.testing.assert_allclose(check.zmp[inner], expected[inner], atol=1e-5)
    np.testing.assert_allclose(check.angular_momentum, 0.0, atol=1e-9)
    np.testing.assert_allclose(check.angular_zmp_offset, 0.0, atol=1e-9)


def test_differences_do_not_span_a_break(talos):
    # Constant velocities on either side of a jump of every coordinate at tick 7: differentiated in two pieces, both
    # are exact; the ticks beside the jump use one-sided differences. Across it, the jump reads as an acceleration.
    model = talos.model
    dt = 0.01
    velocity = _screw_velocity(model)
    jumped = pin.integrate(model, talos.q_half_sitting, np.full(model.nv, 0.004))
    starts = [talos.q_half_sitting] * 7 + [jumped] * 13
    q = np.array([pin.integrate(model, start, velocity * k * dt) for k, start in enumerate(starts)])
    v, a = finite_differences(model, q, dt, breaks=[7])
    np.testing.assert_allclose(v, np.tile(velocity, (20, 1)), atol=1e-9)
    np.testing.assert_allclose(a, 0.0, atol=1e-6)
    across = finite_differences(model, q, dt)[1]
    assert np.abs(across[6:8]).max() > 0.5 * 0.004 / dt**2
    # Pieces of two ticks have one-sided velocities and no acceleration; of one tick, neither.
    v, a = finite_differences(model, q, dt, breaks=[2, 4, 5, 7])
    np.testing.assert_allclose(v[[0, 1, 2, 3, 5, 6]], np.tile(velocity, (6, 1)), atol=1e-9)
    assert np.isnan(a[:7]).all() and np.isnan(v[4]).all()
    np.testing.assert_allclose(a[7:], 0.0, atol=1e-6)
    with pytest.raises(ValueError, match=r"breaks must be ticks within \[1, 19\]"):
        finite_differences(model, q, dt, breaks=[0])


def test_a_jump_between_pieces_leaves_the_pendulum_zmp_as_it_was(talos):
    # The translating body again, moved 4 mm sideways at once at tick 400 (a reference re-anchored): split there, its
    # ZMP is the closed form's on both sides (within a millimetre at the two one-sided ticks); across the
    # jump, the second differences put it metres away.
    times, q, cog, _, expected = _translating_body(talos, 800, 0.002)
    q[400:, 1] += 0.004
    expected[400:, 1] += 0.004
    check = multibody_check(talos.model, times, q, breaks=[400])
    inner = np.r_[1:399, 401:799]
    np.testing.assert_allclose(check.zmp[inner], expected[inner], atol=1e-5)
    np.testing.assert_allclose(check.zmp[[399, 400]], expected[[399, 400]], atol=1e-3)
    spiked = multibody_check(talos.model, times, q).zmp
    assert np.abs(spiked[[399, 400], 1] - expected[[399, 400], 1]).min() > 1.0
    np.testing.assert_array_equal(spiked[inner[(inner < 398) | (inner > 401)]],
                                  check.zmp[inner[(inner < 398) | (inner > 401)]])  # fmt: skip
    # A piece of one tick has no acceleration, so no force nor ZMP; its COG is known.
    lone = multibody_check(talos.model, times, q, breaks=[400, 401])
    assert np.isnan(lone.zmp[400]).all() and np.isnan(lone.vertical_force[400])
    np.testing.assert_allclose(lone.cog[400], cog[400] + [0.0, 0.004, 0.0], atol=1e-12)


def test_walking_zmp_stays_close_to_the_plan(talos, talos_fig8, talos_fig8_motion):
    check = check_motion(talos_fig8_motion, talos_fig8)
    error_x, error_y = check.zmp_error_max
    # The multibody ZMP differs from the planned one by a few centimetres at most (32 mm / 11 mm on this walk).
    assert error_x < 0.05 and error_y < 0.02, (error_x, error_y)
    # The difference is the angular momentum of the swinging legs: without its rate, the multibody ZMP is the
    # planned pendulum ZMP to a fraction of a millimetre (the COG is tracked to micrometres at constant height).
    residual = np.abs(check.zmp_error - check.angular_zmp_offset).max(axis=0)
    assert residual.max() < 1e-3, residual
    assert np.abs(check.angular_zmp_offset).max() > 0.01  # the legs do carry angular momentum
    np.testing.assert_allclose(check.cog[:, 2], talos.description.cog_height, atol=1e-5)


def test_bad_arguments(talos):
    q = np.tile(talos.q_half_sitting, (5, 1))
    with pytest.raises(ValueError, match="uniformly spaced"):
        multibody_check(talos.model, np.array([0.0, 0.1, 0.3, 0.4, 0.5]), q)
    with pytest.raises(ValueError, match="planned_zmp must have shape"):
        multibody_check(talos.model, np.arange(5) * 0.1, q, np.zeros((5, 3)))
    with pytest.raises(ValueError, match="no planned ZMP"):
        _ = multibody_check(talos.model, np.arange(5) * 0.1, q).zmp_error
