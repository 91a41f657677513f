"""The estimator's two complementary filters against their equations: no lag where the sources agree, the
documented attenuation and offset where they do not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.attitude_filter import AttitudeFilter
from rtgait.estimation.velocity_filter import ComplementaryVelocity

DT = 0.001


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """The quaternion ``(w, x, y, z)`` of a turn by ``angle`` about the unit ``axis``."""
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])  # fmt: skip


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    return 2.0 * math.acos(min(1.0, abs(float(np.dot(a, b)))))


def test_the_velocity_filter_follows_consistent_sources_without_lag():
    # The accelerometer's reading is the mean acceleration over the period that ends at the tick: the velocity's
    # change over it divided by the period.
    f = ComplementaryVelocity(3.5)

    def velocity(t: float) -> tuple[float, float, float]:
        return (math.sin(3 * t), t * t, 0.2)

    for k in range(500):
        t = k * DT
        v = velocity(t)
        a = tuple((now - before) / DT for now, before in zip(v, velocity(t - DT), strict=True))
        out = f.update(DT if k else 0.0, v, a)
        assert out == pytest.approx(v, abs=1e-12)


def test_the_velocity_filter_keeps_the_kinematics_low_frequencies():
    # The kinematic velocity has a step the accelerometer does not see: it comes through with tau = 1 / (2 pi f_c).
    f = ComplementaryVelocity(3.5)
    tau = 1.0 / (2.0 * math.pi * 3.5)
    f.update(0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    out = None
    for _ in range(round(tau / DT)):
        out = f.update(DT, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert out[0] == pytest.approx(1.0 - math.exp(-1.0), abs=0.01)


def test_the_velocity_filter_has_noise_and_bias_as_its_cut_off_says_and_no_lag():
    # A plant whose velocity swings at 1.5 Hz (a walk's sway, steps and a push's rise): the legs' velocity with white
    # noise, the accelerometer's mean acceleration with white noise of density n and a bias b (G1's sensors). The
    # estimate errs by the low-passed leg noise, sigma sqrt(dt / 2 tau), the high-passed integrated accelerometer
    # noise, n sqrt(tau / 2), and b tau, and it is not late.
    rng = np.random.default_rng(7)
    dt, cutoff, sigma, density, bias = 0.002, 3.5, 0.025, 1.2e-3, 0.05
    tau = 1.0 / (2.0 * math.pi * cutoff)
    t = np.arange(0.0, 20.0, dt)
    truth = 0.3 * np.sin(2.0 * math.pi * 1.5 * t) + 0.1 * t
    legs = truth + rng.normal(0.0, sigma, t.size)
    accelerometer = np.diff(truth, prepend=truth[0]) / dt + bias + rng.normal(0.0, density / math.sqrt(dt), t.size)
    f = ComplementaryVelocity(cutoff)
    estimate = np.array([f.update(dt if k else 0.0, (legs[k], 0.0, 0.0), (accelerometer[k], 0.0, 0.0))[0]
                         for k in range(t.size)])  # fmt: skip
    error = (estimate - truth)[t > 5.0 * tau]
    noise = math.hypot(sigma * math.sqrt(dt / (2.0 * tau)), density * math.sqrt(tau / 2.0))
    assert abs(float(np.mean(error)) - bias * tau) < 0.2 * bias * tau
    assert float(np.std(error)) == pytest.approx(noise, rel=0.1)
    # The shift of the truth that fits the estimate best: none (a 3.5 Hz low-pass alone would be 45 ms late).
    late = [float(np.mean((estimate[20:] - truth[20 - lag : t.size - lag]) ** 2)) for lag in range(20)]
    assert int(np.argmin(late)) == 0


def test_the_velocity_filter_integrates_the_accelerometer_alone_without_legs():
    # In flight the legs measure nothing: the estimate is the last one plus the integrated acceleration, exactly.
    f = ComplementaryVelocity(3.5)
    f.update(0.0, (0.5, -0.2, 0.1), (0.0, 0.0, 0.0))
    for _ in range(50):
        out = f.update(DT, None, (1.0, 2.0, -9.81))
    assert out == pytest.approx((0.5 + 50 * DT, -0.2 + 100 * DT, 0.1 - 9.81 * 50 * DT), abs=1e-12)
    # It takes the legs' velocity up again where they have one.
    assert f.update(DT, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))[0] < out[0]


def test_the_attitude_filter_tracks_a_turn_the_gyro_measures():
    f = AttitudeFilter()
    axis, rate = np.array([0.6, 0.0, 0.8]), 1.5  # rad/s, about a fixed body axis
    q0 = axis_angle(np.array([1.0, 0.0, 0.0]), 0.1)
    for k in range(1000):
        q = multiply(q0, axis_angle(axis, rate * k * DT))
        out = f.update(DT if k else 0.0, tuple(q), tuple(rate * axis))
    assert angle_between(np.array(out), q) < 1e-5


def test_the_attitude_filter_smooths_white_noise_as_its_time_constant_says():
    rng = np.random.default_rng(0)
    sigma, f = 0.005, AttitudeFilter()
    q = axis_angle(np.array([0.0, 1.0, 0.0]), 0.2)
    errors = []
    for k in range(20000):
        noise = rng.normal(size=3) * sigma
        angle = float(np.linalg.norm(noise))
        noisy = multiply(axis_angle(noise / angle, angle), q)
        out = np.array(f.update(DT if k else 0.0, tuple(noisy), (0.0, 0.0, 0.0)))
        if k > 2000:
            errors.append(angle_between(out, q))
    tau = 1.0 / (2.0 * math.pi * f.cutoff)
    # Three axes of white noise sigma, each low-passed to sigma sqrt(dt / 2 tau): the angle's RMS is sqrt(3) that.
    expected = math.sqrt(3.0) * sigma * math.sqrt(DT / (2.0 * tau))
    assert math.sqrt(np.mean(np.square(errors))) == pytest.approx(expected, rel=0.1)


def test_the_filters_refuse_a_cut_off_that_is_not_positive():
    with pytest.raises(ValueError, match="cut-off"):
        ComplementaryVelocity(0.0)
    with pytest.raises(ValueError, match="cut-off"):
        AttitudeFilter(-1.0)
