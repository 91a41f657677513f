"""A foot's IK target taken smoothly to where the controller has just put it (a re-anchored landing, an early
landing's hold): :class:`FootBlend`, used by :class:`~rtgait.control.controller.WalkingController`.

**Why.** Re-anchoring a landed foot on its measured pose moves its target by the servo lag, a few millimetres, in one
control tick. The commanded joint motion then has the second difference of a step, an acceleration of ``jump /
dt^2`` (3.7 mm in 1 ms: 3700 m/s^2), and the multibody ZMP of the commanded motion a spike metres long.

**The curve.** At ``t0`` the IK's target was at ``o0`` moving at ``v0`` (x, y, yaw), and the foot is to stand at
``g``. Over ``T`` the target goes there along the quintic of the planner's retargeted swing
(:func:`~rtgait.core.geometry.swing.retargeted_swing`),

    q(s) = o0 + b(s) (g - o0) + T v0 h(s),     s = (t - t0) / T,
    b(s) = 10 s^3 - 15 s^4 + 6 s^5,            h(s) = s - 6 s^3 + 8 s^4 - 3 s^5,

which starts with the old target's pose and rate and ends at ``g`` at rest with its acceleration continuous (``b``,
and ``h`` at 1, have no slope or curvature at the ends; ``h'(0) = 1``). The IK gets ``r = q(s) + b(s) (p - g)`` for
the controller's own target ``p(t)``, so that it ends on ``p`` whatever ``p`` does, and a jump ``dz`` of the height
is shed as ``(1 - b(s)) dz``. For a ``p`` at rest at ``g`` (a stance foot re-anchored), ``r = q``: its largest step
per tick is ``15/8 |g - o0| dt / T`` and its largest acceleration ``10/sqrt(3) |g - o0| / T^2`` (5.77: 13 m/s^2
for 3.7 mm over 40 ms). A ``p`` that runs to ``g`` in a few milliseconds (the planner's retargeted swing of a foot
landed just before the plan's touch-down) is taken in at the blend's pace, ``b`` being ``10 s^3`` at first.

Python floats only; :meth:`FootBlend.apply` runs every tick of a blend (``T / dt`` ticks per landing).
"""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import Footstep, Side
from rtgait.core.geometry.swing import blend, retargeted_swing

__all__ = ["FootBlend", "Pose"]

Pose = tuple[float, float, float, float]
"""A foot target ``(x, y, z, yaw)`` (m, rad)."""


class FootBlend:
    """The blend of one foot's IK target (module docstring); idle until :meth:`start`, idle again once over."""

    __slots__ = ("_state", "side")

    def __init__(self, side: Side) -> None:
        self.side: Side = side
        self._state: tuple[float, ...] | None = None

    @property
    def active(self) -> bool:
        """Whether a blend is under way (it ends at the first :meth:`apply` at or after ``t0 + T``)."""
        return self._state is not None

    def reset(self) -> None:
        """Stop any blend."""
        self._state = None

    def start(
        self,
        t: float,
        pose: Pose,
        rate: tuple[float, float, float],
        goal: tuple[float, float, float],
        dz: float,
        duration: float,
    ) -> None:
        """Begin at ``t`` (s) from the IK's target ``pose`` moving at ``rate`` (m/s, m/s, rad/s; x, y, yaw) toward
        the foot's pose ``goal`` (x, y, yaw), with the height ``dz`` (m) above the controller's target to shed,
        over ``duration`` (s, > 0)."""
        if not duration > 0.0:
            raise ValueError(f"a blend needs a duration > 0 s, got {duration}")
        self._state = (t, duration, pose[0], pose[1], pose[3], *rate, *goal, dz)

    def apply(self, t: float, target: Pose) -> Pose:
        """The IK's target at ``t`` (s) for the controller's ``target``: ``target`` itself when idle or over."""
        state = self._state
        if state is None or t - state[0] >= state[1]:
            self._state = None
            return target
        t0, duration, x0, y0, yaw0, vx, vy, vyaw, gx, gy, gyaw, dz = state
        s = max((t - t0) / duration, 0.0)
        x, y, yaw = retargeted_swing((x0, y0, yaw0), (vx, vy, vyaw), Footstep(gx, gy, gyaw, self.side), s, duration)
        k = blend(s)[0]
        yaw += k * math.remainder(target[3] - gyaw, math.tau)
        yaw = target[3] + math.remainder(yaw - target[3], math.tau)  # the plan's yaw need not be within (-pi, pi]
        return (x + k * (target[0] - gx), y + k * (target[1] - gy), target[2] + (1.0 - k) * dz, yaw)
