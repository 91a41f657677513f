"""Appendix A: the Fourier-series COG correction that cancels the angular momentum's ZMP shift."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rtgait.core.lipm.angular import angular_zmp_offset, fit_correction

W = float(np.sqrt(9.81 / 0.8))
BREAKS = np.array([0.0, 1.0, 1.8, 2.0, 2.8, 3.0, 5.0])


def synthetic_offset(times: np.ndarray, order: int, seed: int) -> np.ndarray:
    """A ZMP shift that is exactly a Fourier series of ``order`` on every segment of BREAKS (m)."""
    rng = np.random.default_rng(seed)
    index = np.clip(np.searchsorted(BREAKS, times, side="right") - 1, 0, len(BREAKS) - 2)
    f = np.zeros((len(times), 2))
    for j in range(len(BREAKS) - 1):
        mask = index == j
        period = BREAKS[j + 1] - BREAKS[j]
        tau = (times[mask] - BREAKS[j])[:, None]
        f[mask] += rng.normal(scale=0.01, size=2)
        for i in range(1, order + 1):
            a, b = rng.normal(scale=0.01, size=(2, 2))
            f[mask] += a * np.cos(2 * np.pi * i * tau / period) + b * np.sin(2 * np.pi * i * tau / period)
    return f


@pytest.mark.parametrize("order", [0, 1, 3, 5])
def test_correction_solves_the_pendulum_equation_for_the_offset(order):
    times = np.linspace(BREAKS[0], BREAKS[-1], 4001)
    f = synthetic_offset(times, order, seed=order)
    correction = fit_correction(times, f, BREAKS, W, order)
    # The signal lies in the span of the series: the least-squares fit must reproduce it.
    assert np.abs(correction.offset(times) - f).max() < 1e-12
    dc, _, ddc = correction.evaluate(times)
    assert np.abs(dc - ddc / W**2 - f).max() < 1e-9
    # The correction starts and ends at zero: the corrected COG keeps the plan's ends.
    assert np.abs(dc[0]).max() < 1e-12 and np.abs(dc[-1]).max() < 1e-12


def test_correction_is_continuous_in_position_and_velocity():
    times = np.linspace(BREAKS[0], BREAKS[-1], 2001)
    correction = fit_correction(times, synthetic_offset(times, 3, seed=7), BREAKS, W, 3)
    eps = 1e-8
    for b in BREAKS[1:-1]:
        before = correction.evaluate(np.array([b - eps]))
        after = correction.evaluate(np.array([b + eps]))
        assert np.abs(before[0] - after[0]).max() < 1e-8
        assert np.abs(before[1] - after[1]).max() < 1e-6


def test_derivatives_match_finite_differences():
    times = np.linspace(0.0, 5.0, 3001)
    correction = fit_correction(times, synthetic_offset(times, 3, seed=3), BREAKS, W, 3)
    t = np.array([0.5, 1.3, 2.5, 4.1])
    h = 1e-5
    pos_p, vel_p, _ = correction.evaluate(t + h)
    pos_m, vel_m, _ = correction.evaluate(t - h)
    _, vel, acc = correction.evaluate(t)
    assert np.allclose((pos_p - pos_m) / (2 * h), vel, atol=1e-7)
    assert np.allclose((vel_p - vel_m) / (2 * h), acc, atol=1e-6)


def test_correction_matches_numerical_integration():
    """Integrate dc'' = w^2 (dc - f) from the closed form's own initial state over one segment."""
    times = np.linspace(0.0, 5.0, 5001)
    correction = fit_correction(times, synthetic_offset(times, 2, seed=11), BREAKS, W, 2)
    t0, t1 = BREAKS[1], BREAKS[2]
    dc0, vel0, _ = correction.evaluate(np.array([t0 + 1e-12]))

    def rhs(t, state):
        f = correction.offset(np.array([t]))[0]
        return np.concatenate([state[2:], W**2 * (state[:2] - f)])

    solution = solve_ivp(rhs, (t0, t1), np.concatenate([dc0[0], vel0[0]]), rtol=1e-11, atol=1e-13, dense_output=True)
    t = np.linspace(t0, t1 - 1e-9, 50)
    assert np.abs(solution.sol(t)[:2].T - correction.evaluate(t)[0]).max() < 1e-8


def test_angular_zmp_offset_signs():
    """A positive pitch rate (about +y) pushes the ZMP back along -x, a positive roll rate (about +x) along +y;
    the offset to cancel is their opposite."""
    rate = np.array([[0.0, 2.0, 0.0], [3.0, 0.0, 0.0]])
    offset = angular_zmp_offset(rate, mass=50.0, gravity=10.0)
    assert offset[0] == pytest.approx([2.0 / 500.0, 0.0])
    assert offset[1] == pytest.approx([0.0, -3.0 / 500.0])


def test_bad_inputs():
    times = np.linspace(0.0, 5.0, 101)
    f = np.zeros((101, 2))
    with pytest.raises(ValueError, match="order"):
        fit_correction(times, f, BREAKS, W, -1)
    with pytest.raises(ValueError, match="finite"):
        fit_correction(times, np.full((101, 2), np.nan), BREAKS, W, 1)
    with pytest.raises(ValueError, match="samples"):
        fit_correction(times, f, BREAKS, W, 10)  # 0.2 s segments hold 5 samples, order 10 needs 21
    with pytest.raises(ValueError, match="breaks"):
        fit_correction(times, f, BREAKS[::-1], W, 1)
