"""The phase being sampled, as a control tick reads it: timing, support, feet on the ground, the swing.

Built once per phase (and again whenever the walk changes), so that a sample does no lookup beyond a comparison of
times. A swing whose landing moved mid-swing (step adjustment, an early touch-down) carries a *retarget*: the
pose and velocity the foot had when it moved, from which it continues smoothly
(:func:`~rtgait.core.geometry.swing.retargeted_swing`).
"""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import Footstep, Timeline
from rtgait.core.geometry.swing import (
    down_stair,
    retargeted_swing,
    swing_height,
    swing_pose,
    swing_velocity,
    up_ramp,
)
from rtgait.core.walk.walk import Walk

SwingRetarget = tuple[float, tuple[float, float, float], tuple[float, float, float], float]
"""``(since, pose, velocity, lift)``: time (s from the walk's start) the landing (or the touch-down time) moved, the
swing foot's horizontal pose ``(x, y, yaw)`` (m, rad) and velocity (m/s, rad/s) then, and its progress along the
height profile then (0..1): the height goes on from there to touch-down, so a swing shortened by step timing
adaptation keeps a continuous height."""


class PhaseInfo:
    """The phase containing a time: index, start and end relative to the walk's start (s), support label, the poses
    of the feet on the ground (both, left then right, in double support; the stance foot in single support), the
    swing foot's start and landing footprints (``None`` in double support) and its retarget if any."""

    __slots__ = ("duration", "end", "feet", "index", "retarget", "start", "support", "swing_from", "swing_to")

    def __init__(
        self,
        index: int,
        start: float,
        end: float,
        support: str,
        feet: tuple[float, ...],
        swing_from: Footstep | None = None,
        swing_to: Footstep | None = None,
        retarget: SwingRetarget | None = None,
    ) -> None:
        self.index, self.start, self.end, self.duration = index, start, end, end - start
        self.support, self.feet, self.swing_from, self.swing_to = support, feet, swing_from, swing_to
        self.retarget = retarget

    def swing(self, rel: float, height: float) -> tuple[float, float, float, float]:
        """Swing foot pose ``(x, y, z, yaw)`` (m, rad) at ``rel`` (s from the walk's start)."""
        if self.retarget is None:
            return swing_pose(self.swing_from, self.swing_to, (rel - self.start) / self.duration, height)
        since, pose0, vel0, _ = self.retarget
        span = self.end - since
        x, y, yaw = retargeted_swing(pose0, vel0, self.swing_to, (rel - since) / span, span)
        progress = min(max(self.lift_progress(rel), 0.0), 1.0)
        a, b = self.swing_from, self.swing_to
        z = swing_height(a.z, b.z, progress, height, up_ramp(a, b), down_stair(a, b))
        return (x, y, z, yaw)

    def lift_progress(self, rel: float) -> float:
        """Progress along the height profile at ``rel`` (s from the walk's start): ``(rel - start) / duration``, or
        after a retarget at ``since`` with progress ``s0``, ``s0 + (1 - s0) (rel - since) / (end - since)`` (the
        same when the touch-down time did not move)."""
        if self.retarget is None:
            return (rel - self.start) / self.duration
        since, _, _, s0 = self.retarget
        return s0 + (1.0 - s0) * (rel - since) / (self.end - since)

    def swing_state(self, rel: float, height: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Horizontal pose ``(x, y, yaw)`` and velocity of the swing foot at ``rel``, to retarget from."""
        if self.retarget is None:
            s = (rel - self.start) / self.duration
            x, y, _, yaw = swing_pose(self.swing_from, self.swing_to, s, height)
            vx, vy, _, vyaw = swing_velocity(self.swing_from, self.swing_to, s, height, self.duration)
            return (x, y, yaw), (vx, vy, vyaw)
        h = 1e-6  # a second move within one swing: its velocity by a difference (rare, and smooth enough)
        a, b = self.swing(rel, height), self.swing(rel + h, height)
        return (a[0], a[1], a[3]), ((b[0] - a[0]) / h, (b[1] - a[1]) / h, (b[3] - a[3]) / h)


def phase_info(walk: Walk, timeline: Timeline, rel: float, retarget: tuple[int, SwingRetarget] | None) -> PhaseInfo:
    """What sampling needs to know about the phase containing ``rel`` (s from the start of the walk);
    ``retarget`` is ``(phase, retarget)`` of the last swing whose landing moved."""
    q = timeline.phase_at(rel)
    start = timeline.start_time(q)
    last = timeline.last_phase
    end = math.inf if q == last else timeline.start_time(q + 1)
    if q & 1 and timeline.kind(q) == "single":
        i = (q + 1) >> 1
        stance = walk.footprint(i)
        pose = (stance.x, stance.y, stance.z, stance.yaw)
        moved = retarget[1] if retarget is not None and retarget[0] == q else None
        return PhaseInfo(q, start, end, stance.side, pose, walk.footprint(i - 1), walk.footprint(i + 1), moved)
    a, b = walk.contact_feet(q)
    if a.side != "left":
        a, b = b, a
    return PhaseInfo(q, start, end, "double", (a.x, a.y, a.z, a.yaw, b.x, b.y, b.z, b.yaw))
