"""Velocity and acceleration of the whole-body IK's configurations, one control tick at a time.

The IK gives a configuration ``q_k`` per tick of period ``dt``; inverse dynamics needs its velocity and acceleration.
Backward differences on the configuration manifold (``pin.difference``: the free flyer's velocity in its own frame, as
Pinocchio's algorithms take it), each smoothed by a first-order low-pass of time constant ``T``:

    v_k = v_{k-1} + b ((q_k - q_{k-1}) / dt - v_{k-1}),        a_k = a_{k-1} + b ((v_k - v_{k-1}) / dt - a_{k-1}),

``b = 1 - exp(-dt / T)`` (``T = 0``: the raw differences). A second difference multiplies whatever is not smooth in the
IK's solutions (one Gauss-Newton step a tick, targets fed back from measurements) by ``1 / dt^2``, a million at 1 kHz:
the low-pass keeps that out of the torques, at the price of a lag of about ``T`` on each (``T`` a few milliseconds
against steps of tenths of a second). A reference that jumps (a target moved at once) still gives a burst of
acceleration over a few ``T``: the torques it gives are clipped to the joints' limits by the stack.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

__all__ = ["DEFAULT_RATE_FILTER", "MotionRates"]

DEFAULT_RATE_FILTER = 0.005
"""The low-pass's time constant ``T`` (s): module docstring."""


class MotionRates:
    """Backward differences of a configuration trajectory, low-passed (module docstring).

    Args:
        model: the Pinocchio model of the configurations.
        dt: the period between two configurations (s), ``> 0``.
        time_constant: the low-pass's ``T`` (s), ``>= 0``.

    The first configuration after :meth:`reset` (or after making) starts at rest: zero velocity and acceleration.
    """

    def __init__(self, model: pin.Model, dt: float, time_constant: float = DEFAULT_RATE_FILTER) -> None:
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        if not (math.isfinite(time_constant) and time_constant >= 0.0):
            raise ValueError(f"the rate filter's time constant must be >= 0 s, got {time_constant}")
        self.model, self.dt, self.time_constant = model, float(dt), float(time_constant)
        self._blend = 1.0 if time_constant == 0.0 else -math.expm1(-dt / time_constant)
        self._v = np.zeros(model.nv)
        self._a = np.zeros(model.nv)
        self._q: np.ndarray | None = None

    @property
    def velocity(self) -> np.ndarray:
        """The last :meth:`update`'s velocity (m/s, rad/s; the array the next call rewrites)."""
        return self._v

    @property
    def acceleration(self) -> np.ndarray:
        """The last :meth:`update`'s acceleration (m/s^2, rad/s^2; the array the next call rewrites)."""
        return self._a

    def reset(self) -> None:
        """Forget the trajectory: the next configuration starts at rest."""
        self._q = None
        self._v[:] = 0.0
        self._a[:] = 0.0

    def update(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The velocity and acceleration at this tick's configuration ``q`` (arrays kept and rewritten by the next
        call; m/s and rad/s, m/s^2 and rad/s^2, Pinocchio's velocity coordinates)."""
        previous = self._q
        self._q = np.array(q, dtype=float)
        if previous is None:
            return self._v, self._a
        v, a, b, rate = self._v, self._a, self._blend, 1.0 / self.dt
        step = pin.difference(self.model, previous, self._q)
        step *= rate
        step -= v
        step *= b  # the filtered velocity's change over the tick
        # a + b (step / dt - a), in place: the acceleration's input is that change over the tick.
        a *= 1.0 - b
        a += (b * rate) * step
        v += step
        return v, a
