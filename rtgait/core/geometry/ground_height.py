"""The planned ground height under a foot target: the height of the footholds it stands on or swings between.

A foot target at ``p = (x, y)`` of side ``s`` takes the height of the segment between the two consecutive footholds
``a, b`` of that side nearest to ``p``, by its progress along it (as :mod:`rtgait.core.geometry.foot_tilt` takes
their tilt):

    u = clip((p - a) . (b - a) / |b - a|^2, 0, 1),      z_ground = (1 - u) z_a + u z_b        (m)

so a stance foot stands at its foothold's height and a swing foot reaches the landing's as it arrives over it. The
difference between the feet's is what the estimator's landing gate allows a landing on a planned tread higher than
the other foot's (:mod:`rtgait.estimation.landing_gate`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep

__all__ = ["changes_ground_height", "ground_height", "ground_rise"]


def ground_height(prints: Sequence[Footstep], side: str, x: float, y: float) -> float:
    """The planned ground height (m) under a ``side`` foot target at ``(x, y)`` (m) among the footholds ``prints``
    (module docstring); 0 when ``prints`` has no foothold of that side."""
    own = [foot for foot in prints if foot.side == side]
    if not own:
        return 0.0
    if len(own) == 1:
        return own[0].z
    best, height = float("inf"), 0.0
    for a, b in itertools.pairwise(own):
        dx, dy = b.x - a.x, b.y - a.y
        length2 = dx * dx + dy * dy
        u = 0.0 if length2 == 0.0 else min(1.0, max(0.0, ((x - a.x) * dx + (y - a.y) * dy) / length2))
        ex, ey = a.x + u * dx - x, a.y + u * dy - y
        distance2 = ex * ex + ey * ey
        if distance2 < best:
            best, height = distance2, a.z + u * (b.z - a.z)
    return height


def ground_rise(prints: Sequence[Footstep], left: Sequence[float], right: Sequence[float]) -> float:
    """The planned ground height under the ``left`` foot target less under the ``right`` one (m); targets start
    ``(x, y, ...)``."""
    return ground_height(prints, "left", left[0], left[1]) - ground_height(prints, "right", right[0], right[1])


def changes_ground_height(prints: Sequence[Footstep]) -> bool:
    """Whether the footholds ``prints`` are not all at one height."""
    return any(foot.z != prints[0].z for foot in prints)
