"""The lean's servo-shaped reference (rtgait.core.laws.servo_reference) and the hip strategy that sends it.

Independent truths: a critically damped second-order system of natural frequency ``w`` stepped from rest by ``d``
follows ``d (1 - (1 + w t) e^{-w t})`` (closed form); the reference's acceleration is taken from second differences
of the values it outputs, not from its own bookkeeping, and must stay within ``min(w^2 reach, torque bound)``.
"""

from __future__ import annotations

import itertools
import math

import pytest

from rtgait.core.laws.hip_strategy import HipStrategy, HipStrategyLimits
from rtgait.core.laws.servo_reference import ServoReference

W, REACH, TORQUE_BOUND, DT = 8.0, 0.25, 47.6, 0.002  # G1's forward lean at its own hip gains, its 2 ms loop


def second_differences(values: list[float], dt: float) -> list[float]:
    return [(values[i + 1] - 2.0 * values[i] + values[i - 1]) / (dt * dt) for i in range(1, len(values) - 1)]


def test_a_step_follows_the_critically_damped_response_and_reaches_its_target() -> None:
    servo = ServoReference(W, REACH, TORQUE_BOUND, DT)
    values = [servo.step(REACH) for _ in range(int(2.0 / DT))]
    for i in range(0, len(values), 50):
        t = (i + 1) * DT
        assert values[i] == pytest.approx(REACH * (1.0 - (1.0 + W * t) * math.exp(-W * t)), abs=0.01 * REACH)
    assert values[-1] == pytest.approx(REACH, abs=1e-3 * REACH)
    assert max(values) <= REACH * (1.0 + 1e-9)  # approached from rest: no overshoot


@pytest.mark.parametrize("torque_bound", [TORQUE_BOUND, 5.0])
def test_the_acceleration_and_rate_stay_within_the_servos_bound(torque_bound: float) -> None:
    """A bang-bang target that reverses between the reach's ends asks (1) for up to twice the bound."""
    servo = ServoReference(W, REACH, torque_bound, DT)
    bound = min(W * W * REACH, torque_bound)
    values = [0.0]
    for i in range(int(3.0 / DT)):
        target = REACH if (i * DT) % 0.6 < 0.3 else -REACH
        values.append(servo.step(target))
    accelerations = second_differences(values, DT)
    assert max(abs(a) for a in accelerations) <= bound * (1.0 + 1e-9)
    assert max(abs(a) for a in accelerations) >= 0.99 * bound  # the bound binds: the test can fail
    rates = [(b - a) / DT for a, b in itertools.pairwise(values)]
    assert max(abs(r) for r in rates) <= W * REACH * (1.0 + 1e-9)


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="bandwidth"):
        ServoReference(0.0, REACH, TORQUE_BOUND, DT)
    with pytest.raises(ValueError, match="servo_bandwidth"):
        HipStrategyLimits(inertia=(1.0, 1.0), max_acceleration=(1.0, 1.0), servo_bandwidth=(1.0, -1.0))


def test_the_hip_strategy_sends_the_servos_reference_and_the_cmp_it_makes() -> None:
    """A shortfall held on the forward axis: the law leans bang-bang at 47.6 rad/s^2; the lean sent leans no faster
    than the servo's bound, and the CMP shift it reports is the inertia times the sent lean's acceleration."""
    inertia, mass, gravity = 0.92, 33.0, 9.81
    limits = HipStrategyLimits(inertia=(inertia, inertia), max_acceleration=(TORQUE_BOUND, TORQUE_BOUND),
                               max_lean=REACH, servo_bandwidth=(W, W))  # fmt: skip
    strategy = HipStrategy(limits, mass, DT, gravity)
    sent, shifts = [0.0], []
    for i in range(int(2.0 / DT)):
        out = strategy.update((0.05 if i < 150 else 0.0, 0.0), 0.0)
        sent.append(out.lean[1])  # a forward lean turns about +y
        shifts.append(out.cmp_offset[0])
    accelerations = second_differences(sent, DT)
    assert max(abs(a) for a in accelerations) <= W * W * REACH * (1.0 + 1e-9)
    for a, shift in zip(accelerations, shifts[1:], strict=False):
        assert shift == pytest.approx(inertia * a / (mass * gravity), abs=1e-9)
    assert max(sent) > 0.5 * REACH  # it does lean
    unbounded = HipStrategy(HipStrategyLimits(inertia=(inertia, inertia), max_acceleration=(TORQUE_BOUND,) * 2,
                                              max_lean=REACH), mass, DT, gravity)  # fmt: skip
    first = unbounded.update((0.05, 0.0), 0.0)
    assert first.cmp_offset[0] == pytest.approx(inertia * TORQUE_BOUND / (mass * gravity))  # stiff: unchanged law
