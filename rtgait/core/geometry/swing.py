"""Swing-foot trajectories: smooth lift-off and touch-down.

Horizontal position and yaw follow a quintic blend (zero velocity and acceleration at both ends); the height
follows ``h * 64 s^3 (1 - s)^3``, which peaks at ``h`` mid-swing and also starts and ends with zero velocity and
acceleration, so the foot neither scuffs at lift-off nor strikes at touch-down.
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


def swing_pose(start: Footstep, end: Footstep, s: float, height: float) -> tuple[float, float, float, float]:
    """Foot pose ``(x, y, z, yaw)`` (m, rad) at swing progress ``s`` in [0, 1] from ``start`` to ``end``."""
    s = min(max(s, 0.0), 1.0)
    k, _ = blend(s)
    z, _ = lift(s)
    return (
        start.x + k * (end.x - start.x),
        start.y + k * (end.y - start.y),
        height * z,
        wrap_angle(start.yaw + k * wrap_angle(end.yaw - start.yaw)),
    )


def swing_velocity(start: Footstep, end: Footstep, s: float, height: float, duration: float) -> tuple[float, ...]:
    """Foot velocity ``(vx, vy, vz, yaw_rate)`` (m/s, rad/s) at swing progress ``s`` over ``duration`` (s)."""
    s = min(max(s, 0.0), 1.0)
    _, dk = blend(s)
    _, dz = lift(s)
    scale = 1.0 / duration
    return (
        dk * (end.x - start.x) * scale,
        dk * (end.y - start.y) * scale,
        height * dz * scale,
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
