"""Footsteps, strides and sole rectangles of a walk (its phase timeline, re-exported here, is in
:mod:`rtgait.core.geometry.timeline`).

A footprint is a foothold in 3D: its foot frame position ``(x, y, z)`` (m), heading ``yaw`` and the support
surface's ``pitch`` and ``roll`` (rad, rotations about the foot's lateral and forward axes; 0 on level ground). A
stride carries the height change ``rise = z_landing - z_stance`` and the landing surface's pitch and roll, so that a
change of a stride's length keeps the step's height.

Footprints are numbered ``F[0], F[1], ...``: ``F[0]`` is the standing position of the foot that swings first,
``F[1]`` that of the other foot, and ``F[i + 1]`` is where step ``i`` (1-based) lands. Step ``i`` swings the
foot from ``F[i - 1]`` to ``F[i + 1]`` while the robot stands on ``F[i]``.

Phases are numbered ``q = 0, 1, 2, ...`` (:mod:`rtgait.core.geometry.timeline`): ``q = 2i - 1`` is the single
support of step ``i``, ``q = 2i`` the double support after it lands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from rtgait.core.geometry.timeline import PhaseKind, Timeline, Timing, check_step_timings
from rtgait.core.input_bounds import InputOutOfBoundsError
from rtgait.core.limits import MAX_STRIDE, MAX_SURFACE_TILT

Side = Literal["left", "right"]
SIDES: tuple[Side, Side] = ("left", "right")


def other_side(side: Side) -> Side:
    return "right" if side == "left" else "left"


def wrap_angle(angle: float) -> float:
    """Angle wrapped to ``[-pi, pi)`` (rad)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def _require_finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise InputOutOfBoundsError(f"{name} must be a finite number, got {value}")


def _check_height_and_tilt(what: str, z: float, pitch: float, roll: float) -> None:
    """``z`` within +-:data:`MAX_STRIDE` m, ``pitch`` and ``roll`` within +-:data:`MAX_SURFACE_TILT` rad."""
    if not abs(z) <= MAX_STRIDE:  # also refuses NaN
        raise InputOutOfBoundsError(f"{what} z (height) must be finite and within +-{MAX_STRIDE:g} m, got {z}")
    for name, value in (("pitch", pitch), ("roll", roll)):
        if not abs(value) <= MAX_SURFACE_TILT:
            raise InputOutOfBoundsError(
                f"{what} {name} must be finite and within +-{MAX_SURFACE_TILT:g} rad, got {value}"
            )


@dataclass(frozen=True, slots=True)
class Footstep:
    """A footprint: foot frame position (m), yaw (rad), which foot, and its height ``z`` (m) and the support
    surface's ``pitch`` and ``roll`` (rad, each within :data:`~rtgait.core.limits.MAX_SURFACE_TILT`)."""

    x: float
    y: float
    yaw: float
    side: Side
    z: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x) and math.isfinite(self.y) and math.isfinite(self.yaw)):
            for name in ("x", "y", "yaw"):
                _require_finite(f"footstep {name}", getattr(self, name))
        if self.side not in SIDES:
            raise InputOutOfBoundsError(f"footstep side must be 'left' or 'right', got {self.side!r}")
        if self.z or self.pitch or self.roll:  # level footprints (the common case) skip the checks
            _check_height_and_tilt("footstep", self.z, self.pitch, self.roll)

    @property
    def level(self) -> bool:
        """True on level ground at height 0 (every footprint of a flat walk)."""
        return not (self.z or self.pitch or self.roll)

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x, self.y])


@dataclass(frozen=True)
class Stride:
    """Where a step lands relative to the previous footprint (the stance foot).

    Attributes:
        length: forward displacement along the mean heading of the two footprints (m).
        width: lateral distance between the two footprints, positive = feet apart (m).
        turn: yaw change from the stance foot to the landing foot (rad), positive = to the left.
        rise: height of the landing above the stance foot (m), negative = down.
        pitch: pitch of the landing's support surface (rad, absolute, not relative to the stance foot's).
        roll: roll of the landing's support surface (rad, absolute).
    """

    length: float
    width: float
    turn: float = 0.0
    rise: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        if self.rise or self.pitch or self.roll:
            _check_height_and_tilt("stride", self.rise, self.pitch, self.roll)
        for name in ("length", "width", "turn"):
            _require_finite(f"stride {name}", getattr(self, name))
        if self.width <= 0.0:
            raise InputOutOfBoundsError(f"stride width must be > 0 m (feet apart), got {self.width}")
        if abs(self.length) > MAX_STRIDE or self.width > MAX_STRIDE:
            raise InputOutOfBoundsError(
                f"stride length and width must be at most {MAX_STRIDE:g} m, got {self.length}, {self.width}"
            )
        if abs(self.turn) >= math.pi / 2:
            raise InputOutOfBoundsError(f"stride turn must be within +-pi/2 rad, got {self.turn}")


def place_step(stance: Footstep, stride: Stride) -> Footstep:
    """Landing footprint of the other foot for ``stride`` taken from ``stance``."""
    side = other_side(stance.side)
    lateral = stride.width if side == "left" else -stride.width
    heading = stance.yaw + 0.5 * stride.turn
    c, s = math.cos(heading), math.sin(heading)
    return Footstep(
        x=stance.x + c * stride.length - s * lateral,
        y=stance.y + s * stride.length + c * lateral,
        yaw=wrap_angle(stance.yaw + stride.turn),
        side=side,
        z=stance.z + stride.rise,
        pitch=stride.pitch,
        roll=stride.roll,
    )


def stride_between(stance: Footstep, landing: Footstep) -> Stride:
    """Inverse of :func:`place_step`: the stride that takes ``stance`` to ``landing``."""
    if landing.side == stance.side:
        raise InputOutOfBoundsError("consecutive footprints must alternate between left and right")
    turn = wrap_angle(landing.yaw - stance.yaw)
    heading = stance.yaw + 0.5 * turn
    c, s = math.cos(heading), math.sin(heading)
    dx, dy = landing.x - stance.x, landing.y - stance.y
    lateral = -s * dx + c * dy
    width = lateral if landing.side == "left" else -lateral
    return Stride(c * dx + s * dy, width, turn, landing.z - stance.z, landing.pitch, landing.roll)


def standing_feet(step_width: float, first_side: Side = "right") -> tuple[Footstep, Footstep]:
    """``(F[0], F[1])``: feet side by side at the origin, ``step_width`` (m) apart, heading +x."""
    if not (math.isfinite(step_width) and step_width > 0.0):
        raise ValueError(f"step_width must be > 0 m, got {step_width}")
    if first_side not in SIDES:
        raise ValueError(f"first_side must be 'left' or 'right', got {first_side!r}")
    half = 0.5 * step_width
    first = Footstep(0.0, half if first_side == "left" else -half, 0.0, first_side)
    second = Footstep(0.0, -first.y, 0.0, other_side(first_side))
    return first, second


def place_footsteps(start: tuple[Footstep, Footstep], strides: list[Stride]) -> list[Footstep]:
    """Footprints ``F[0..N+1]`` of a walk of ``N = len(strides)`` steps from standing feet ``start``."""
    prints = list(start)
    for stride in strides:
        prints.append(place_step(prints[-1], stride))
    return prints


def midpoint(a: Footstep, b: Footstep) -> tuple[float, float]:
    """Point halfway between two footprints (m)."""
    return 0.5 * (a.x + b.x), 0.5 * (a.y + b.y)


def mean_heading(yaw_a: float, yaw_b: float) -> float:
    """The heading halfway between two (rad), the short way round: safe across the +-pi wrap."""
    return yaw_a + 0.5 * math.remainder(yaw_b - yaw_a, 2.0 * math.pi)


@dataclass(frozen=True)
class SoleRect:
    """Sole rectangle around the foot frame (m): ``front``/``back`` along the foot, ``inner`` toward the other
    foot, ``outer`` away from it. All distances are from the foot frame origin and non-negative."""

    front: float
    back: float
    inner: float
    outer: float

    def __post_init__(self) -> None:
        for name in ("front", "back", "inner", "outer"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"sole {name} must be a finite distance >= 0 m, got {value}")
        if self.front + self.back <= 0.0 or self.inner + self.outer <= 0.0:
            raise ValueError("sole rectangle must have a positive length and width")

    def corners(self, foot: Footstep) -> np.ndarray:
        """World corners of the sole of ``foot``, counter-clockwise, shape ``(4, 2)`` (m)."""
        left = foot.side == "left"
        y_max = self.outer if left else self.inner
        y_min = -self.inner if left else -self.outer
        local = np.array([[self.front, y_min], [self.front, y_max], [-self.back, y_max], [-self.back, y_min]])
        c, s = math.cos(foot.yaw), math.sin(foot.yaw)
        rotation = np.array([[c, -s], [s, c]])
        return local @ rotation.T + foot.position


__all__ = [
    "SIDES", "Footstep", "PhaseKind", "Side", "SoleRect", "Stride", "Timeline", "Timing", "check_step_timings",
    "mean_heading", "midpoint", "other_side", "place_footsteps", "place_step", "standing_feet", "stride_between",
    "wrap_angle",
]  # fmt: skip
