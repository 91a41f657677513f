"""Bounds on what a robot's sensors and its caller hand the closed-loop planner, and the one error beyond them.

The online planner's closed-loop calls (``start``, ``observe``, ``touchdown``, ``replan_now`` and the walk's changes)
check every argument against these bounds before they change anything; a value beyond one raises
:class:`InputOutOfBoundsError`, naming the argument and the bound, and the planner stays exactly as it was. The
bounds are physical and generous: they refuse what no walking robot measures (a COM a kilometre away, a foot landing
a quarter turn from the stance foot), never a push the controllers recover from. ``docs/closed_loop.md`` ("Bounds on
measured inputs") lists them with the configuration values they derive from.

Why these numbers, for a COM at height ``zc`` (m) under gravity ``g`` (m/s^2):

* COM reach, ``|c - m| <= COM_REACH_HEIGHTS zc + d / 2`` from the midpoint ``m`` of the feet on the ground, ``d``
  apart: a body pivoting over a foot lies flat with its COM at most ``zc`` beyond it, so twice that is a robot
  already on the ground, with room for an estimator's error.
* COM speed, ``|c'| <= COM_SPEED_FROUDE sqrt(g zc)``: walking keeps the Froude number ``|c'|^2 / (g zc)`` below 1
  (faster, a pendulum leg leaves the ground), and a COM falling from ``zc`` hits the ground at ``sqrt(2 g zc)``.
* Landings (:class:`LandingBounds`): the stride box from the stance foot that the walk's and step adjustment's limits
  allow, widened by :data:`LANDING_TOLERANCE` for where a foot really lands, turned less than a quarter turn.
* Positions within :data:`MAX_POSITION` of the origin, where double precision still resolves 1e-10 m, headings within
  :data:`MAX_YAW` and times within :data:`MAX_TIME` of zero.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol

from rtgait.core.limits import MAX_STRIDE


class InputOutOfBoundsError(ValueError):
    """An argument of a planner call is not finite or lies beyond its documented bound (the message names both);
    the call changed nothing."""


COM_REACH_HEIGHTS = 2.0
"""Farthest a measured COM may be from the midpoint of the feet on the ground, in COM heights ``zc``, plus half the
distance between those feet (dimensionless; module docstring)."""

COM_SPEED_FROUDE = 2.0
"""Fastest a measured horizontal COM velocity may be, in units of ``sqrt(g zc)`` (dimensionless; at 0.8 m COM
height, 5.6 m/s; module docstring)."""

MAX_TURN = math.pi / 2
"""Largest heading change between a landing foot and its stance foot (rad, exclusive): a quarter turn, as for a
:class:`~rtgait.core.geometry.footsteps.Stride`."""

LANDING_TOLERANCE = 0.2
"""How far beyond the planned stride box a foot may really land (m): a foot dragged by a push, a slip, a capture
step's tracking error. Beyond it the reading is a sensor fault, not a step."""

MAX_TIME = 1e10
"""Largest ``|t|`` of any time given to the planner (s): 317 years, room for a UNIX time stamp (1.7e9 s), where a time
still resolves 2e-6 s, well within a control tick. Beyond it a phase's duration is lost in round-off."""

MAX_POSITION = 1e6
"""Largest ``|x|`` or ``|y|`` of a footprint or a measured COM (m): 1000 km from the origin, farther than any walk,
where a coordinate still resolves 1e-10 m (double precision, relative 2.2e-16)."""

MAX_YAW = 1e6
"""Largest ``|yaw|`` of a footprint given to the planner (rad): an estimator may hand over an unwrapped heading, but
not 160,000 turns of it; up to here a heading still resolves 1e-10 rad, while beyond ~1e16 wrapping it (and so
the turn between two feet) is lost in round-off."""


class _Pose(Protocol):
    x: float
    y: float
    yaw: float
    side: str


def stride_components(stance: _Pose, landing: _Pose) -> tuple[float, float, float]:
    """``(length, width, turn)`` (m, m, rad) of the stride from ``stance`` to ``landing``, as
    :func:`~rtgait.core.geometry.footsteps.stride_between` measures it but never refusing: along the mean heading,
    across it (positive: the landing foot on its own side) and the heading change, wrapped to ``[-pi, pi]``."""
    turn = math.remainder(landing.yaw - stance.yaw, math.tau)
    heading = stance.yaw + 0.5 * turn
    c, s = math.cos(heading), math.sin(heading)
    dx, dy = landing.x - stance.x, landing.y - stance.y
    lateral = -s * dx + c * dy
    return c * dx + s * dy, lateral if landing.side == "left" else -lateral, turn


class LandingBounds(NamedTuple):
    """The stride box a measured landing must lie in, relative to its stance foot (m, rad): along the mean heading of
    the two feet within ``+-max_length``, across it between ``min_width`` and ``max_width`` on the landing foot's side,
    each widened by ``tolerance`` (so the feet may cross by ``tolerance - min_width``) and capped at ``max_stride``,
    and turned less than ``max_turn``."""

    max_length: float
    min_width: float
    max_width: float
    tolerance: float = LANDING_TOLERANCE
    max_turn: float = MAX_TURN
    max_stride: float = MAX_STRIDE

    def check(self, name: str, stance: _Pose, landing: _Pose, planned: tuple[_Pose, _Pose] | None = None) -> None:
        """Raise :class:`InputOutOfBoundsError` naming ``name`` when ``landing`` is outside the box of ``stance``.

        ``planned``: the stance and landing footprints as planned, whose stride widens the box (a walk may plan
        strides beyond the limits of its velocity commands and of step adjustment)."""
        length, width, turn = stride_components(stance, landing)
        if not abs(turn) < self.max_turn:
            raise InputOutOfBoundsError(
                f"{name}: the landing turns {turn:.3f} rad from the stance foot, beyond +-{self.max_turn:.4f} rad"
            )
        longest, low, high = self.max_length, self.min_width, self.max_width
        if planned is not None:
            plan_length, plan_width, _ = stride_components(*planned)
            longest, low, high = max(longest, abs(plan_length)), min(low, plan_width), max(high, plan_width)
        longest = min(longest + self.tolerance, self.max_stride)
        low, high = low - self.tolerance, min(high + self.tolerance, self.max_stride)
        if not abs(length) <= longest:
            raise InputOutOfBoundsError(
                f"{name}: the landing is {length:.3f} m along the stance foot, beyond +-{longest:.3f} m"
            )
        if not low <= width <= high:
            raise InputOutOfBoundsError(
                f"{name}: the landing is {width:.3f} m beside the stance foot, outside [{low:.3f}, {high:.3f}] m"
            )


def check_footstep(name: str, footstep: _Pose) -> None:
    """Raise :class:`InputOutOfBoundsError` naming ``name`` unless ``footstep``'s position is within
    :data:`MAX_POSITION` (m) and its yaw within :data:`MAX_YAW` (rad)."""
    check_position(name, footstep.x, footstep.y)
    if not abs(footstep.yaw) <= MAX_YAW:
        raise InputOutOfBoundsError(f"{name} yaw must be finite and within +-{MAX_YAW:g} rad, got {footstep.yaw}")


def check_position(name: str, x: float, y: float) -> None:
    """Raise :class:`InputOutOfBoundsError` naming ``name`` unless ``x`` and ``y`` are finite and within
    :data:`MAX_POSITION` (m)."""
    if not (abs(x) <= MAX_POSITION and abs(y) <= MAX_POSITION):  # also refuses NaN
        raise InputOutOfBoundsError(f"{name} must be finite and within +-{MAX_POSITION:g} m, got ({x}, {y})")


__all__ = [
    "COM_REACH_HEIGHTS", "COM_SPEED_FROUDE", "LANDING_TOLERANCE", "MAX_POSITION", "MAX_TIME", "MAX_TURN",
    "MAX_YAW", "InputOutOfBoundsError", "LandingBounds", "check_footstep", "check_position", "stride_components",
]  # fmt: skip
