"""The DCM bias estimator against a simulated pendulum whose estimated DCM is off the true one by a known bias."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.dcm_bias import DcmBiasEstimator, DcmBiasSettings

W = math.sqrt(9.81 / 0.64)  # 1/s, a G1-like pendulum
DT = 0.002


def walk(bias_of_time, seconds: float, seed: int = 0, zmp_noise: float = 0.01, dcm_noise: float = 0.001):
    """A pendulum balanced about a swaying reference by a DCM law on the estimator's unbiased DCM; the estimate is
    the true DCM plus ``bias_of_time(t)`` (world frame) and noise, the measured ZMP the true one plus noise. Returns
    the times, the true biases and the estimated ones."""
    rng = np.random.default_rng(seed)
    estimator = DcmBiasEstimator(W, DT)
    dcm = np.zeros(2)
    times, truth, estimates = [], [], []
    for k in range(int(seconds / DT)):
        t = k * DT
        bias, heading = bias_of_time(t)
        measured = dcm + bias + dcm_noise * rng.standard_normal(2)
        # The plant's ZMP, planned to sway 8 cm sideways at 0.7 Hz, with the law acting on the unbiased estimate.
        reference = np.array([0.0, 0.08 * math.sin(2.0 * math.pi * 0.7 * t)])
        zmp = reference + (1.0 + 2.0 / W) * (measured - estimator.bias - reference)
        estimated = estimator.update(tuple(measured), tuple(zmp + zmp_noise * rng.standard_normal(2)), heading)
        dcm = dcm + W * DT * (dcm - zmp)  # the true pendulum, driven by the true ZMP
        times.append(t)
        truth.append(bias)
        estimates.append(estimated)
    return np.array(times), np.array(truth), np.array(estimates)


def test_a_constant_bias_is_found_and_the_unbiased_dcm_follows_the_pendulum():
    bias = np.array([0.004, -0.0025])  # m: a G1 seed's COM error is a few millimetres
    times, truth, estimates = walk(lambda t: (bias, 0.0), 6.0)
    late = times > 3.0
    assert np.max(np.abs(estimates[late] - truth[late])) < 1e-3
    # Without a bias it stays near zero (what the walk's noise makes of it).
    times, _, estimates = walk(lambda t: (np.zeros(2), 0.0), 6.0, seed=1)
    assert np.max(np.abs(estimates[times > 3.0])) < 1e-3


def test_the_bias_turns_with_the_body():
    body = np.array([0.006, 0.0])  # m, in the body's frame

    def turning(t):
        heading = 0.5 * math.pi * min(t / 8.0, 1.0)  # a quarter turn over 8 s
        c, s = math.cos(heading), math.sin(heading)
        return np.array([c * body[0] - s * body[1], s * body[0] + c * body[1]]), heading

    times, truth, estimates = walk(turning, 10.0)
    assert np.max(np.abs(estimates[times > 9.0] - truth[times > 9.0])) < 1e-3
    assert abs(estimates[-1][1] - 0.006) < 1e-3  # the bias ended along y


def test_the_bias_is_clamped_and_bad_inputs_are_refused():
    _, _, estimates = walk(lambda t: (np.array([0.05, -0.05]), 0.0), 4.0)
    limit = DcmBiasSettings().max_bias
    assert np.max(np.abs(estimates)) <= limit + 1e-12
    assert np.allclose(estimates[-1], [limit, -limit])
    with pytest.raises(ValueError, match="w must be"):
        DcmBiasEstimator(0.0, DT)
    with pytest.raises(ValueError, match="dt must be"):
        DcmBiasEstimator(W, -1.0)
    with pytest.raises(ValueError, match="zmp_error"):
        DcmBiasSettings(zmp_error=0.0)
    with pytest.raises(ValueError, match="dcm must be finite"):
        DcmBiasEstimator(W, DT).update((math.nan, 0.0), (0.0, 0.0), 0.0)


def test_the_filter_is_the_same_at_any_control_period():
    """The noises are densities: the bias's step response at 1 ms and at 5 ms agree."""

    def response(dt):
        estimator = DcmBiasEstimator(W, dt)
        values = []
        for _ in range(int(3.0 / dt)):
            # At rest the DCM is over the ZMP: an estimate that stays 5 mm off it is biased by 5 mm.
            values.append(estimator.update((0.005, 0.0), (0.0, 0.0), 0.0)[0])
        return np.array(values)[int(0.25 / dt) - 1 :: int(0.25 / dt)]

    fine, coarse = response(0.001), response(0.005)
    assert abs(fine[-1] - 0.005) < 2e-4
    assert np.allclose(fine, coarse, atol=5e-4)
