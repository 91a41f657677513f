"""A terrain given as a grid of heights (a scenario's heightfield file).

:class:`Heightfield`: heights ``H[i, j]`` (m) on a regular grid of ``ny x nx`` samples (``i`` along y, ``j`` along
x) spanning ``size = (Lx, Ly)`` (m) from ``origin = (x0, y0)``, the world position of sample ``H[0, 0]``::

    x_j = x0 + j Lx / (nx - 1),    y_i = y0 + i Ly / (ny - 1)

Between samples the surface is piecewise planar: each cell is cut into two triangles along its diagonal from
``(x_j, y_i)`` to ``(x_j+1, y_i+1)``, as MuJoCo's height field collides (its triangular prisms), so that the planner
and the simulator see the same ground. With ``(u, v)`` in ``[0, 1]^2`` the position in the cell and ``h00, h10, h01,
h11`` its corners (``h10`` one sample further along x)::

    h = h00 + u (h10 - h00) + v (h11 - h10)     (u >= v)
    h = h00 + v (h01 - h00) + u (h11 - h01)     (u <  v)

Outside the grid the ground is level at ``h = 0``.

Footholds are placed on it by the least-squares plane under each sole
(:func:`~rtgait.core.geometry.terrain_walk.sole_plane`).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

MAX_GRID_SAMPLES = 4_000_000
"""Most samples a height field may have (32 MB of float64): a 20 m x 20 m field at 1 cm."""
MAX_ABS_HEIGHT = 5.0
"""Largest ``|height|`` a height field may hold (m): more than any floor a walking humanoid meets."""


def _check_pair(name: str, pair: tuple[float, float], low: float, high: float, *, positive: bool = False) -> None:
    ok = len(pair) == 2 and all(math.isfinite(v) and low <= v <= high and (v > 0.0 or not positive) for v in pair)
    if not ok:
        rule = f"within (0, {high:g}]" if positive else f"within [{low:g}, {high:g}]"
        raise ValueError(f"terrain {name} must be two numbers {rule} m, got {pair!r}")


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Heights ``heights`` ``(ny, nx)`` (m) over ``size`` ``(Lx, Ly)`` (m) from ``origin`` ``(x0, y0)`` (m), the
    position of ``heights[0, 0]``; ``source`` names the file they came from (informative)."""

    heights: np.ndarray
    size: tuple[float, float]
    origin: tuple[float, float] = (0.0, 0.0)
    source: str = field(default="")
    kind: Literal["heightfield"] = "heightfield"

    def __post_init__(self) -> None:
        grid = np.asarray(self.heights)
        if grid.ndim != 2 or min(grid.shape) < 2:
            raise ValueError(f"terrain heights must be a 2D grid of at least 2 x 2 samples, got shape {grid.shape}")
        if grid.size > MAX_GRID_SAMPLES:
            raise ValueError(f"terrain heights must have at most {MAX_GRID_SAMPLES} samples, got {grid.size}")
        if not np.issubdtype(grid.dtype, np.number) or not np.all(np.isfinite(grid)):
            raise ValueError("terrain heights must be finite numbers (m)")
        if np.abs(grid).max() > MAX_ABS_HEIGHT:
            raise ValueError(f"terrain heights must be within +-{MAX_ABS_HEIGHT:g} m, got {np.abs(grid).max():g}")
        _check_pair("size", tuple(self.size), 0.0, 200.0, positive=True)
        _check_pair("origin", tuple(self.origin), -100.0, 100.0)
        grid = np.array(grid, dtype=float)  # an own copy, read-only: the terrain cannot change under a walk
        grid.flags.writeable = False
        object.__setattr__(self, "heights", grid)
        object.__setattr__(self, "size", (float(self.size[0]), float(self.size[1])))
        object.__setattr__(self, "origin", (float(self.origin[0]), float(self.origin[1])))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Heightfield):
            return NotImplemented
        same = (self.size, self.origin) == (other.size, other.origin)
        return same and np.array_equal(self.heights, other.heights)

    def __hash__(self) -> int:
        return hash((self.size, self.origin, self.digest))

    @property
    def digest(self) -> str:
        """A hash of the grid (16 hex digits): two fields with the same heights have the same digest."""
        return hashlib.sha256(self.heights.tobytes() + str(self.heights.shape).encode()).hexdigest()[:16]

    @property
    def spacing(self) -> tuple[float, float]:
        """Distance between samples along x and y (m)."""
        ny, nx = self.heights.shape
        return self.size[0] / (nx - 1), self.size[1] / (ny - 1)

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray | float:
        """``h(x, y)`` (m), vectorised (module docstring)."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        grid = self.heights
        ny, nx = grid.shape
        dx, dy = self.spacing
        gx, gy = (x - self.origin[0]) / dx, (y - self.origin[1]) / dy
        inside = (gx >= 0.0) & (gx <= nx - 1) & (gy >= 0.0) & (gy <= ny - 1)
        j = np.clip(np.floor(np.where(inside, gx, 0.0)), 0, nx - 2).astype(int)
        i = np.clip(np.floor(np.where(inside, gy, 0.0)), 0, ny - 2).astype(int)
        u, v = np.clip(gx - j, 0.0, 1.0), np.clip(gy - i, 0.0, 1.0)
        h00, h10, h01, h11 = grid[i, j], grid[i, j + 1], grid[i + 1, j], grid[i + 1, j + 1]
        lower = h00 + u * (h10 - h00) + v * (h11 - h10)
        upper = h00 + v * (h01 - h00) + u * (h11 - h01)
        h = np.where(inside, np.where(u >= v, lower, upper), 0.0)
        return h if np.ndim(h) else float(h)


__all__ = ["MAX_ABS_HEIGHT", "MAX_GRID_SAMPLES", "Heightfield"]
