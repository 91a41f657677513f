"""The sole's tilt (pitch, roll) a foot target takes from the footholds: the surface it stands on or swings toward.

The planner's samples give each foot as ``(x, y, z, yaw)``; its footholds (:class:`~rtgait.core.geometry.footsteps.
Footstep`) carry the pitch and roll of their surface. A foot target at ``p = (x, y)`` of side ``s`` takes the tilt
of the segment between two consecutive footholds ``a, b`` of that side nearest to ``p``, by its progress along it:

    u = clip((p - a) . (b - a) / |b - a|^2, 0, 1),      tilt = (1 - u) tilt_a + u tilt_b

so a stance foot (``p = a``) has exactly its foothold's tilt, and a swing turns the sole from the lift-off's to the
landing's surface as it moves, levelled to it at touch-down. On level footholds every tilt is 0 and nothing changes.

A foothold's surface is the plane through it with the sole's normal ``n = R e_z``, ``R = Rz(yaw) Ry(pitch) Rx(roll)``:
moved by ``(dx, dy)`` on it the height changes by ``-(n_x dx + n_y dy) / n_z`` (:func:`surface_rise`), the height a
touch-down short of or beyond a tilted foothold re-anchors it at.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep

__all__ = ["foot_tilt", "foothold_segment", "is_tilted", "surface_rise", "tilted_feet"]


def is_tilted(prints: Sequence[Footstep]) -> bool:
    """Whether any of ``prints`` stands on a tilted surface (pitch or roll not 0)."""
    return any(foot.pitch or foot.roll for foot in prints)


def foothold_segment(prints: Sequence[Footstep], side: str, x: float, y: float) -> tuple[Footstep, Footstep, float]:
    """The two consecutive footholds ``a, b`` of side ``side`` nearest to ``(x, y)`` (m) and the progress ``u`` in
    [0, 1] along them (module docstring); ``a = b``, ``u = 0`` for a single foothold.

    Raises:
        ValueError: ``prints`` has no foothold of that side.
    """
    own = [foot for foot in prints if foot.side == side]
    if not own:
        raise ValueError(f"no {side} foothold")
    if len(own) == 1:
        return own[0], own[0], 0.0
    best = (float("inf"), own[0], own[0], 0.0)
    for a, b in itertools.pairwise(own):
        dx, dy = b.x - a.x, b.y - a.y
        length2 = dx * dx + dy * dy
        u = 0.0 if length2 == 0.0 else min(1.0, max(0.0, ((x - a.x) * dx + (y - a.y) * dy) / length2))
        ex, ey = a.x + u * dx - x, a.y + u * dy - y
        distance2 = ex * ex + ey * ey
        if distance2 < best[0]:
            best = (distance2, a, b, u)
    return best[1], best[2], best[3]


def foot_tilt(prints: Sequence[Footstep], side: str, x: float, y: float) -> tuple[float, float]:
    """``(pitch, roll)`` (rad) of a ``side`` foot target at ``(x, y)`` (m) among the footholds ``prints`` (module
    docstring); ``(0, 0)`` when ``prints`` has no foothold of that side."""
    if not any(foot.side == side for foot in prints):
        return 0.0, 0.0
    a, b, u = foothold_segment(prints, side, x, y)
    return a.pitch + u * (b.pitch - a.pitch), a.roll + u * (b.roll - a.roll)


def tilted_feet(
    prints: Sequence[Footstep], left: Sequence[float], right: Sequence[float]
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The feet targets ``(x, y, z, yaw)`` with the footholds' tilt appended: ``(x, y, z, yaw, pitch, roll)``."""
    return (
        (*left[:4], *foot_tilt(prints, "left", left[0], left[1])),
        (*right[:4], *foot_tilt(prints, "right", right[0], right[1])),
    )


def surface_rise(foot: Footstep, dx: float, dy: float) -> float:
    """Height change (m) of the plane a foothold stands on from ``foot`` to ``(foot.x + dx, foot.y + dy)`` (m), the
    module docstring's ``-(n_x dx + n_y dy) / n_z``: ``dx tan(a)`` up a ramp of angle ``a`` along +x (pitch ``-a``),
    0 on a level foothold (a floor, a stair tread)."""
    if not (foot.pitch or foot.roll):
        return 0.0
    cy, sy = math.cos(foot.yaw), math.sin(foot.yaw)
    cp, sp = math.cos(foot.pitch), math.sin(foot.pitch)
    cr, sr = math.cos(foot.roll), math.sin(foot.roll)
    # R e_z = Rz(yaw) (sp cr, -sr, cp cr)
    ax, ay, nz = sp * cr, -sr, cp * cr
    nx, ny = cy * ax - sy * ay, sy * ax + cy * ay
    return -(nx * dx + ny * dy) / nz
