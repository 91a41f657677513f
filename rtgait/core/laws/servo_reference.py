"""A reference a position servo can follow: a target passed through a critically damped second-order filter.

A joint servo of stiffness ``kp`` (N m/rad) moving an inertia ``I`` (kg m^2) follows its reference like a
second-order system of natural frequency ``w_s = sqrt(kp / I)`` (1/s). A reference that accelerates faster than the
servo's own step response is not tracked: the joint lags, then overshoots (the upper body of a light robot on soft
gains swings past a bang-bang lean). Shaped by the servo's own dynamics,

    r'' = w_s^2 (target - r) - 2 w_s r'        (rad/s^2)                                          (1)

the reference is what the servo would do anyway, and the law that asks for it knows the acceleration actually made.
Bounds, for a target within ``[-reach, reach]``: from rest, a step of ``d`` (|d| <= reach) gives
``r(t) = d (1 - (1 + w_s t) e^{-w_s t})``, whose acceleration peaks at ``w_s^2 d`` at once and rate at ``w_s d / e``.
So

    |r''| <= a_max = min(w_s^2 reach, torque bound),   |r'| <= v_max = w_s reach                     (2)

``w_s^2 reach`` is the servo's torque at an error of the whole reach, ``kp reach``, over ``I``; the torque bound is
the drive's rated share over ``I``. A target that reverses could ask (1) for up to twice (2); the reference is
clipped to (2) (a critically damped reference does not pass a target it approaches from rest). Stepped
semi-implicitly (rate, then value) at period ``dt``.
"""

from __future__ import annotations

import math

__all__ = ["ServoReference"]


class ServoReference:
    """Eq. (1) of the module docstring at natural frequency ``bandwidth`` (1/s), clipped to eq. (2) with ``reach``
    (rad) and ``max_acceleration`` (the torque bound, rad/s^2), stepped every ``dt`` (s)."""

    def __init__(self, bandwidth: float, reach: float, max_acceleration: float, dt: float) -> None:
        for name, value in (("bandwidth", bandwidth), ("reach", reach), ("max_acceleration", max_acceleration),
                            ("dt", dt)):  # fmt: skip
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"ServoReference {name} must be finite and > 0, got {value}")
        self.bandwidth, self.reach, self.dt = float(bandwidth), float(reach), float(dt)
        self.max_acceleration = min(bandwidth * bandwidth * reach, float(max_acceleration))
        self.max_rate = bandwidth * reach
        self.reset()

    def reset(self) -> None:
        """At zero and at rest."""
        self.value = 0.0
        self.rate = 0.0
        self.acceleration = 0.0

    @property
    def at_rest(self) -> bool:
        """At zero and still (within 1e-6 rad and rad/s)."""
        return abs(self.value) < 1e-6 and abs(self.rate) < 1e-6

    def step(self, target: float) -> float:
        """One period toward ``target`` (rad); returns the new value. :attr:`acceleration` is the one applied."""
        w, high, fast = self.bandwidth, self.max_acceleration, self.max_rate
        acc = w * w * (target - self.value) - 2.0 * w * self.rate
        acc = -high if acc < -high else (high if acc > high else acc)
        rate = self.rate + acc * self.dt
        rate = -fast if rate < -fast else (fast if rate > fast else rate)
        value = self.value + rate * self.dt
        self.acceleration = (rate - self.rate) / self.dt
        self.value, self.rate = value, rate
        return value
