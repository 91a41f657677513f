"""Swing-foot trajectories: smooth lift-off and touch-down, and over a height change.

Horizontal position and yaw follow a quintic blend (zero velocity and acceleration at both ends); between footholds
at one height ``z0`` the height follows ``z0 + h * 64 s^3 (1 - s)^3``, which peaks at ``h`` mid-swing and also starts
and ends with zero velocity and acceleration, so the foot neither scuffs at lift-off nor strikes at touch-down.

Between footholds at different heights ``z0 != z1`` (a stair, a step) the foot rises first and comes down last:
with ``top = max(z0, z1) + h`` and ``sigma`` = :data:`RISE_SHARE`,
``z(s) = z0 + (top - z0) b(s / sigma) - (top - z1) b((s - 1 + sigma) / sigma)`` (``b`` the quintic blend, clipped to
[0, 1]), so the sole is ``h`` above the higher foothold over the middle ``1 - 2 sigma`` of the swing, and the
horizontal blend starts :data:`HORIZONTAL_DELAY` later and ends as much earlier: the toe is above the upper tread
before it passes the stair nose (going up).

Down a stair (both footholds level, the landing lower: :func:`down_stair`) the foot moves forward first and comes down
after: the horizontal blend runs from the lift-off to :data:`DESCENT_REACH` of the swing (``k(s) = b(s / R)``), the
height rises to ``top = z0 + h`` over the first :data:`DESCENT_RISE` (``rho``) and comes straight down onto the landing
over the rest, ``z(s) = z0 + (top - z0) b(s / rho) - (top - z1) b((s - R) / (1 - R))``. The sole thus stays ``h``
above the upper tread until it is over its landing, so no nose between the footholds (none higher than the upper
tread) comes closer than ``h`` wherever it lies, also the one just behind the landing's heel; and the foot is no
longer held high over the tread below, behind and then level with the stance foot, while the stance leg bends to
lower the body (:mod:`rtgait.core.geometry.support_height`): with the profile above, Talos's swing leg folded to 0.28 m
hip-to-ankle over the 0.185 m stairs, out of its reach (``docs/results.md``).

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
from rtgait.core.geometry.toe_off import stair_rise


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
DESCENT_REACH = 0.5
"""Share of a swing down a stair by which the foot has reached its landing horizontally, at the top; over the rest
it comes straight down onto it (module docstring)."""
DESCENT_RISE = 0.25
"""Share of a swing down a stair over which the sole rises to ``h`` above the upper tread, while it already moves
forward: at the lift-off the height grows as ``10 h (s / DESCENT_RISE)^3`` and the forward travel as
``10 L (s / DESCENT_REACH)^3``, as steep as each other (45 degrees) for ``DESCENT_RISE = DESCENT_REACH (h / L)^(1/3)``,
0.23-0.24 for the built-in stairs (h = 0.05 m, L = 0.44-0.50 m); at 0.25 the toe, on the tread at the lift-off, rises
off it at 39-42 degrees. Rising over :data:`RISE_SHARE` instead (16-18 degrees), Talos fell at the end of its 15 cm
stairs in one run of three (``docs/results.md``)."""


def _clip01(s: float) -> float:
    return min(max(s, 0.0), 1.0)


def up_ramp(start: Footstep, end: Footstep) -> bool:
    """Whether a swing from ``start`` to ``end`` goes up a ramp: a foothold tilted to its surface and the landing
    higher (module docstring)."""
    tilted = start.pitch or start.roll or end.pitch or end.roll
    return bool(tilted) and end.z > start.z


def down_stair(start: Footstep, end: Footstep) -> bool:
    """Whether a swing from ``start`` to ``end`` goes down a stair: both footholds level, the landing lower by
    :data:`~rtgait.core.geometry.toe_off.MIN_RISE` or more."""
    return stair_rise(start, end) < 0.0


def swing_height(z0: float, z1: float, s: float, height: float, ramp: bool = False, stair_down: bool = False) -> float:
    """Swing foot height (m) at progress ``s`` in [0, 1] from a foothold at ``z0`` to one at ``z1`` (module
    docstring), ``height`` the clearance above the higher one (``ramp``: up a ramp, above the line between them;
    ``stair_down``: down a stair, :func:`down_stair`)."""
    return swing_vertical(z0, z1, s, height, ramp, stair_down)[0]


def swing_vertical(
    z0: float, z1: float, s: float, height: float, ramp: bool = False, stair_down: bool = False
) -> tuple[float, float]:
    """Swing foot height (m) and its derivative d/ds at progress ``s`` (module docstring); ``ramp``: a swing up a
    ramp (:func:`up_ramp`), ``stair_down``: down a stair (:func:`down_stair`)."""
    if z0 == z1 or ramp:  # level (a flat walk's swings unchanged) or up a ramp: the lift profile over the footholds
        z, dz = lift(s)
        if not ramp:
            return z0 + height * z, height * dz
        k, dk = blend(s)
        return z0 + (z1 - z0) * k + height * z, (z1 - z0) * dk + height * dz
    top = max(z0, z1) + height
    if stair_down:  # forward at the top first, then straight down (module docstring)
        up, dup = blend(_clip01(s / DESCENT_RISE))
        span = 1.0 - DESCENT_REACH
        down, ddown = blend(_clip01((s - DESCENT_REACH) / span))
        return z0 + (top - z0) * up - (top - z1) * down, (top - z0) * dup / DESCENT_RISE - (top - z1) * ddown / span
    up, dup = blend(_clip01(s / RISE_SHARE))
    down, ddown = blend(_clip01((s - 1.0 + RISE_SHARE) / RISE_SHARE))
    return z0 + (top - z0) * up - (top - z1) * down, ((top - z0) * dup - (top - z1) * ddown) / RISE_SHARE


def _horizontal(start: Footstep, end: Footstep, s: float) -> tuple[float, float]:
    """Horizontal blend and its derivative d/ds: delayed at both ends over a height change but up a ramp."""
    if start.z == end.z or up_ramp(start, end):
        return blend(s)
    if down_stair(start, end):  # from the lift-off, done at DESCENT_REACH
        k, dk = blend(_clip01(s / DESCENT_REACH))
        return k, dk / DESCENT_REACH
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
        swing_vertical(start.z, end.z, s, height, up_ramp(start, end), down_stair(start, end))[0],
        wrap_angle(start.yaw + k * wrap_angle(end.yaw - start.yaw)),
    )


def swing_velocity(start: Footstep, end: Footstep, s: float, height: float, duration: float) -> tuple[float, ...]:
    """Foot velocity ``(vx, vy, vz, yaw_rate)`` (m/s, rad/s) at swing progress ``s`` over ``duration`` (s)."""
    s = _clip01(s)
    _, dk = _horizontal(start, end, s)
    _, dz = swing_vertical(start.z, end.z, s, height, up_ramp(start, end), down_stair(start, end))
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
