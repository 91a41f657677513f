"""Terrain the robot walks on: its height ``z = h(x, y)`` (m) and the footholds placed on it.

Every terrain runs along the world x axis (the walk's heading from the standing feet at the origin) and is level
before its ``start`` (x, m):

* :class:`Flat`: ``h = 0``.
* :class:`Stairs`: ``count`` steps of ``riser`` (m) height and ``tread`` (m) depth, going up (or down) from ``start``:
  ``h = +-riser * min(floor((x - start) / tread) + 1, count)`` for ``x >= start``; the stair noses are at
  ``x = start + k tread``.
* :class:`Slope`: a ramp of ``angle`` (rad, positive up) over ``length`` (m, horizontal) from ``start``, level
  after it: ``h = tan(angle) * clip(x - start, 0, length)``.
* :class:`SteppingStones`: ``count`` pairs of stones ``length`` x ``width`` (m), ``gap`` (m) apart along x, one row
  under each foot (``y = +-row_spacing / 2``), their tops at ``h = 0``; off the stones, from ``start`` to the last
  stone, a pit :data:`PIT_DEPTH` deep.
* :class:`Step`: ``h = height`` for ``x >= x_step`` (negative: a step down).
* :class:`~rtgait.core.geometry.heightfield.Heightfield`: anything else, a grid of heights read from a file.

:func:`surface` gives the support surface under a point: its height and the foot's pitch and roll on it (pitch is a
right-hand rotation about the foot's lateral axis, so a floor rising along the foot's heading ``psi`` has pitch
``-atan(dh/ds)``). :func:`place_footstep` puts a footprint on the terrain and :func:`sole_gap` measures how far the
terrain lies below (positive) or cuts into (negative) a sole placed there.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, replace
from typing import Any, Literal, Protocol

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.heightfield import Heightfield

PIT_DEPTH = 1.0
"""Depth of the pit between stepping stones (m): deep enough that no sole touches its floor."""
EDGE_TOLERANCE = 0.005
"""How far a terrain point may rise above a sole placed on the terrain before the sole is said to cut into an edge
(m): the height of a sole's rubber, not of a step."""
_SLOPE_PROBE = 1e-4  # m: the finite difference that gives a surface's slope where it is smooth


class Terrain(Protocol):
    """A height field ``h(x, y)`` (m), vectorised over numpy arrays."""

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float: ...


def _check(name: str, value: float, low: float, high: float, unit: str, *, open_low: bool = False) -> None:
    ok = math.isfinite(value) and (low < value if open_low else low <= value) and value <= high
    if not ok:
        bracket = "(" if open_low else "["
        raise ValueError(f"terrain {name} must be within {bracket}{low:g}, {high:g}] {unit}, got {value}")


@dataclass(frozen=True)
class Flat:
    """Level ground at height 0."""

    kind: Literal["flat"] = "flat"

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        return np.zeros(np.broadcast(x, y).shape) if np.ndim(x) or np.ndim(y) else 0.0


@dataclass(frozen=True)
class Stairs:
    """``count`` steps of ``riser`` x ``tread`` (m) from ``x = start`` (m), ``direction`` ``"up"`` or ``"down"``."""

    riser: float
    tread: float
    count: int
    direction: Literal["up", "down"] = "up"
    start: float = 0.5
    kind: Literal["stairs"] = "stairs"

    def __post_init__(self) -> None:
        _check("riser", self.riser, 0.0, 0.5, "m", open_low=True)
        _check("tread", self.tread, 0.05, 2.0, "m")
        if not (isinstance(self.count, int) and 1 <= self.count <= 1000):
            raise ValueError(f"terrain count must be an integer within [1, 1000], got {self.count!r}")
        if self.direction not in ("up", "down"):
            raise ValueError(f"terrain direction must be 'up' or 'down', got {self.direction!r}")
        _check("start", self.start, -100.0, 100.0, "m")

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        steps = np.clip(np.floor((np.asarray(x, float) - self.start) / self.tread) + 1.0, 0.0, self.count)
        sign = 1.0 if self.direction == "up" else -1.0
        h = sign * self.riser * steps + 0.0 * np.asarray(y, float)
        return h if np.ndim(h) else float(h)


@dataclass(frozen=True)
class Slope:
    """A ramp of ``angle`` (rad, positive up) over ``length`` (m) from ``x = start`` (m), level after it."""

    angle: float
    length: float
    start: float = 0.5
    kind: Literal["slope"] = "slope"

    def __post_init__(self) -> None:
        _check("angle", self.angle, -0.5, 0.5, "rad")
        _check("length", self.length, 0.0, 100.0, "m", open_low=True)
        _check("start", self.start, -100.0, 100.0, "m")

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        run = np.clip(np.asarray(x, float) - self.start, 0.0, self.length)
        h = math.tan(self.angle) * run + 0.0 * np.asarray(y, float)
        return h if np.ndim(h) else float(h)


@dataclass(frozen=True)
class SteppingStones:
    """``count`` pairs of stones ``length`` x ``width`` (m), ``gap`` (m) apart along x from ``x = start`` (m), rows
    ``row_spacing`` (m) apart, centred on ``y = 0``; a pit :data:`PIT_DEPTH` deep around them."""

    length: float
    width: float
    gap: float
    count: int
    row_spacing: float
    start: float = 0.3
    kind: Literal["stones"] = "stones"

    def __post_init__(self) -> None:
        _check("stone length", self.length, 0.05, 2.0, "m")
        _check("stone width", self.width, 0.05, 2.0, "m")
        _check("gap", self.gap, 0.0, 2.0, "m")
        if not (isinstance(self.count, int) and 1 <= self.count <= 1000):
            raise ValueError(f"terrain count must be an integer within [1, 1000], got {self.count!r}")
        _check("row spacing", self.row_spacing, self.width, 2.0, "m", open_low=True)
        _check("start", self.start, -100.0, 100.0, "m")

    @property
    def end(self) -> float:
        """Far edge of the last stone (m): level ground again after it."""
        return self.start + self.count * (self.length + self.gap) - self.gap

    def centre(self, k: int) -> float:
        """x of the centre of the ``k``-th stone of each row (m), ``k = 0..count - 1``."""
        return self.start + 0.5 * self.length + k * (self.length + self.gap)

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        pitch = self.length + self.gap
        along = np.mod(x - self.start, pitch)
        on_row = np.abs(np.abs(y) - 0.5 * self.row_spacing) <= 0.5 * self.width
        on_stone = (along <= self.length) & on_row
        in_field = (x >= self.start) & (x <= self.end)
        h = np.where(in_field & ~on_stone, -PIT_DEPTH, 0.0)
        return h if np.ndim(h) else float(h)


@dataclass(frozen=True)
class Step:
    """A single step of ``height`` (m, negative: down) at ``x = x_step`` (m)."""

    height_change: float
    x_step: float
    kind: Literal["step"] = "step"

    def __post_init__(self) -> None:
        _check("step height", self.height_change, -0.5, 0.5, "m")
        _check("step x", self.x_step, -100.0, 100.0, "m")

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        h = np.where(np.asarray(x, float) >= self.x_step, self.height_change, 0.0) + 0.0 * np.asarray(y, float)
        return h if np.ndim(h) else float(h)


TerrainKind = Flat | Stairs | Slope | SteppingStones | Step | Heightfield
"""Every terrain a scenario's ``[terrain]`` table describes."""
TERRAIN_CLASSES: dict[str, type[TerrainKind]] = {
    cls.kind: cls  # type: ignore[misc]
    for cls in (Flat, Stairs, Slope, SteppingStones, Step, Heightfield)
}
"""Each terrain's class by its ``kind``."""


def terrain_fields(terrain: TerrainKind) -> dict[str, Any]:
    """``terrain`` as JSON-ready fields, ``kind`` among them (m, rad; :func:`terrain_from_fields` reads them back); a
    height field's grid as nested lists (rows along y)."""
    fields = dataclasses.asdict(terrain)
    if isinstance(terrain, Heightfield):
        fields.update(heights=terrain.heights.tolist(), size=list(terrain.size), origin=list(terrain.origin))
    return fields


def terrain_from_fields(fields: dict[str, Any]) -> TerrainKind:
    """The terrain of :func:`terrain_fields`' output; a ``ValueError`` names a bad kind or field."""
    kind = fields.get("kind")
    if kind not in TERRAIN_CLASSES:
        raise ValueError(f"terrain kind must be one of {', '.join(map(repr, TERRAIN_CLASSES))}, got {kind!r}")
    try:
        return TERRAIN_CLASSES[kind](**fields)  # type: ignore[arg-type]
    except TypeError as error:
        raise ValueError(f"terrain {kind}: {error}") from None


def surface(terrain: Terrain, x: float, y: float, yaw: float) -> tuple[float, float, float]:
    """``(z, pitch, roll)`` of the support surface at ``(x, y)`` under a foot heading ``yaw`` (m, rad).

    The slope is a centred difference over :data:`_SLOPE_PROBE`; on an edge (a stair nose) the two sides differ by
    the step and the foot's tilt would be meaningless, so a slope steeper than 1 counts as level.
    """
    z = float(terrain.height(x, y)) + 0.0  # + 0.0: no -0.0 in outputs
    c, s = math.cos(yaw), math.sin(yaw)
    d = _SLOPE_PROBE
    forward = (float(terrain.height(x + d * c, y + d * s)) - float(terrain.height(x - d * c, y - d * s))) / (2 * d)
    lateral = (float(terrain.height(x - d * s, y + d * c)) - float(terrain.height(x + d * s, y - d * c))) / (2 * d)
    pitch = 0.0 - math.atan(forward) if abs(forward) <= 1.0 else 0.0
    # Roll is right-hand about the foot's forward axis: it lifts the foot's left edge, as ground rising to the left.
    roll = math.atan(lateral) + 0.0 if abs(lateral) <= 1.0 else 0.0
    return z, pitch, roll


def place_footstep(terrain: Terrain, foot: Footstep) -> Footstep:
    """``foot`` with the height, pitch and roll of the terrain under its frame origin."""
    z, pitch, roll = surface(terrain, foot.x, foot.y, foot.yaw)
    return replace(foot, z=z, pitch=pitch, roll=roll)


def sole_points(foot: Footstep, sole: SoleRect, n_long: int = 7, n_wide: int = 5) -> np.ndarray:
    """World points ``(n, 3)`` (m) of a grid over the sole of ``foot``, on the plane of its pitch and roll."""
    left = foot.side == "left"
    y_hi = sole.outer if left else sole.inner
    y_lo = -sole.inner if left else -sole.outer
    u, v = np.meshgrid(np.linspace(-sole.back, sole.front, n_long), np.linspace(y_lo, y_hi, n_wide))
    u, v = u.ravel(), v.ravel()
    c, s = math.cos(foot.yaw), math.sin(foot.yaw)
    # Heights on the tilted sole plane: pitch lowers the toes (right-hand about the lateral axis), roll the right edge.
    z = foot.z - math.tan(foot.pitch) * u + math.tan(foot.roll) * v
    return np.column_stack((foot.x + c * u - s * v, foot.y + s * u + c * v, z))


def sole_gap(terrain: Terrain, foot: Footstep, sole: SoleRect) -> tuple[float, float]:
    """``(lowest, highest)`` gap (m) between the sole of ``foot`` and the terrain under it: the sole's height minus the
    terrain's over a grid of the sole. A negative ``lowest`` means the terrain cuts into the sole (an edge under it);
    a large ``highest`` means part of the sole overhangs a drop."""
    points = sole_points(foot, sole)
    gap = points[:, 2] - np.asarray(terrain.height(points[:, 0], points[:, 1]), float)
    return float(gap.min()), float(gap.max())


__all__ = [
    "EDGE_TOLERANCE", "PIT_DEPTH", "TERRAIN_CLASSES", "Flat", "Heightfield", "Slope", "Stairs", "Step",
    "SteppingStones", "Terrain", "TerrainKind", "place_footstep", "sole_gap", "sole_points", "surface",
    "terrain_fields", "terrain_from_fields",
]  # fmt: skip
