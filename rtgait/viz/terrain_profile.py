"""A side view (x-z) of the terrain under a walk and the soles' heights over it, for the figures of walks off the flat
floor.

The terrain is drawn as its height ``h(x, y)`` (:mod:`rtgait.core.geometry.terrain`) along the line the feet walk:
``y = 0``, or for stepping stones the row of the left foot's stones, ``y = row_spacing / 2`` (both rows lie at the
same x). The soles are their frames' measured ``(x, z)`` over the walk, so a sole standing on a tread lies on its
top and a swing shows its clearance over the nose. The view spans the soles' x and heights with a margin; a pit
(stepping stones) deeper than that is cut at the panel's bottom.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rtgait.core.geometry.scene_boxes import TERRAIN_RGBA
from rtgait.core.geometry.terrain import Flat, SteppingStones, TerrainKind

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["PROFILE_SAMPLES", "draw_terrain_profile", "profile_line"]

PROFILE_SAMPLES = 3000
"""Points of the terrain's profile over the view: 1 mm apart over 3 m, so a stair's riser is drawn upright."""
_MARGIN_X = 0.3  # m beyond the soles' first and last x
_MARGIN_BELOW = 0.15  # m under the lowest sole
_MARGIN_ABOVE = 0.1  # m over the highest sole


def _cm(value: float) -> float:
    """``value`` (m) to the nearest centimetre."""
    return round(float(value) * 100.0) / 100.0


def profile_line(terrain: TerrainKind) -> float:
    """The y (m) along which the profile is taken (module docstring)."""
    return 0.5 * terrain.row_spacing if isinstance(terrain, SteppingStones) else 0.0


def draw_terrain_profile(ax: Axes, terrain: TerrainKind, sole_xz: np.ndarray, source: str = "measured") -> None:
    """Draw ``terrain``'s profile and the soles' paths onto ``ax``: ``sole_xz`` ``(k, 2, 2)``, per sample the
    (left, right) soles' ``(x, z)`` (m; NaN rows are left out), ``source`` what they are (``"measured"``,
    ``"planned"``), for the legend."""
    from rtgait.viz.style import SIDE_COLORS, clean_ticks

    finite = np.isfinite(sole_xz).all(axis=2)
    xs, zs = sole_xz[..., 0][finite], sole_xz[..., 1][finite]
    if xs.size == 0 or isinstance(terrain, Flat):
        return
    # The view's limits on a 1 cm grid: a run read back from a CSV's 10 digits draws the very same profile.
    x = np.linspace(_cm(xs.min() - _MARGIN_X), _cm(xs.max() + _MARGIN_X), PROFILE_SAMPLES)
    y = profile_line(terrain)
    h = np.asarray(terrain.height(x, np.full_like(x, y)), dtype=float)
    bottom = max(float(h.min()), _cm(zs.min() - _MARGIN_BELOW))
    top = _cm(max(float(h.max()), float(zs.max())) + _MARGIN_ABOVE)
    if bottom >= float(h.min()):
        bottom -= 0.05  # some ground under the lowest tread
    where = f" (y = {y:+.2f} m)" if y else ""
    ax.fill_between(x, np.maximum(h, bottom), bottom, color=TERRAIN_RGBA[:3], lw=0, zorder=1,
                    label=f"terrain: {terrain.kind}{where}")  # fmt: skip
    ax.plot(x, np.maximum(h, bottom), color="0.3", lw=0.8, zorder=2)
    for index, side in enumerate(("left", "right")):
        path = np.where(finite[:, index, None], sole_xz[:, index], math.nan)
        ax.plot(path[:, 0], path[:, 1], color=SIDE_COLORS[side], lw=1.1, zorder=3, label=f"{side} sole ({source})")
    ax.set_xlim(float(x[0]), float(x[-1]))
    ax.set_ylim(bottom, top)
    ax.set_xlabel("x (world) [m]")
    ax.set_ylabel("z (world) [m]")
    ax.set_title("side view: the soles' heights over the terrain", fontsize=9)
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=8)
    clean_ticks(ax)
