"""The descent of a late foot's target (:mod:`rtgait.control.landings`, "Heights"): smooth in position and velocity.

A swing's height profile ends at rest (:mod:`rtgait.core.geometry.swing`), so a foot still in the air at its planned
touch-down has a target at rest. Sent down at ``v`` (m/s) from the next tick, the target's velocity steps by ``v``:
the IK's joint velocity references step with it (``v / dt`` of acceleration, 300 m/s^2 at 0.3 m/s and 1 ms), the
drives saturate for a tick, and the leg rings. The force the sole's sensor reads from that ringing (or the joint
torques' estimate of it) is taken for a landing while the sole is still millimetres up.

**The profile.** The descent continues the swing's end state, at rest, with the velocity of a quintic blend: over a
ramp ``T_r`` the speed goes from 0 to ``v`` as ``v b(s)``, ``b(s) = 10 s^3 - 15 s^4 + 6 s^5``, ``s = tau / T_r``,
and the depth below where it started is its integral,

    d(tau) = v T_r B(s),     B(s) = 5/2 s^4 - 3 s^5 + s^6      (B(1) = 1/2),

then ``v (tau - T_r / 2)`` at full speed; it stops at the descent's limit ``L`` (m) the same way, the ramp mirrored,
so that it reaches ``L`` at rest: position, velocity and acceleration are continuous throughout. When ``L < v T_r``
there is no full speed: the peak speed is ``L / T_r``, reached halfway.

**The ramp.** ``T_r = 15/8 v / a``: the blend's peak acceleration, ``15/8 v / T_r``, is ``a``
(``ControllerOptions.late_descent_acceleration``). Its argued value is gravity's, the most a foot let drop falls
with: 57 ms at 0.3 m/s, and the lag it adds to the depth, ``v T_r / 2``, is 8.6 mm.

Python floats only (every tick of a late foot).
"""

from __future__ import annotations

from rtgait.core.lipm.closed_form import GRAVITY

__all__ = ["descent_depth", "descent_ramp"]

_PEAK_RATE = 15.0 / 8.0
"""Peak slope of the quintic blend ``b`` (at ``s = 1/2``)."""


def descent_ramp(speed: float, acceleration: float = GRAVITY) -> float:
    """The ramp ``T_r`` (s) to the descent's ``speed`` (m/s) at the peak ``acceleration`` (m/s^2, > 0)."""
    return _PEAK_RATE * speed / acceleration


def _ramp_depth(s: float) -> float:
    """``B(s)``, the integral of the quintic blend from 0 to ``s`` in [0, 1]."""
    s4 = s * s * s * s
    return s4 * (2.5 - 3.0 * s + s * s)


def descent_depth(tau: float, speed: float, limit: float, acceleration: float = GRAVITY) -> float:
    """Depth (m, >= 0) a late foot's target has gone down ``tau`` (s) after its descent began, at most ``limit`` (m),
    at ``speed`` (m/s) when there is room for it, leaving rest and coming to it at the peak ``acceleration`` (m/s^2,
    > 0; module docstring)."""
    if tau <= 0.0 or limit <= 0.0 or speed <= 0.0:
        return 0.0
    ramp = descent_ramp(speed, acceleration)
    if limit < speed * ramp:  # too short for full speed: up to L / T_r and straight back down to rest
        speed = limit / ramp
    cruise = limit / speed - ramp  # time at full speed (s), >= 0
    if tau < ramp:
        return speed * ramp * _ramp_depth(tau / ramp)
    if tau < ramp + cruise:
        return speed * (tau - 0.5 * ramp)
    left = 2.0 * ramp + cruise - tau  # time (s) until it reaches the limit at rest
    if left <= 0.0:
        return limit
    return limit - speed * ramp * _ramp_depth(left / ramp)
