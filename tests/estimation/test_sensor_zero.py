"""A foot sensor's zero learnt in the air (rtgait.estimation.sensor_zero) on synthetic readings whose offset is known:
a foot that swings with a ringing inertia and lands on a load, its sensor off by a fixed wrench, with white noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtgait.estimation.load import LoadHysteresis
from rtgait.estimation.sensor_zero import DEFAULT_SETTLE_TIME, AirborneZero

DT = 0.001  # s
STEP = 0.8  # s: 0.5 s carrying, 0.3 s in the air
OFFSET = (1.5, -2.0, 4.0, 0.2, -0.3, 0.1)  # N, N m: the sensor's error, as the sole wrench reads it
LOAD = 440.0  # N, half of Talos's weight


def _readings(steps: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The sole wrench a sensor reads every ``DT`` over ``steps`` steps (its offset, noise and, in the air, the foot's
    inertia: a 1.6 kg foot that rises and comes down, 300 N of ringing at 400 Hz after lift-off), and the true normal
    force."""
    t = np.arange(round(steps * STEP / DT)) * DT
    phase = np.mod(t, STEP)
    air = phase < 0.3
    true_fz = np.where(air, 0.0, LOAD)
    rng = np.random.default_rng(seed)
    wrench = np.tile(OFFSET, (len(t), 1)) + 0.5 * rng.standard_normal((len(t), 6))
    wrench[:, 2] += true_fz
    # The swing's inertia: 1.6 kg times a vertical acceleration whose mean over the ticks learnt from (after the
    # settle time) is nil: a foot at rest then, as after a lift-off's first 50 ms it nearly is (the module docstring).
    settle = DEFAULT_SETTLE_TIME
    swing = np.clip((phase - settle) / (0.3 - settle), 0.0, 1.0)
    wrench[:, 2] += np.where(air, 1.6 * 8.0 * np.sin(2.0 * math.pi * swing), 0.0)
    wrench[:, 2] += np.where(air, 300.0 * np.exp(-phase / 0.005) * np.sin(2.0 * math.pi * 400.0 * phase), 0.0)
    return wrench, true_fz


def _run(zero: AirborneZero, steps: int, seed: int = 0) -> list[tuple[float, ...]]:
    """The corrected sole wrenches of a walk, with the load detection reading their normal force."""
    wrench, _ = _readings(steps, seed)
    load = LoadHysteresis(25.0, 12.5, 0.05)
    out = []
    for k, w in enumerate(wrench):
        t = k * DT
        raw = tuple(float(x) for x in w)
        corrected = zero.corrected(0, raw)
        load.update(0, corrected[2], t)
        load.prime()
        zero.learn(0, corrected, DT if k else 0.0, load.air_time(0, t))
        out.append(corrected)
    return out


def test_the_zero_converges_to_the_sensors_offset_in_the_air():
    zero = AirborneZero()
    _run(zero, 40)  # 10 s in the air: five time constants
    # The swing's inertia averages out: each component within half a newton of its offset (the exponential average
    # weighs the last swing's end most: 13 N of inertia leave about 0.2 N).
    assert zero.zeros[0] == pytest.approx(OFFSET, abs=0.5)
    assert zero.zeros[1] == (0.0,) * 6  # the other foot never flew


def test_a_loaded_foot_and_a_fresh_lift_off_teach_nothing():
    zero = AirborneZero()
    zero.learn(0, (100.0,) * 6, DT, 0.0)  # loaded
    zero.learn(0, (100.0,) * 6, DT, DEFAULT_SETTLE_TIME - 2 * DT)  # the lift-off's ringing
    zero.learn(0, (100.0,) * 6, 0.0, 1.0)  # the first tick
    assert zero.zeros[0] == (0.0,) * 6
    zero.learn(0, (2.0, 0.0, 0.0, 0.0, 0.0, 0.0), DT, 1.0)  # an airborne tick moves it by dt / tau of the way
    assert zero.zeros[0][0] == pytest.approx(2.0 * DT / zero.time_constant)
    zero.reset()
    assert zero.zeros == [(0.0,) * 6, (0.0,) * 6]


def test_the_corrected_stance_force_is_the_grounds():
    corrected = np.array(_run(AirborneZero(), 40))
    _, true_fz = _readings(40, 0)
    late = np.arange(len(true_fz)) * DT > 24.0
    stance = late & (true_fz > 0.0)
    # Once learnt, what is left of the offset (4 N) is within half a newton on the mean.
    assert abs(np.mean(corrected[stance, 2] - true_fz[stance])) < 0.5
    assert abs(np.mean(corrected[stance, 0])) < 0.5


def test_bad_settings_are_refused():
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="time_constant must be > 0 s"):
            AirborneZero(bad)
    with pytest.raises(ValueError, match="settle_time must be >= 0 s"):
        AirborneZero(1.0, -0.1)
