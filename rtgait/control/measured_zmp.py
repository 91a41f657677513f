"""Whether a measured ZMP is one the feet's contacts can produce, before the COM admittance acts on it.

A foot on the ground pushes (its normal force ``f_i >= 0``) through a centre of pressure ``c_i`` inside its sole, and
the ZMP is their force-weighted mean ``p = sum f_i c_i / sum f_i``: a point of the convex hull of the soles. The hull
of two soles lies within ``r`` of the segment between their sole points ``a`` and ``b``, with ``r`` the largest
distance from a sole point to its sole's corners,

    r = hypot(max(front, back), max(inner, outer)),        dist(p, [a, b]) <= r                   (1)

(each sole lies in the disc of radius ``r`` about its sole point, and the hull of two discs is the segment widened by
``r``). A measured ZMP beyond (1) is no contact's: it is a reading of ``M / F`` on a total normal force near zero, one
foot's sensor reading a pull (a negative normal force) against the other's push. Fed to the COM admittance
``d' = -A (p_cmd - p_measured)`` (:mod:`rtgait.core.laws.feedback`) such a ZMP, metres off, moves the IK's COM target
by ``A |p_cmd - p| dt`` in one tick: 26 mm on Talos descending the 0.185 m stairs (``docs/results.md``, "A
DCM-error replan's step of the COM target"). The controller takes it as no measurement (the admittance then takes the
planned ZMP for the realised one). (1) is a superset of the hull: a ZMP any contact gives is never refused.
"""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import SoleRect

__all__ = ["sole_radius", "within_soles"]


def sole_radius(sole: SoleRect) -> float:
    """``r`` of (1): the largest distance (m) from the sole point to a corner of ``sole``."""
    return math.hypot(max(sole.front, sole.back), max(sole.inner, sole.outer))


def within_soles(x: float, y: float, a: tuple[float, ...], b: tuple[float, ...], radius: float) -> bool:
    """Whether the point ``(x, y)`` (m) is within ``radius`` (m) of the segment from sole point ``a`` to ``b``
    (``(x, y, ...)``, m): (1) of the module docstring. ``False`` for a NaN point."""
    ax, ay = a[0], a[1]
    ux, uy = b[0] - ax, b[1] - ay
    dx, dy = x - ax, y - ay
    length2 = ux * ux + uy * uy
    s = (dx * ux + dy * uy) / length2 if length2 > 0.0 else 0.0
    s = 0.0 if s < 0.0 else (1.0 if s > 1.0 else s)
    ex, ey = dx - s * ux, dy - s * uy
    return ex * ex + ey * ey <= radius * radius
