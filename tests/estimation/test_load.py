"""The feet's load and landing detection (rtgait.estimation.load) on synthetic force traces whose true contact
instants are known: a foot that swings (no force), lands on a heel-strike ramp, carries the robot and lifts off, with
the white noise of a force sensor; and the estimator's threshold on torque-estimated wrenches against their noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from rtgait.estimation.kinematic_inertial import TORQUE_LANDING_FRACTION
from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME, LoadHysteresis
from rtgait.estimation.torque_wrenches import DEFAULT_WRENCH_CUTOFF

WEIGHT = 885.0  # N, Talos's
DT = 0.001  # s
STEP = 0.8  # s: 0.5 s carrying, 0.3 s in the air
RAMP = 0.02  # s from touch to full load, and from full load to lift-off


def _walk(steps: int, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """A foot's vertical force (N) every ``DT`` over ``steps`` steps, with white noise of ``noise`` N; whether it
    touches the ground (force > 0); and the instants it touches down (s)."""
    t = np.arange(round(steps * STEP / DT)) * DT
    phase = np.mod(t, STEP)
    air = 0.3
    rise = np.clip((phase - air) / RAMP, 0.0, 1.0)
    fall = np.clip((STEP - phase) / RAMP, 0.0, 1.0)
    force = np.where(phase >= air, 0.5 * WEIGHT * np.minimum(rise, fall), 0.0)
    touches = [k * STEP + air for k in range(steps)]
    noisy = force + noise * np.random.default_rng(seed).standard_normal(len(t))
    return noisy, force > 0.0, touches


def _detect(force: np.ndarray, load: LoadHysteresis) -> tuple[np.ndarray, list[float]]:
    load.reset()
    states, landings = [], []
    for k, f in enumerate(force):
        state = load.update(0, float(f), k * DT)
        if state is None:
            landings.append(k * DT)
        states.append(state is not False)
        load.prime()
    return np.array(states), landings


def _talos_load() -> LoadHysteresis:
    landing = DEFAULT_LANDING_FRACTION * WEIGHT
    return LoadHysteresis(landing, 0.5 * landing, DEFAULT_MIN_UNLOADED_TIME)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_ankle_sensor_sees_every_landing_within_a_few_milliseconds(seed):
    # 0.5 N of white noise (Talos's ankle sensors): the landing is seen as the ramp crosses the threshold, 25 N of a
    # 442 N ramp over 20 ms, 1.1 ms after the touch; the lift-off likewise before it.
    force, touching, touches = _walk(20, 0.5, seed)
    states, landings = _detect(force, _talos_load())
    assert len(landings) == len(touches)
    delays = np.array(landings) - np.array(touches)
    ramp_time = DEFAULT_LANDING_FRACTION * WEIGHT / (0.5 * WEIGHT) * RAMP
    assert np.all(delays >= 0.0) and np.all(delays <= ramp_time + 2 * DT)
    assert np.mean(states == touching) > 0.99


def test_a_scuff_shorter_than_the_least_flight_is_not_a_landing():
    force = np.full(400, 300.0)
    force[100:130] = 0.0  # 30 ms unloaded: a scuff
    force[200:300] = 0.0  # 100 ms: a flight
    states, landings = _detect(force, _talos_load())
    assert landings == [pytest.approx(0.3)]
    assert not states[100:130].any() and states[130:200].all()


def test_the_torque_threshold_stands_above_the_swing_noise_and_sees_the_heel_strike():
    # G1's filtered torque wrench on a swinging leg: 5.0 N RMS at its described sensor noise, here white noise
    # through the wrench's first-order low-pass. A minute of swing on both feet crosses the threshold nowhere; a heel
    # strike that loads the foot with half of G1's 327 N weight in 20 ms is seen within the ramp's time to the
    # threshold and the filter's time constant.
    weight, dt, sigma = 327.0, 0.002, 5.0
    beta = math.exp(-2.0 * math.pi * DEFAULT_WRENCH_CUTOFF * dt)
    white = np.random.default_rng(0).standard_normal(2 * round(60.0 / dt)) * sigma * math.sqrt((1 + beta) / (1 - beta))
    filtered = lfilter([1.0 - beta], [1.0, -beta], white)  # F_k = beta F_k-1 + (1 - beta) f_k
    assert np.std(filtered) == pytest.approx(sigma, rel=0.05)
    landing = TORQUE_LANDING_FRACTION * weight
    assert filtered.max() < landing
    ramp = np.clip(np.arange(100) * dt / RAMP, 0.0, 1.0) * 0.5 * weight
    seen = lfilter([1.0 - beta], [1.0, -beta], ramp)
    delay = np.argmax(seen > landing) * dt
    time_constant = -dt / math.log(beta)
    assert delay <= landing / (0.5 * weight) * RAMP + time_constant + dt
