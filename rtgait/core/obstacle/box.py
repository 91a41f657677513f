"""An obstacle on the ground: a box seen at a given time, and the region a foot frame must keep out of.

The box has its centre at ``(x, y)`` (m), a ``length`` along its own x axis (turned ``yaw`` rad from the world's), a
``width`` across it and a ``height`` (m); it is seen at ``seen_at`` (s from the walk's start).

A sole (:class:`~rtgait.core.geometry.footsteps.SoleRect`, the rectangle ``[-back, front] x [y0, y1]`` around the
foot frame) touches the box when some sole point ``a + R(psi) s`` lies in it, ``a`` the ankle (foot frame origin) and
``psi`` the foot's yaw relative to the box. So the ankle must stay out of the Minkowski sum ``box + (-R(psi) sole)``:
in the box's frame, with ``[sx0, sx1] x [sy0, sy1]`` the bounding box of the turned sole and ``m`` a margin,

    -L/2 - sx1 - m  <=  u  <=  L/2 - sx0 + m,      -W/2 - sy1 - m  <=  v  <=  W/2 - sy0 + m

is the forbidden rectangle of that footprint (:meth:`Obstacle.keep_out`). It is exact for a foot square to the box
(``psi`` a multiple of a quarter turn) and conservative otherwise (the bounding box of a turned sole is larger than
the sole). A swing passes over the box when the box is lower than the swing height less a clearance; otherwise the
ankle's horizontal path, the straight segment from lift-off to landing (:mod:`rtgait.core.geometry.swing`), must stay
out of the forbidden rectangle too (:meth:`Obstacle.segment_hits`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.input_bounds import MAX_POSITION, MAX_TIME

MAX_OBSTACLE_SIZE = 100.0
"""Largest length, width or height of an obstacle (m): anything larger is a wall, not a box on the path."""


@dataclass(frozen=True)
class Obstacle:
    """A box on the ground, seen while walking (module docstring; m, rad, s)."""

    x: float
    y: float
    length: float
    width: float
    height: float
    yaw: float = 0.0
    seen_at: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "length", "width", "height", "yaw", "seen_at"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"obstacle {name} must be a finite number, got {value!r}")
        for name in ("x", "y"):
            if abs(getattr(self, name)) > MAX_POSITION:
                raise ValueError(f"obstacle {name} must be within +-{MAX_POSITION:g} m, got {getattr(self, name)}")
        for name in ("length", "width"):
            if not 0.0 < getattr(self, name) <= MAX_OBSTACLE_SIZE:
                value = getattr(self, name)
                raise ValueError(f"obstacle {name} must be within (0, {MAX_OBSTACLE_SIZE:g}] m, got {value}")
        if not 0.0 <= self.height <= MAX_OBSTACLE_SIZE:
            raise ValueError(f"obstacle height must be within [0, {MAX_OBSTACLE_SIZE:g}] m, got {self.height}")
        if abs(self.yaw) > math.pi:
            raise ValueError(f"obstacle yaw must be within [-pi, pi] rad, got {self.yaw}")
        if not 0.0 <= self.seen_at <= MAX_TIME:
            raise ValueError(f"obstacle seen_at must be within [0, {MAX_TIME:g}] s, got {self.seen_at}")

    # ----- frames ----------------------------------------------------------------------------------------
    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points ``(..., 2)`` (m) in the box's frame (origin at its centre, x along its length)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        d = np.asarray(points, dtype=float) - (self.x, self.y)
        return np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)

    def to_world(self, points: np.ndarray) -> np.ndarray:
        """Points ``(..., 2)`` of the box's frame in the world (m)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        p = np.asarray(points, dtype=float)
        return np.stack([self.x + c * p[..., 0] - s * p[..., 1], self.y + s * p[..., 0] + c * p[..., 1]], axis=-1)

    def corners(self) -> np.ndarray:
        """The box's ground corners in the world, counter-clockwise, ``(4, 2)`` (m)."""
        hl, hw = 0.5 * self.length, 0.5 * self.width
        return self.to_world(np.array([[hl, -hw], [hl, hw], [-hl, hw], [-hl, -hw]]))

    # ----- where a foot may not stand ----------------------------------------------------------------------
    def keep_out(self, foot: Footstep, sole: SoleRect, margin: float) -> tuple[float, float, float, float]:
        """``(u0, u1, v0, v1)``: the rectangle of the box's frame the ankle of ``foot`` (its yaw and side) must stay
        out of for its sole to keep ``margin`` (m) from the box (module docstring)."""
        turned = sole.corners(Footstep(self.x, self.y, foot.yaw, foot.side))  # the sole around the box's centre
        corners = self.to_local(turned)
        sx0, sy0 = corners.min(axis=0)
        sx1, sy1 = corners.max(axis=0)
        hl, hw = 0.5 * self.length, 0.5 * self.width
        return (-hl - sx1 - margin, hl - sx0 + margin, -hw - sy1 - margin, hw - sy0 + margin)

    def keep_out_corners(self, foot: Footstep, sole: SoleRect, margin: float) -> np.ndarray:
        """The corners of :meth:`keep_out` in the world, counter-clockwise, ``(4, 2)`` (m)."""
        u0, u1, v0, v1 = self.keep_out(foot, sole, margin)
        return self.to_world(np.array([[u1, v0], [u1, v1], [u0, v1], [u0, v0]]))

    def clearance(self, foot: Footstep, sole: SoleRect, margin: float) -> float:
        """How far (m) the ankle of ``foot`` is outside its :meth:`keep_out` rectangle along the nearer axis of the
        box: positive outside (the sole keeps at least ``margin`` from the box), negative inside."""
        u0, u1, v0, v1 = self.keep_out(foot, sole, margin)
        u, v = self.to_local(np.array([foot.x, foot.y]))
        return float(max(u0 - u, u - u1, v0 - v, v - v1))

    def segment_hits(self, a: Footstep, b: Footstep, sole: SoleRect, margin: float) -> bool:
        """Whether the ankle's straight path from ``a`` to ``b`` (a swing) crosses the keep-out rectangle of either
        end's yaw (Liang-Barsky clipping; touching the boundary is not crossing)."""
        pa, pb = self.to_local(np.array([[a.x, a.y], [b.x, b.y]]))
        d = pb - pa
        for foot in (a, b):
            u0, u1, v0, v1 = self.keep_out(foot, sole, margin)
            lo, hi = 0.0, 1.0
            inside = True
            for p, q in ((-d[0], pa[0] - u0), (d[0], u1 - pa[0]), (-d[1], pa[1] - v0), (d[1], v1 - pa[1])):
                if abs(p) < 1e-15:
                    if q <= 0.0:
                        inside = False
                        break
                    continue
                r = q / p
                if p < 0.0:
                    lo = max(lo, r)
                else:
                    hi = min(hi, r)
                if lo >= hi:
                    inside = False
                    break
            if inside:
                return True
        return False

    def can_step_over(self, step_height: float, clearance: float) -> bool:
        """Whether a swing of peak ``step_height`` (m) passes over the box with ``clearance`` (m) to spare."""
        return self.height + clearance <= step_height


__all__ = ["MAX_OBSTACLE_SIZE", "Obstacle"]
