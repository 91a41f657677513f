"""Toe-off: the rear heel lifting about the toe before a step that changes height, the foot levelling again early in
its swing up a stair and late in its swing down one.

Climbing (or descending) a stair, the rear foot stays a tread below (above) the COG's new height; with its sole level
the leg runs out of length or its ankle out of dorsiflexion at the end of the double support. Walking robots on
stairs (HRP-4 with lipm_walking_controller, PAL's Talos) roll the rear foot onto its toe instead. Here a rear foot
whose next foothold, both level, differs in height by :data:`MIN_RISE` or more (a stair) pitches about its toe line by

    theta = THETA * smooth(s),       s = clip((z_x - t) / (d - t), 0, 1),       smooth(s) = 3 s^2 - 2 s^3

in the double support before its swing, where ``z_x`` is the ZMP's distance ahead of the rear foot's sole point
along its heading, ``t`` the sole's toe (its ``front``) and ``d`` the front foot's distance. The heel starts to rise
only once the ZMP is ahead of the toe line: from then on the support is the hull of the rear toe line and the front
foot, and the planner's ZMP, a straight line from the rear foot to the front foot in double support and on the
front foot at the lift-off (``s = 1``), lies in it. Up a stair the foot, on its toe at the lift-off, levels again
over the first share ``w`` of its swing's horizontal progress ``u`` (as in :mod:`foot_tilt`):

    theta = THETA (1 - smooth(u / w)),        w = :data:`RELEASE` unless the robot gives its own.

Rising behind the stance foot to clear the nose, the swing's shank leans back and a level sole needs the ankle's
dorsiflexion; a robot whose ankle has less of it than the lean needs (G1: 0.873 rad) keeps the toe down until the foot
passes the stance foot, ``w = 1/2`` with one foot per tread (its description's ``walking.toe_release``).

Down a stair the foot keeps its toe-off pitch through the swing (the ankle, folded under the hip as the foot passes
the stance foot, is spared its dorsiflexion limit) and levels over the last :data:`RELEASE` of it,

    theta = THETA (1 - smooth((u - 1 + RELEASE) / RELEASE)),

to land flat: with the stance lowered before the step down (:mod:`rtgait.core.geometry.support_height`) the leg
reaches the lower tread flat, and a flat sole carries load from its touch-down, where a toe-first landing stayed
unloaded until it had flattened, a tenth of a second into the double support, while the ZMP could not move onto
it (``docs/results.md``).

Pitching by ``theta`` about the toe moves the sole point (the target, under the ankle) from ``p`` to

    p' = p + Rz(yaw) [ (Ry(pitch + theta) - Ry(pitch)) (-t, 0, 0) ]

so that the toe stays where it was; the pitch of the target grows by ``theta`` (positive: heel up, ``Ry``).
Footholds of one height add nothing: a flat walk is unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep

__all__ = ["MIN_RISE", "NEAR", "RELEASE", "THETA", "changes_height", "stair_rise", "toe_off_feet", "toe_pitch"]

THETA = 0.4
"""Largest toe-off pitch (rad, 23 degrees): the heel up by ``front sin(THETA)`` (4 cm for Talos, 5 cm for G1) at the
lift-off. The heel rises while the ZMP crosses from the rear toe line to the front foot, a tenth of a second in the
middle of the built-in stairs' 0.3 s double support, so the roll's peak rate is about ``12 THETA`` rad/s: 0.4 keeps it
under Talos's ankle pitch speed limit (5.8 rad/s)."""

MIN_RISE = 0.01
"""Height change of a step (m) from which the rear foot rolls onto its toe; smaller steps walk as on the flat."""

RELEASE = 0.3
"""Fraction of a swing's horizontal progress over which the sole levels after a toe-off: the first up a stair (unless
the robot gives its own share), the last down one."""

NEAR = 0.02
"""Distance (m) within which a foot target counts as standing on a foothold of its side: the closed loop's targets
follow the measured landings, millimetres off the plan's footholds."""


def _smooth(s: float) -> float:
    return s * s * (3.0 - 2.0 * s)


def _index(prints: Sequence[Footstep], foot: Sequence[float], side: str) -> int | None:
    """Index of the ``side`` foothold ``foot`` stands on (the nearest within :data:`NEAR`), ``None`` when it is off
    every one (swinging)."""
    best, index = NEAR * NEAR, None
    for i, step in enumerate(prints):
        if step.side == side:
            d2 = (step.x - foot[0]) ** 2 + (step.y - foot[1]) ** 2 + (step.z - foot[2]) ** 2
            if d2 < best:
                best, index = d2, i
    return index


def stair_rise(a: Footstep, b: Footstep) -> float:
    """The height change (m) of a stair-like step from foothold ``a`` to ``b``: both level, heights :data:`MIN_RISE`
    or more apart; 0 for any other step (a slope's footholds turn the soles to the surface instead: foot_tilt.py)."""
    if a.pitch or a.roll or b.pitch or b.roll or abs(b.z - a.z) < MIN_RISE:
        return 0.0
    return b.z - a.z


def _next_own(prints: Sequence[Footstep], i: int) -> Footstep | None:
    side = prints[i].side
    return next((step for step in prints[i + 1 :] if step.side == side), None)


def toe_pitch(
    prints: Sequence[Footstep],
    front: float,
    foot: Sequence[float],
    other: Sequence[float],
    zmp: Sequence[float],
    side: str,
    release: float = RELEASE,
) -> float:
    """Toe-off pitch (rad, heel up) of the ``side`` foot target ``foot`` (``(x, y, z, yaw, ...)``) while ``other`` is
    the other foot's target and ``zmp`` the ZMP ``(x, y)`` (m); ``front`` is the sole's toe ahead of its sole point (m)
    (module docstring); ``release`` is the share of a swing up a stair over which its sole levels. 0 when no step of the
    walk changes height by :data:`MIN_RISE`."""
    own = _index(prints, foot, side)
    there = _index(prints, other, "right" if side == "left" else "left")
    if own is not None and there is not None:  # double support: only the rear foot (the earlier foothold) rolls
        rear, ahead_foot = (foot, other) if own < there else (other, foot)
        c, s = math.cos(rear[3]), math.sin(rear[3])
        ahead = (zmp[0] - rear[0]) * c + (zmp[1] - rear[1]) * s  # the ZMP ahead of the rear sole point
        reach = (ahead_foot[0] - rear[0]) * c + (ahead_foot[1] - rear[1]) * s
        if reach <= front:
            return 0.0
        if own > there:  # the front foot stands flat (it landed flat, also after a step down)
            return 0.0
        landing = _next_own(prints, own)
        if landing is None or stair_rise(prints[own], landing) == 0.0:
            return 0.0
        return THETA * _smooth(min(1.0, max(0.0, (ahead - front) / (reach - front))))
    if own is not None or there is None:
        return 0.0
    # ``foot`` swings while ``other`` stands on foothold ``there``: it left the previous foothold of its side.
    side = prints[there].side
    lift = next((i for i in range(there - 1, -1, -1) if prints[i].side != side), None)
    if lift is None:
        return 0.0
    a = prints[lift]
    b = _next_own(prints, lift)
    rise = 0.0 if b is None else stair_rise(a, b)
    if rise == 0.0:
        return 0.0
    dx, dy = b.x - a.x, b.y - a.y
    length2 = dx * dx + dy * dy
    u = 1.0 if length2 == 0.0 else min(1.0, max(0.0, ((foot[0] - a.x) * dx + (foot[1] - a.y) * dy) / length2))
    if rise < 0.0:  # a step down: the toe stays down until the last RELEASE of the swing, which lands flat
        return THETA * (1.0 - _smooth(min(1.0, max(0.0, (u - 1.0 + RELEASE) / RELEASE))))
    return THETA * (1.0 - _smooth(min(1.0, u / release)))


def _rolled(foot: Sequence[float], front: float, theta: float) -> tuple[float, ...]:
    """``foot`` (6 values, with its pitch and roll) turned by ``theta`` about its toe line (module docstring)."""
    x, y, z, yaw, pitch, roll = foot[:6]
    forward = front * (math.cos(pitch) - math.cos(pitch + theta))  # along the heading
    up = front * (math.sin(pitch + theta) - math.sin(pitch))
    return (x + forward * math.cos(yaw), y + forward * math.sin(yaw), z + up, yaw, pitch + theta, roll)


def toe_off_feet(
    prints: Sequence[Footstep],
    front: float,
    left: Sequence[float],
    right: Sequence[float],
    zmp: Sequence[float],
    release: float = RELEASE,
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The feet targets ``(x, y, z, yaw, pitch, roll)`` with each foot's toe-off (:func:`toe_pitch`, ``release`` the
    share of a swing up a stair over which its sole levels) applied."""
    theta_left = toe_pitch(prints, front, left, right, zmp, "left", release)
    theta_right = toe_pitch(prints, front, right, left, zmp, "right", release)
    return (
        _rolled(left, front, theta_left) if theta_left else tuple(left),
        _rolled(right, front, theta_right) if theta_right else tuple(right),
    )


def changes_height(prints: Sequence[Footstep]) -> bool:
    """Whether a step of ``prints`` between level footholds changes height by :data:`MIN_RISE` or more (a toe-off
    somewhere)."""
    for i in range(len(prints)):
        landing = _next_own(prints, i)
        if landing is not None and stair_rise(prints[i], landing) != 0.0:
            return True
    return False
