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
