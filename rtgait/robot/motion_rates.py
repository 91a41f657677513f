"""Velocity and acceleration of the whole-body IK's configurations, one control tick at a time.

The IK gives a configuration ``q_k`` per tick of period ``dt``; inverse dynamics needs its velocity and acceleration.
Backward differences on the configuration manifold (``pin.difference``: the free flyer's velocity in its own frame, as
Pinocchio's algorithms take it), each smoothed by a first-order low-pass of time constant ``T``:

    v_k = v_{k-1} + b ((q_k - q_{k-1}) / dt - v_{k-1}),        a_k = a_{k-1} + b ((v_k - v_{k-1}) / dt - a_{k-1}),

``b = 1 - exp(-dt / T)`` (``T = 0``: the raw differences). A second difference multiplies whatever is not smooth in the
IK's solutions (one Gauss-Newton step a tick, targets fed back from measurements) by ``1 / dt^2``, a million at 1 kHz:
the low-pass keeps that out of the torques, at the price of a lag of about ``T`` on each (``T`` a few milliseconds
against steps of tenths of a second). A reference that jumps (a target moved at once) would still give a burst of
acceleration over a few ``T``. With the joints' speed limits given, a tick on which some joint's difference is faster
than its limit, or on which the free flyer's velocity changes by more than :data:`JUMP_ACCELERATION` allows (a moved
COM target moves the IK's base at once), is taken as such a jump, not a motion: the configuration becomes the new one
to difference from and the rates are kept (no joint can move that fast, and the burst, tens of times the motion's
acceleration, saturates the feed-forward torques: G1's at each landing, where the controller moves the landed foot's
target to where it touched down and replans the COM).

**After a jump** the velocity is the new reference's, which need not be the old one's: a replan from a pushed state
moves the COM target and gives it the measured velocity. Until the next tick whose difference is within the joints'
limits and whose base velocity differs from the previous tick's difference by less than the bound (the IK, one
Gauss-Newton step a tick, may take a few ticks to reach a moved target), each tick is a jump too; that tick's
difference is then taken as the velocity, ``v = (q_k - q_{k-1}) / dt``, the acceleration kept, and the low-pass goes
on. Compared with the velocity kept from before the jump instead, every tick after such a replan differed from it by
more than :data:`JUMP_ACCELERATION` allows, so every tick read as a jump and the rates stayed frozen at the pre-push
motion (Talos at its own gains, an 11 N s push on fig8: 0.67 s, the whole recovery), until the velocity drifted back
within the bound and the low-pass caught up in one burst (3.8 m/s^2 of the base, 120 rad/s^2 at an ankle: the stance
foot's wrench 2.8 kN outside its cone, the hips at their torque limits, the stance foot tipped and the robot fell).
"""

from __future__ import annotations

import math
from operator import gt as _gt

import numpy as np
import pinocchio as pin

__all__ = ["DEFAULT_RATE_FILTER", "JUMP_ACCELERATION", "MotionRates"]

JUMP_ACCELERATION = 50.0
"""The free flyer's linear acceleration beyond which a tick is a jump of the reference (m/s^2; with joint speed
limits only): five times gravity, where a walking robot's base accelerates by a few m/s^2 and a target moved by a
millimetre in a 2 ms tick gives 250 m/s^2."""

_difference, _subtract, _multiply = pin.difference, np.subtract, np.multiply

DEFAULT_RATE_FILTER = 0.005
"""The low-pass's time constant ``T`` (s): module docstring."""


class MotionRates:
    """Backward differences of a configuration trajectory, low-passed (module docstring).

    Args:
        model: the Pinocchio model of the configurations.
        dt: the period between two configurations (s), ``> 0``.
        time_constant: the low-pass's ``T`` (s), ``>= 0``.
        speed_limit: the joints' speed limits (rad/s, joint order; ``inf``: none); ``None``: no jump detection
            (module docstring).

    The first configuration after :meth:`reset` (or after making) starts at rest: zero velocity and acceleration.
    """

    def __init__(
        self,
        model: pin.Model,
        dt: float,
        time_constant: float = DEFAULT_RATE_FILTER,
        speed_limit: np.ndarray | None = None,
    ) -> None:
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        if not (math.isfinite(time_constant) and time_constant >= 0.0):
            raise ValueError(f"the rate filter's time constant must be >= 0 s, got {time_constant}")
        self.model, self.dt, self.time_constant = model, float(dt), float(time_constant)
        self._blend = 1.0 if time_constant == 0.0 else -math.expm1(-dt / time_constant)
        self._v = np.zeros(model.nv)
        self._a = np.zeros(model.nv)
        self._q: np.ndarray | None = None
        self._reseed = False  # since the last jump the reference has not yet moved smoothly (module docstring)
        self._last_step = np.zeros(model.nv)  # the last difference (velocity units) while _reseed
        self._change = np.zeros(model.nv)  # the filtered velocity's change over a tick (update)
        self._scaled = np.zeros(model.nv)  # that change over the tick, times b (update)
        self.speed_limit = None if speed_limit is None else np.asarray(speed_limit, dtype=float)
        self._limits = None if speed_limit is None else self.speed_limit.tolist()
        self._spare = np.zeros(model.nq)  # the buffer of the next configuration (update)
        self.jumps = 0
        """Ticks taken as jumps of the reference (module docstring)."""

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
        self._reseed = False
        self._v[:] = 0.0
        self._a[:] = 0.0

    def update(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The velocity and acceleration at this tick's configuration ``q`` (arrays kept and rewritten by the next
        call; m/s and rad/s, m/s^2 and rad/s^2, Pinocchio's velocity coordinates)."""
        previous = self._q
        if previous is None:
            self._q = np.array(q, dtype=float)
            self._spare = np.empty_like(self._q)
            return self._v, self._a
        # The configuration kept in the buffer the previous one's frees (no allocation a tick).
        current = self._spare
        current[:] = q
        self._q, self._spare = current, previous
        v, a, b, rate = self._v, self._a, self._blend, 1.0 / self.dt
        step = _difference(self.model, previous, current)
        step *= rate
        limits = self._limits
        if limits is not None:
            reseed = self._reseed
            # After a jump the base's difference is compared with the last difference, not with the kept velocity.
            # The joints' speeds are compared as Python floats, mapped in C (numpy's comparisons without its calls).
            jumped = any(map(_gt, map(abs, step[6:].tolist()), limits)) or _base_jump(
                step[:3] - (self._last_step[:3] if reseed else v[:3]), rate
            )
            self._last_step = step  # a new array each tick, which the filter below does not change
            if jumped:
                self.jumps += 1  # a jump of the reference, not a motion: the rates go on from the new configuration
                self._reseed = True
                return v, a
            if reseed:  # the reference moves smoothly again: its difference is its velocity (module docstring)
                self._reseed = False
                v[:] = step
                return v, a
        change = _subtract(step, v, out=self._change)
        change *= b  # the filtered velocity's change over the tick
        # a + b (step / dt - a), in place: the acceleration's input is that change over the tick.
        a *= 1.0 - b
        a += _multiply(change, b * rate, out=self._scaled)
        v += change
        return v, a


def _base_jump(change: np.ndarray, rate: float) -> bool:
    """Whether the base's velocity changes by ``change`` (m/s) faster than :data:`JUMP_ACCELERATION` (``rate``:
    ticks per s), the norm as ``np.linalg.norm`` takes it: the square root of the vector's dot product."""
    return math.sqrt(change.dot(change)) * rate > JUMP_ACCELERATION
