"""Each foot force sensor's zero, learnt while its foot is in the air.

A strain-gauge force/torque sensor reads the wrench on it plus an offset ``b`` that its calibration leaves (and
temperature moves, over minutes): a few newtons on an ankle sensor, the order of the margin between a light foot's
force and the load thresholds (12.5 N and 25 N on Talos). With the foot in the air the ground pushes nothing, so the
sole wrench from the reading (the weight below the sensor removed, :mod:`rtgait.estimation.sole_wrenches`) is the
offset plus the foot's inertia, whose mean over a swing is about nil (the foot starts and ends it at rest). The zero
is the mean of the airborne sole wrenches, in the sole frame (the sensor's, turned: both are on the foot):

    b <- b + (dt / tau) (w - b)                                                             (N, N m)

from ``b = 0`` (the sensor's own calibration), an exponential average over ``tau`` of airborne time
(:data:`DEFAULT_ZERO_TIME`, a few swings): a running mean from the first airborne tick on would take the first
swing's few ticks, whatever they read, for the zero. Only ticks at least
``settle_time`` after a lift-off count (the ground's force and the foot's ringing die out first), and the caller
subtracts ``b`` from every reading of the foot (mc_rtc and auto_stabilizer zero their robots' foot sensors with the
feet in the air likewise, once, before walking).
"""

from __future__ import annotations

import math

from rtgait.estimation.sole_wrenches import SoleWrench

__all__ = ["DEFAULT_SETTLE_TIME", "DEFAULT_ZERO_TIME", "AirborneZero"]

DEFAULT_ZERO_TIME = 2.0
"""Airborne time (s) the zero averages over: a few swings (0.6-0.8 s each), over which the foot's inertia averages
out; an offset drifts over minutes."""
DEFAULT_SETTLE_TIME = 0.05
"""Time after a lift-off (s) before the readings count: the load detection's least flight."""

_ZERO6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class AirborneZero:
    """The two feet sensors' zeros (module docstring).

    Args:
        time_constant: ``tau``, the airborne time the zero averages over (s).
        settle_time: time after a lift-off before a reading counts (s).
    """

    def __init__(self, time_constant: float = DEFAULT_ZERO_TIME, settle_time: float = DEFAULT_SETTLE_TIME) -> None:
        if not (math.isfinite(time_constant) and time_constant > 0.0):
            raise ValueError(f"time_constant must be > 0 s, got {time_constant}")
        if not (math.isfinite(settle_time) and settle_time >= 0.0):
            raise ValueError(f"settle_time must be >= 0 s, got {settle_time}")
        self.time_constant = float(time_constant)
        self.settle_time = float(settle_time)
        self.reset()

    def reset(self) -> None:
        """Forget the zeros."""
        self.zeros: list[SoleWrench] = [_ZERO6, _ZERO6]

    def corrected(self, index: int, wrench: SoleWrench) -> SoleWrench:
        """Foot ``index``'s (0 left, 1 right) sole wrench less its sensor's zero."""
        b = self.zeros[index]
        return (wrench[0] - b[0], wrench[1] - b[1], wrench[2] - b[2], wrench[3] - b[3], wrench[4] - b[4],
                wrench[5] - b[5])  # fmt: skip

    def learn(self, index: int, residual: SoleWrench, dt: float, air_time: float) -> None:
        """Take foot ``index``'s sole wrench of a tick ``dt`` long (s), given as its ``residual`` (the wrench less the
        current zero, ``w - b``: what the reading corrected by :meth:`corrected` gives), into its zero if the foot has
        been in the air for ``air_time`` (s; 0 for a loaded foot) of at least the settle time."""
        if dt <= 0.0 or air_time < self.settle_time:
            return
        a = dt / self.time_constant if dt < self.time_constant else 1.0
        b0, b1, b2, b3, b4, b5 = self.zeros[index]
        e0, e1, e2, e3, e4, e5 = residual
        # Written out: a generator over the six components costs more than their arithmetic.
        self.zeros[index] = (b0 + a * e0, b1 + a * e1, b2 + a * e2, b3 + a * e3, b4 + a * e4, b5 + a * e5)
