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

from collections.abc import Sequence

from rtgait.core.geometry.foot_tilt import foothold_segment
from rtgait.core.geometry.footsteps import Footstep

__all__ = ["changes_ground_height", "ground_height", "ground_rise"]


def ground_height(prints: Sequence[Footstep], side: str, x: float, y: float) -> float:
    """The planned ground height (m) under a ``side`` foot target at ``(x, y)`` (m) among the footholds ``prints``
    (module docstring); 0 when ``prints`` has no foothold of that side."""
    if not any(foot.side == side for foot in prints):
        return 0.0
    a, b, u = foothold_segment(prints, side, x, y)
    return a.z + u * (b.z - a.z)


def ground_rise(prints: Sequence[Footstep], left: Sequence[float], right: Sequence[float]) -> float:
    """The planned ground height under the ``left`` foot target less under the ``right`` one (m); targets start
    ``(x, y, ...)``."""
    return ground_height(prints, "left", left[0], left[1]) - ground_height(prints, "right", right[0], right[1])


def changes_ground_height(prints: Sequence[Footstep]) -> bool:
    """Whether the footholds ``prints`` are not all at one height."""
    return any(foot.z != prints[0].z for foot in prints)
