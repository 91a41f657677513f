"""What a landing must show besides a load: a sole near the ground, and a force that lasts.

A load on a swinging foot is taken for a touch-down only if the robot's own sensing agrees it can be one:

* **Near the ground.** The sole's lowest corner is at most ``clearance`` above the other sole's lowest corner, both
  from the leg kinematics in one estimated frame. With a sole rectangle ``x0 <= x <= x1``, ``y0 <= y <= y1`` about
  the sole origin ``o`` and the sole's rotation ``R`` (row-major ``m``), a corner's height is ``o_z + m6 x + m7 y``,
  so the lowest is

      z_low = o_z + min(m6 x0, m6 x1) + min(m7 y0, m7 y1)                                        (m)

  and an unloaded foot may become loaded only where ``z_low(foot) - z_low(other) <= clearance``. The other foot is
  the ground's reference whether or not it is loaded: the stance foot stands on the ground (its anchor), and a foot
  that is off the ground for a moment (a bounce, the ankle sensor's ringing taking it below the release force, a
  flight) is above it, so a foot far above the other one cannot be touching level ground either. The default,
  :data:`DEFAULT_LANDING_CLEARANCE` = 35 mm, is the height of a step the plan does not know of (+-30 mm) plus the
  kinematics' error on the height of one sole relative to the other (a few mm: encoder noise through two 0.7-0.9 m
  legs and the IMU's tilt error over the feet's 0.2-0.3 m spread). Only the upper side is gated: a foot below the
  other stands on lower ground. A loaded foot is not gated.
* **A force that lasts** (``sustain_time``, off by default: :data:`DEFAULT_SUSTAIN_TIME`). An ankle force sensor
  under a whipped foot reads the foot's ringing inertia, its sign alternating from one 1 ms tick to the next (+330,
  -260, +64 N): a component at 250-500 Hz, half period 1-2 ms, which a load required to stay above the landing force
  for 3 ms would reject. But a real heel strike rings the same way: on Talos pushed 45 N s forward (noise x1, in the
  shadow of a walk on the truth) such a requirement delayed landings by up to 226 ms (95th percentile 131 ms,
  against 2 ms), far beyond the 10 ms a landing's detection may take, and removed few false contacts the height
  gate had not (75 -> 67 ticks). The height gate alone is used.

The foot's inertia is taken out of the force the load detection reads (:mod:`rtgait.estimation.foot_inertia`):
what is left of a whipped foot's reading is the removal's error, which the gate still backs up.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_LANDING_CLEARANCE", "DEFAULT_SUSTAIN_TIME", "lowest_sole_height", "near_ground"]

DEFAULT_LANDING_CLEARANCE = 0.035
"""Highest a landing sole's lowest corner may be above the stance sole's (m): a 30 mm unseen step and 5 mm of the
legs' kinematic error (module docstring)."""

DEFAULT_SUSTAIN_TIME = 0.0
"""Time a load must stay above the landing force before it counts (s): none, a real landing rings as a false one
does (module docstring)."""

Extents = tuple[float, float, float, float]


def lowest_sole_height(z: float, m: tuple[float, ...] | list[float], extents: Extents | None) -> float:
    """Height (m) of the lowest corner of a sole at height ``z`` with row-major rotation ``m`` and extents ``(x0, x1,
    y0, y1)`` about its origin (m); the origin's height without extents."""
    if extents is None:
        return z
    x0, x1, y0, y1 = extents
    m6, m7 = m[6], m[7]
    ax, bx, ay, by = m6 * x0, m6 * x1, m7 * y0, m7 * y1
    return z + (ax if ax < bx else bx) + (ay if ay < by else by)


def near_ground(
    clearance: float, loaded: tuple[bool, bool], heights: tuple[float, float], rise: float = 0.0
) -> tuple[bool, bool]:
    """Whether each foot (left, right) may become loaded: the lowest sole heights ``heights`` (m, one frame), the
    feet's load states ``loaded`` at the last tick. A loaded foot may; an unloaded one if its sole is at most
    ``clearance`` above the other's (loaded or not: the lower foot is on or above the ground), plus the planned
    ``rise`` of the ground under it over the other's: ``rise`` is the left foot's planned ground height less the
    right's (m). A foot landing on a planned stair tread higher than the other foot's is let down onto it; one
    swinging down to a lower tread is taken as landed only within ``clearance`` of that tread's height (over the
    stair it leaves, its toe pointed down, the ankle sensor reads the swing's own load: docs/results.md)."""
    if math.isinf(clearance):
        return True, True
    left, right = heights
    return loaded[0] or left - right <= clearance + rise, loaded[1] or right - left <= clearance - rise
