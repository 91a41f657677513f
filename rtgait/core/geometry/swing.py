"""Swing-foot trajectories: smooth lift-off and touch-down, and over a height change.

Horizontal position and yaw follow a quintic blend (zero velocity and acceleration at both ends); between footholds
at one height ``z0`` the height follows ``z0 + h * 64 s^3 (1 - s)^3``, which peaks at ``h`` mid-swing and also starts
and ends with zero velocity and acceleration, so the foot neither scuffs at lift-off nor strikes at touch-down.

Between footholds at different heights ``z0 != z1`` (a stair, a step) the foot rises first and comes down last:
with ``top = max(z0, z1) + h`` and ``sigma`` = :data:`RISE_SHARE`,
``z(s) = z0 + (top - z0) b(s / sigma) - (top - z1) b((s - 1 + sigma) / sigma)`` (``b`` the quintic blend, clipped to
[0, 1]), so the sole is ``h`` above the higher foothold over the middle ``1 - 2 sigma`` of the swing, and the
horizontal blend starts :data:`HORIZONTAL_DELAY` later and ends as much earlier: the toe is above the upper tread
before it passes the stair nose (going up), the heel leaves the nose before the foot comes down (going down).

Up a ramp (a foothold tilted to its surface, the landing higher: onto the ramp, along it and off its top) there is
no nose to clear: the foot moves along the line between the footholds and lifts off it as on level ground,
``z(s) = z0 + (z1 - z0) b(s) + h * 64 s^3 (1 - s)^3`` with the horizontal blend ``b(s)`` undelayed (over the ramp's
top edge the lift keeps the sole clear: the terrain check below). The stair profile there lifted the foot up to the
landing's height behind the body before moving it forward, its sole pitched toes up with the ramp: beyond G1's ankle
dorsiflexion (``docs/results.md``). Down a ramp the stair profile is kept.
:mod:`rtgait.core.geometry.swing_terrain` checks the swept sole against the terrain.
"""

from __future__ import annotations

from rtgait.core.geometry.footsteps import Footstep, wrap_angle


def blend(s: float) -> tuple[float, float]:
    """Quintic blend ``10 s^3 - 15 s^4 + 6 s^5`` and its derivative d/ds, for ``s`` in [0, 1]."""
    s2 = s * s
    return s2 * s * (10.0 - 15.0 * s + 6.0 * s2), 30.0 * s2 * (1.0 - s) * (1.0 - s)


def lift(s: float) -> tuple[float, float]:
    """Height profile ``64 s^3 (1 - s)^3`` (peak 1 at s = 0.5) and its derivative d/ds."""
    r = 1.0 - s
    return 64.0 * s**3 * r**3, 192.0 * s * s * r * r * (r - s)


RISE_SHARE = 0.35
"""Share of a height-changing swing spent rising (and as much coming down) to ``max(z0, z1) + h``."""
HORIZONTAL_DELAY = 0.1
"""Share of a height-changing swing at each end during which the foot only moves vertically."""


def _clip01(s: float) -> float:
    return min(max(s, 0.0), 1.0)


def up_ramp(start: Footstep, end: Footstep) -> bool:
    """Whether a swing from ``start`` to ``end`` goes up a ramp: a foothold tilted to its surface and the landing
    higher (module docstring)."""
    tilted = start.pitch or start.roll or end.pitch or end.roll
    return bool(tilted) and end.z > start.z


def swing_height(z0: float, z1: float, s: float, height: float, ramp: bool = False) -> float:
    """Swing foot height (m) at progress ``s`` in [0, 1] from a foothold at ``z0`` to one at ``z1`` (module
    docstring), ``height`` the clearance above the higher one (``ramp``: up a ramp, above the line between them)."""
    return swing_vertical(z0, z1, s, height, ramp)[0]


def swing_vertical(z0: float, z1: float, s: float, height: float, ramp: bool = False) -> tuple[float, float]:
    """Swing foot height (m) and its derivative d/ds at progress ``s`` (module docstring); ``ramp``: a swing up a
    ramp (:func:`up_ramp`)."""
    if z0 == z1 or ramp:  # level (a flat walk's swings unchanged) or up a ramp: the lift profile over the footholds
        z, dz = lift(s)
        if not ramp:
            return z0 + height * z, height * dz
        k, dk = blend(s)
        return z0 + (z1 - z0) * k + height * z, (z1 - z0) * dk + height * dz
    top = max(z0, z1) + height
    up, dup = blend(_clip01(s / RISE_SHARE))
    down, ddown = blend(_clip01((s - 1.0 + RISE_SHARE) / RISE_SHARE))
    return z0 + (top - z0) * up - (top - z1) * down, ((top - z0) * dup - (top - z1) * ddown) / RISE_SHARE


def _horizontal(start: Footstep, end: Footstep, s: float) -> tuple[float, float]:
    """Horizontal blend and its derivative d/ds: delayed at both ends over a height change but up a ramp."""
    if start.z == end.z or up_ramp(start, end):
        return blend(s)
    span = 1.0 - 2.0 * HORIZONTAL_DELAY
    k, dk = blend(_clip01((s - HORIZONTAL_DELAY) / span))
    return k, dk / span


def swing_pose(start: Footstep, end: Footstep, s: float, height: float) -> tuple[float, float, float, float]:
    """Foot pose ``(x, y, z, yaw)`` (m, rad) at swing progress ``s`` in [0, 1] from ``start`` to ``end``."""
    s = _clip01(s)
    k, _ = _horizontal(start, end, s)
    return (
        start.x + k * (end.x - start.x),
        start.y + k * (end.y - start.y),
        swing_vertical(start.z, end.z, s, height, up_ramp(start, end))[0],
        wrap_angle(start.yaw + k * wrap_angle(end.yaw - start.yaw)),
    )


def swing_velocity(start: Footstep, end: Footstep, s: float, height: float, duration: float) -> tuple[float, ...]:
    """Foot velocity ``(vx, vy, vz, yaw_rate)`` (m/s, rad/s) at swing progress ``s`` over ``duration`` (s)."""
    s = _clip01(s)
    _, dk = _horizontal(start, end, s)
    _, dz = swing_vertical(start.z, end.z, s, height, up_ramp(start, end))
    scale = 1.0 / duration
    return (
        dk * (end.x - start.x) * scale,
        dk * (end.y - start.y) * scale,
        dz * scale,
        dk * wrap_angle(end.yaw - start.yaw) * scale,
    )


def retargeted_swing(
    start: tuple[float, float, float],
    velocity: tuple[float, float, float],
    end: Footstep,
    s: float,
    duration: float,
) -> tuple[float, float, float]:
    """Horizontal pose ``(x, y, yaw)`` (m, rad) of a swing foot sent to a new landing ``end`` mid-swing.

    From the pose ``start`` and velocity ``velocity`` (m/s, rad/s) it had when the landing changed, a quintic over
    the ``duration`` (s) left reaches ``end`` with zero velocity and acceleration: ``x(s) = x0 + (x1 - x0) b(s) +
    T v0 h(s)`` with the blend ``b`` and ``h(s) = s - 6 s^3 + 8 s^4 - 3 s^5`` (``h(0) = 0``, ``h'(0) = 1``, and
    ``h``, ``h'``, ``h''`` zero at 1), so position and velocity are continuous at the change.
    """
    s = min(max(s, 0.0), 1.0)
    k, _ = blend(s)
    s3 = s * s * s
    h = duration * (s - 6.0 * s3 + 8.0 * s3 * s - 3.0 * s3 * s * s)
    x0, y0, yaw0 = start
    return (
        x0 + k * (end.x - x0) + h * velocity[0],
        y0 + k * (end.y - y0) + h * velocity[1],
        wrap_angle(yaw0 + k * wrap_angle(end.yaw - yaw0) + h * velocity[2]),
    )
