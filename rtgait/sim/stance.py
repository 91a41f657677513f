"""The stances of a walk's feet and how far each slipped: the slip measure of :class:`~rtgait.sim.result.SimResult`.

A *stance* is a stretch of ticks over which the foot carries at least :data:`STANCE_FRACTION` of the weight; its
slip is the largest horizontal distance of the sole point from where it was at the stance's first tick (m), and
likewise the largest change of heading (rad).
:attr:`SimResult.foot_slip_max <rtgait.sim.result.SimResult.foot_slip_max>` is the largest over all stances: a
robot that walks keeps it at a millimetre or two; one that is dragged does not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["STANCE_FRACTION", "Stance", "stances"]

STANCE_FRACTION = 0.1
"""A foot is a stance foot, for the slip measure, while it carries at least this fraction of the weight: a foot
that only touches (the end of a swing, the start of a lift-off) may scuff without the robot slipping."""


@dataclass(frozen=True)
class Stance:
    """One foot's stretch of ticks on the ground under load, and how far it slipped.

    Attributes:
        side: ``"left"`` or ``"right"``.
        start, end: its first and last tick times (s, walk clock).
        slip: largest horizontal distance of the sole point from its place at ``start`` (m).
        yaw_slip: largest change of the sole's heading from ``start`` (rad).
    """

    side: str
    start: float
    end: float
    slip: float
    yaw_slip: float


def stances(times: np.ndarray, normal_force: np.ndarray, sole_pose: np.ndarray, threshold: float) -> list[Stance]:
    """The stances of both feet (module docstring): ``normal_force`` ``(k, 2)`` (N) above ``threshold`` (N), sole
    poses ``(k, 2, 3)`` as ``(x, y, yaw)`` (m, rad)."""
    found = []
    for i, side in enumerate(("left", "right")):
        loaded = np.r_[False, normal_force[:, i] >= threshold, False].astype(np.int8)
        edges = np.flatnonzero(np.diff(loaded))
        for begin, stop in zip(edges[::2], edges[1::2], strict=True):
            pose = sole_pose[begin:stop, i]
            moved = pose[:, 0:2] - pose[0, 0:2]
            turned = np.abs(np.remainder(pose[:, 2] - pose[0, 2] + math.pi, 2.0 * math.pi) - math.pi)
            found.append(
                Stance(side, float(times[begin]), float(times[stop - 1]), float(np.hypot(*moved.T).max()),
                       float(turned.max()))
            )  # fmt: skip
    return sorted(found, key=lambda s: s.start)
