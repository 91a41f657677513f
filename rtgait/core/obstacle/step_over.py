"""Stepping over a low obstacle: the least change of the remaining step lengths that lands no sole on it.

A box lower than the swing height less a clearance (:meth:`Obstacle.can_step_over`) may be stepped over: the swings
pass above it and only the soles must keep off it. In the frame of :mod:`rtgait.core.obstacle.detour` (``s`` along the
heading at the first open step's stance foot, ``l`` across it) this keeps every ``l`` and yaw and moves the
footprints along the walk. The footprints whose ``l`` lies across the box's keep-out rectangle
(:meth:`Obstacle.keep_out`) must land before it or after it; footprints follow each other along ``s``, so a split
index ``m`` says which (``F[..m]`` before, ``F[m + 1..]`` after), and per split the change is again a projection:

    min  sum_j (s_j - s_j^0)^2
    s.t. s_j <= front_j   (j <= m)   or   s_j >= back_j   (j > m)     for the footprints across the box,
         min(0, len_i^0) <= s_{i+1} - s_i <= C_i                        the length of step i,
         s_{N+1} - s_N = len_{N+1}^0                                     the closing step keeps its length,

``C_i = L sqrt(1 - (D_i / Dmax)^2 - (turn_i / (Tmax / 2))^2)`` the length the step limits' ellipsoid leaves at the
step's own sideways move ``D_i`` and turn (or its nominal length, if longer). The least-distance solve and the checks
are :mod:`rtgait.core.obstacle.detour`'s; the splits worth trying are those around the footprints that land on the box
now, and the least change over them is the candidate ``"over"``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.obstacle.detour import (
    TOLERANCE,
    Detour,
    LinearBounds,
    NoDetourError,
    StrideRules,
    blocked,
    check_detour,
    frame,
    make_detour,
    to_frame,
)


def plan_step_over(
    footprints: Sequence[Footstep],
    first_open: int,
    obstacle: Obstacle,
    sole: SoleRect,
    rules: StrideRules,
    base: int = 0,
) -> Detour:
    """The least change (module docstring) of ``footprints`` ``F[base..N + 1]`` that steps over ``obstacle``, the
    steps before ``first_open`` (1-based) committed. Raises :class:`NoDetourError` when there is none."""
    if not obstacle.can_step_over(rules.step_height, rules.clearance):
        raise NoDetourError(
            f"the box ({obstacle.height:g} m) is too high to step over with {rules.step_height:g} m swings and "
            f"{rules.clearance:g} m clearance"
        )
    prints = list(footprints)
    k0 = first_open - base
    if not 1 <= k0 < len(prints) - 1:
        raise NoDetourError(f"no step is left to change (first open step {first_open})")
    hits = blocked(prints, k0 + 1, obstacle, sole, rules)
    if not hits:
        raise NoDetourError("no footstep lands on the obstacle")
    origin = prints[k0]
    sl = to_frame(np.array([[f.x, f.y] for f in prints]), origin)
    s0, l0 = sl[:, 0], sl[:, 1]
    across: dict[int, tuple[float, float]] = {}  # footprint -> (s it must not pass before the box, s after it)
    for j in range(len(prints)):
        box = to_frame(obstacle.keep_out_corners(prints[j], sole, rules.margin), origin)
        if box[:, 1].min() < l0[j] < box[:, 1].max():
            across[j] = (box[:, 0].min(), box[:, 0].max())
    best: Detour | None = None
    reasons = []
    for split in range(max(min(hits) - 2, k0), max(hits) + 1):
        try:
            detour = _split(prints, s0, l0, k0, split, across, origin, first_open, rules)
            check_detour(prints, detour, obstacle, sole, rules, base)
        except NoDetourError as error:
            reasons.append(str(error))
            continue
        if best is None or detour.cost < best.cost:
            best = detour
    if best is None:
        raise NoDetourError(f"stepping over it needs more than the step limits allow ({reasons[-1]})")
    return best


def _split(
    prints: list[Footstep],
    s0: np.ndarray,
    l0: np.ndarray,
    k0: int,
    split: int,
    across: dict[int, tuple[float, float]],
    origin: Footstep,
    first_open: int,
    rules: StrideRules,
) -> Detour:
    """The least change landing ``F[..split]`` before the box and ``F[split + 1..]`` after it."""
    bounds = LinearBounds(s0, k0, f"a committed footstep stands on the box (split after F[{split}])")
    add, free = bounds.add, bounds.free

    for j, (front, back) in across.items():
        if j <= split:
            add({j: -1.0}, -front)
        else:
            add({j: 1.0}, back)
    limits = rules.limits
    last = len(prints) - 1
    for i in range(k0, last):
        nominal = s0[i + 1] - s0[i]
        if i + 1 == last:  # the closing step keeps its length: the walk ends with the feet side by side
            add({i + 1: 1.0, i: -1.0}, nominal)
            add({i + 1: -1.0, i: 1.0}, -nominal)
            continue
        sideways = l0[i + 1] - l0[i - 1]
        turn = math.remainder(prints[i + 1].yaw - prints[i].yaw, math.tau)
        share = 1.0 - (sideways / limits.lateral) ** 2 - (turn / (0.5 * limits.turn)) ** 2
        cap = max(limits.length * math.sqrt(max(share, 0.0)), nominal)
        add({i + 1: 1.0, i: -1.0}, min(0.0, nominal))
        add({i + 1: -1.0, i: 1.0}, -cap)
    x, violation = bounds.least_change()
    if violation > TOLERANCE:
        raise NoDetourError(f"landing F[..{split}] before it is short by {violation:.3g} m")
    o, R = frame(origin)
    moved = list(prints)
    for j, sj in zip(free, x, strict=True):
        world = o + R @ np.array([sj, l0[j]])
        moved[j] = Footstep(float(world[0]), float(world[1]), prints[j].yaw, prints[j].side)
    return make_detour("over", prints, moved, first_open)


__all__ = ["plan_step_over"]
