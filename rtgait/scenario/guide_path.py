"""The path along which a person leads the robot by the hand (a scenario's ``[guide]`` table; the paper's Section 6,
walked in physics by :mod:`rtgait.sim.guided`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["GuidePath"]


@dataclass(frozen=True)
class GuidePath:
    """The path along which a person leads the robot by the hand: straight, an arc, straight, then a stop.

    The path starts at the robot's hand and heads where the robot faces.

    Attributes:
        forward: length of the first straight part (m, >= 0).
        turn: angle of the arc (rad, positive to the left, |turn| <= pi).
        radius: radius of the arc (m, > 0).
        after: length of the straight part after the arc (m, >= 0).
        speed: the person's speed along the path (m/s, > 0).
    """

    forward: float = 1.0
    turn: float = math.pi / 2
    radius: float = 1.0
    after: float = 0.5
    speed: float = 0.15

    def __post_init__(self) -> None:
        checks = {
            "forward": self.forward >= 0.0,
            "radius": self.radius > 0.0,
            "after": self.after >= 0.0,
            "speed": self.speed > 0.0,
            "turn": abs(self.turn) <= math.pi,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and ok):
                raise ValueError(f"guide.{name} is out of range, got {value}")

    @property
    def length(self) -> float:
        """Length of the whole path (m)."""
        return self.forward + abs(self.turn) * self.radius + self.after

    @property
    def duration(self) -> float:
        """Time the person walks (s)."""
        return self.length / self.speed

    def at(self, s: float) -> tuple[float, float, float]:
        """Position ``(x, y)`` (m) and heading (rad) after ``s`` metres along the path, relative to its start
        (heading +x); ``s`` is clipped to ``[0, length]``."""
        s = min(max(s, 0.0), self.length)
        if s <= self.forward:
            return s, 0.0, 0.0
        arc = abs(self.turn) * self.radius
        side = 1.0 if self.turn >= 0.0 else -1.0
        angle = side * min(s - self.forward, arc) / self.radius
        # The arc's centre is `radius` to the side of the end of the first straight part.
        x = self.forward + side * self.radius * math.sin(angle)
        y = side * self.radius * (1.0 - math.cos(angle))
        rest = max(s - self.forward - arc, 0.0)
        return x + rest * math.cos(angle), y + rest * math.sin(angle), angle
