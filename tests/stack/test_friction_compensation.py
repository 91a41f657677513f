"""The friction compensation of the feed-forward: a share of the description's friction, opposing nothing at rest
and along the reference's motion when it moves; on a joint with Coulomb friction, integrated here on its own, it
removes the dead band a low-gain drive leaves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.stack.friction_compensation import (
    IDENTIFIED_FRACTION,
    STICTION_SPEED,
    FrictionCompensation,
    identified_friction,
)


def test_moving_joints_get_the_fraction_of_coulomb_and_viscous_friction() -> None:
    compensation = FrictionCompensation(np.array([2.4, 1.2]), np.array([0.24, 0.12]), fraction=0.5)
    velocity = np.array([2.0, -3.0])  # 40 and 60 times the stiction speed: tanh is 1 to 1e-30
    expected = 0.5 * np.array([2.4 + 0.24 * 2.0, -(1.2 + 0.12 * 3.0)])
    np.testing.assert_allclose(compensation.torques(velocity), expected, rtol=1e-12)


def test_rest_gets_none_and_the_sign_is_smoothed() -> None:
    compensation = FrictionCompensation(np.array([1.0]), np.array([0.0]))
    assert compensation.torques(np.zeros(1))[0] == 0.0
    at_speed = compensation.torques(np.array([STICTION_SPEED]))[0]
    assert at_speed == pytest.approx(IDENTIFIED_FRACTION * math.tanh(1.0))
    assert compensation.torques(np.array([-STICTION_SPEED]))[0] == pytest.approx(-at_speed)


def test_the_robots_motor_types_give_the_friction() -> None:
    pytest.importorskip("pinocchio")
    from rtgait.robot.model import RobotModel

    g1 = RobotModel.load("g1")
    compensation = FrictionCompensation.of(g1)
    knee = g1.joint_names.index("left_knee_joint")
    assert compensation.coulomb[knee] == pytest.approx(IDENTIFIED_FRACTION * 2.4)  # N7520-22.5's 2.4 N m
    assert compensation.viscous[knee] == pytest.approx(IDENTIFIED_FRACTION * 0.24)
    assert len(compensation.coulomb) == len(g1.joint_names)
    friction = identified_friction(g1)
    np.testing.assert_array_equal(friction.coulomb * IDENTIFIED_FRACTION, compensation.coulomb)


# G1's swinging ankle roll: armature and foot (kg m^2), Unitree's example gains, the 2xN5020-16 pair's friction.
INERTIA, KP, KD, COULOMB, VISCOUS = 0.01, 40.0, 1.0, 1.2, 0.12
CONTROL_DT, STEP = 0.002, 1e-4  # the 500 Hz command; the joint's integration step (s)
AMPLITUDE, FREQUENCY = 0.1, 1.0  # the reference: a 0.1 rad, 1 Hz sine (up to 0.63 rad/s, a swinging ankle's)
STOPPED = 1e-6  # rad/s: the integration's standstill


def _track(compensation: FrictionCompensation | None, scale: float) -> tuple[float, float]:
    """A joint of inertia INERTIA with Coulomb and viscous friction ``scale`` times the identified ones, under the drive
    ``tau = tau_ff + kp (q_ref - q) + kd (dq_ref - dq)`` at every step, its command (the reference sampled each
    CONTROL_DT, its finite difference, the compensation at it) applied one period late, as G1's bus does. Friction by
    Karnopp's stick-slip model: a joint at rest stays there while less than F_c acts on it. Returns the tracking
    error's RMS (rad) and the share of the ticks the joint stood still while its reference moved faster than
    0.05 rad/s, over 2 s after a 1 s start."""
    coulomb, viscous = scale * COULOMB, scale * VISCOUS
    q = dq = previous = 0.0
    command = (0.0, 0.0, 0.0)
    errors, still, moving = [], 0, 0
    for k in range(round(3.0 / CONTROL_DT)):
        t = k * CONTROL_DT
        reference = AMPLITUDE * math.sin(2.0 * math.pi * FREQUENCY * t)
        velocity = (reference - previous) / CONTROL_DT
        previous = reference
        feed = 0.0 if compensation is None else float(compensation.torques(np.array([velocity]))[0])
        (q_ref, dq_ref, tau_ff), command = command, (reference, velocity, feed)
        for _ in range(round(CONTROL_DT / STEP)):
            tau = tau_ff + KP * (q_ref - q) + KD * (dq_ref - dq)
            if abs(dq) < STOPPED and abs(tau) <= coulomb:
                dq = 0.0  # stuck
            else:
                sign = math.copysign(1.0, dq if abs(dq) >= STOPPED else tau)
                after = dq + STEP * (tau - coulomb * sign - viscous * dq) / INERTIA
                dq = 0.0 if abs(dq) >= STOPPED and after * dq < 0.0 else after  # through zero: stop, then decide
            q += STEP * dq
        if t >= 1.0:
            errors.append(reference - q)
            if abs(velocity) > 0.05:
                moving += 1
                still += dq == 0.0
    return math.sqrt(float(np.mean(np.square(errors)))), still / moving


@pytest.mark.parametrize("scale", [0.7, 1.0, 1.3])
def test_the_compensated_joint_tracks_where_the_uncompensated_one_sticks(scale: float) -> None:
    """The true friction 0.7, 1 and 1.3 times the identified one (the compensation's): without compensation the
    joint lags its reference by its dead band F_c / kp (30 mrad at 1.2 N m on 40 N m/rad) and stands still for a
    fifth or more of the moving reference's ticks; compensated, it tracks within the residual friction's band
    |F_c - F_c,identified| / kp (+ 2 mrad) and hardly sticks."""
    bare_rms, bare_still = _track(None, scale)
    rms, still = _track(FrictionCompensation(np.array([COULOMB]), np.array([VISCOUS])), scale)
    dead_band = scale * COULOMB / KP
    assert bare_rms > 0.6 * dead_band
    assert bare_still > 0.2
    residual = abs(scale - IDENTIFIED_FRACTION) * COULOMB / KP
    assert rms < residual + 0.002
    assert rms < 0.5 * bare_rms
    assert still < 0.5 * bare_still


@pytest.mark.parametrize(
    ("coulomb", "viscous", "fraction", "speed"),
    [([-1.0], [0.0], 0.7, 0.05), ([1.0], [0.0, 1.0], 0.7, 0.05), ([1.0], [0.0], 1.5, 0.05), ([1.0], [0.0], 0.7, 0.0)],
)
def test_bad_settings_are_refused(coulomb, viscous, fraction, speed) -> None:
    with pytest.raises(ValueError):
        FrictionCompensation(np.array(coulomb), np.array(viscous), fraction, speed)
