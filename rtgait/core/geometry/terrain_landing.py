"""A landing moved by step adjustment, put on the terrain: kept on its foothold's own surface and given its height
and tilt there.

Step adjustment (:mod:`rtgait.core.laws.landing_choice`) moves a landing ``F`` horizontally by ``delta`` (m). On
terrain the new place must still carry the sole: :func:`land_on_terrain` shrinks ``delta`` until the sole keeps the
support it had at ``F``, and gives the landing the terrain's height and tilt there.

*Support.* A sole placed at ``p`` (on the plane of the terrain's surface under its frame origin,
:func:`~rtgait.core.geometry.terrain.surface`; on a height field the least-squares plane under it,
:func:`~rtgait.core.geometry.terrain_walk.sole_plane`) is supported at a point of a grid over it
(:data:`SOLE_GRID` apart) where the terrain lies within :data:`~rtgait.core.geometry.terrain.EDGE_TOLERANCE` of that
plane; ``n(p)`` counts those points. Over a stair nose or a stone's side the terrain drops (or rises) by the riser
or the pit under part of the sole, and ``n`` falls.

*The clamp.* With ``delta = a e_a + b e_b`` in the landing's frame (``e_a`` along its heading, ``e_b`` to its left),
the move along each axis is the largest fraction ``s`` in [0, 1] such that every place from ``F`` to ``F + s a e_a``
(sampled every :data:`SCAN_STEP`) has ``n >= n(F)``: the sole keeps at least its planned support, so it stays on
the tread or stone it was planned on (a place on the next tread is beyond a place across the nose, which stops the
scan) and a sole planned a little longer than its stone (Talos's 21 cm on 20 cm stones) may move only by its
overhang. The move is then ``s_c (s_a a e_a + s_b b e_b)``, ``s_c`` the same scan along that combined move (1 on a
tread or stone, whose edges lie along the axes). The result is within a grid spacing of the exact edge.

*Height and tilt.* The landing takes the terrain's change from ``F`` to the new place:

    z' = z_F + h(p') - h(p_F),      pitch' = pitch_F + pitch(p') - pitch(p_F),      roll' likewise,

where ``h, pitch, roll`` are the terrain's surface (or fitted plane) under the sole. The walk's frame follows the
measured feet (a landing re-anchors the footprints after it), so a foothold's height may differ from the terrain's
by the landings' errors; the terrain's change keeps that offset instead of undoing it. On a slope the landing moved
``d`` up the ramp rises ``d tan(angle)``; on a tread it keeps its height.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.heightfield import Heightfield
from rtgait.core.geometry.terrain import EDGE_TOLERANCE, Terrain, sole_points, surface
from rtgait.core.geometry.terrain_walk import sole_plane

__all__ = ["SCAN_STEP", "SOLE_GRID", "TerrainLanding", "land_on_terrain", "sole_support"]

SOLE_GRID = 0.005
"""Spacing of the points over the sole at which support is counted (m): the edge tolerance, so that a sole moved
across an edge loses a row of points within that distance."""
SCAN_STEP = 0.0025
"""Spacing of the places sampled along a move (m): half the sole grid's, so no row of points is stepped over."""
_BATCH = 16  # places evaluated at once: a clamp usually stops within the first few centimetres


class TerrainLanding(NamedTuple):
    """Where a moved landing goes on the terrain: the footprint (m, rad), how far it moves from the nominal one
    and how far it was asked to (m)."""

    footprint: Footstep
    moved: float
    asked: float

    @property
    def clamped(self) -> bool:
        """Whether the terrain shortened the move (by more than a micrometre)."""
        return self.asked - self.moved > 1e-6


def _grid(sole: SoleRect, side: str) -> np.ndarray:
    """The sole's grid points ``(P, 2)`` in the foot frame (m): along, then to the foot's left."""
    n_long = max(2, math.ceil((sole.front + sole.back) / SOLE_GRID) + 1)
    n_wide = max(2, math.ceil((sole.inner + sole.outer) / SOLE_GRID) + 1)
    return sole_points(Footstep(0.0, 0.0, 0.0, side), sole, n_long, n_wide)[:, :2]  # type: ignore[arg-type]


def _planes(terrain: Terrain, nominal: Footstep, sole: SoleRect, places: np.ndarray) -> np.ndarray:
    """``(z, pitch, roll)`` of the terrain's surface under a sole at each of ``places`` ``(S, 2)`` (m), heading as
    ``nominal``: ``(S, 3)``."""
    yaw, side = nominal.yaw, nominal.side
    if isinstance(terrain, Heightfield):
        fits = [sole_plane(terrain, Footstep(float(x), float(y), yaw, side), sole)[:3] for x, y in places]
        return np.array(fits, float)
    return np.array([surface(terrain, float(x), float(y), yaw) for x, y in places], float)


def sole_support(terrain: Terrain, nominal: Footstep, sole: SoleRect, places: np.ndarray) -> tuple[np.ndarray, ...]:
    """For a sole heading and sided as ``nominal`` at each of ``places`` ``(S, 2)`` (m): how many of its grid points
    the terrain supports ``(S,)`` (module docstring) and the surface ``(z, pitch, roll)`` under it ``(S, 3)``."""
    places = np.atleast_2d(np.asarray(places, float))
    local = _grid(sole, nominal.side)
    c, s = math.cos(nominal.yaw), math.sin(nominal.yaw)
    u, v = local[:, 0], local[:, 1]
    px = places[:, 0:1] + c * u - s * v  # (S, P)
    py = places[:, 1:2] + s * u + c * v
    planes = _planes(terrain, nominal, sole, places)
    z, pitch, roll = planes[:, 0:1], planes[:, 1:2], planes[:, 2:3]
    # The sole's plane (terrain.sole_points' convention): pitch lowers the toes, roll the right edge.
    sole_z = z - np.tan(pitch) * u + np.tan(roll) * v
    ground = np.asarray(terrain.height(px.ravel(), py.ravel()), float).reshape(px.shape)
    supported = np.count_nonzero(np.abs(sole_z - ground) <= EDGE_TOLERANCE, axis=1)
    return supported, planes


def _reach(
    terrain: Terrain, nominal: Footstep, sole: SoleRect, origin: np.ndarray, move: np.ndarray, need: int
) -> float:
    """The largest fraction ``s`` in [0, 1] of ``move`` (m) from ``origin`` (m) such that every place sampled from
    ``origin`` to ``origin + s move`` supports at least ``need`` points of the sole."""
    length = float(np.hypot(*move))
    if length < 1e-9:  # nothing to shrink: the move is taken as it is (a candidate's exact coordinates kept)
        return 1.0
    fractions = np.append(np.arange(1, math.ceil(length / SCAN_STEP)) * (SCAN_STEP / length), 1.0)
    reached = 0.0
    for start in range(0, len(fractions), _BATCH):
        batch = fractions[start : start + _BATCH]
        supported, _ = sole_support(terrain, nominal, sole, origin + batch[:, None] * move)
        short = np.flatnonzero(supported < need)
        if short.size:
            return float(batch[short[0] - 1]) if short[0] > 0 else reached
        reached = float(batch[-1])
    return reached


def land_on_terrain(terrain: Terrain, nominal: Footstep, x: float, y: float, sole: SoleRect) -> TerrainLanding:
    """``nominal`` (a landing on ``terrain``) moved toward ``(x, y)`` (m) as far as its sole keeps the support it
    has at ``nominal``, with the terrain's height and tilt there (module docstring)."""
    start = np.array([nominal.x, nominal.y])
    delta = np.array([x, y], float) - start
    asked = float(np.hypot(*delta))
    if asked < 1e-9:  # a move within round-off: taken as asked (as on the flat floor), its surface the nominal's
        return TerrainLanding(replace(nominal, x=float(x), y=float(y)), asked, asked)
    c, s = math.cos(nominal.yaw), math.sin(nominal.yaw)
    along, lateral = np.array([c, s]), np.array([-s, c])
    supported, planes = sole_support(terrain, nominal, sole, start[None])
    need = int(supported[0])
    a, b = float(delta @ along) * along, float(delta @ lateral) * lateral
    fraction_a, fraction_b = (
        _reach(terrain, nominal, sole, start, a, need),
        _reach(terrain, nominal, sole, start, b, need),
    )
    corner = delta if fraction_a == fraction_b == 1.0 else fraction_a * a + fraction_b * b  # exact when whole
    fraction = _reach(terrain, nominal, sole, start, corner, need)
    move = fraction * corner
    place = np.array([x, y], float) if fraction == 1.0 and corner is delta else start + move
    _, after = sole_support(terrain, nominal, sole, place[None])
    dz, dpitch, droll = (after[0] - planes[0]).tolist()
    # + 0.0: no -0.0 in outputs
    footprint = Footstep(
        float(place[0]), float(place[1]), nominal.yaw, nominal.side,
        nominal.z + dz + 0.0, nominal.pitch + dpitch + 0.0, nominal.roll + droll + 0.0,
    )  # fmt: skip
    return TerrainLanding(footprint, float(np.hypot(*move)), asked)
