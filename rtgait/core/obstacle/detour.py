"""The least change of a walk's remaining footsteps that keeps them off an obstacle: a lateral detour.

Work in the frame of the walk's heading at the stance foot of the first step still open, ``F[k0]``: ``s`` along it,
``l`` to its left (m). Footprints ``F[..k0]`` are committed; ``F[k0 + 1..N + 1]`` may move. A detour keeps every
``s`` (the step lengths and the timing: the robot reaches the obstacle when it planned to) and every yaw, and moves
the footprints sideways, passing the box on its left or on its right. Per side it is the projection

    min  sum_j (l_j - l_j^0)^2                                                  (m^2, the change)
    s.t. l_j >= top_j   (left)   or   l_j <= bottom_j   (right)   for the footprints j near the box,
         w_lo <= sigma_i (l_{i+1} - l_i) <= w_hi                   the stance width of step i,
         |l_{i+1} - l_{i-1}| <= D_i                                 the swing's sideways move of step i,

with ``top_j``, ``bottom_j`` the extent of footprint ``j``'s keep-out rectangle (:meth:`Obstacle.keep_out`, turned into
this frame), ``sigma_i = +1`` when step ``i`` lands a left foot. "Near the box": the footprint lies within the
rectangle's ``s`` range. When the box is too high to step over, each swing's straight path (from ``F[j - 2]`` to
``F[j]``) must pass it too: where the path enters and leaves the ``s`` range, at shares ``lam`` of the way, its
lateral position ``(1 - lam) l_{j-2} + lam l_j`` is again bounded by ``top`` (or ``bottom``), which is linear in the
two ends and exact for a straight path (the quintic blend of :mod:`rtgait.core.geometry.swing` moves ``s`` and ``l``
together). The stride bounds are the walk's :class:`~rtgait.core.walk.velocity_command.StepLimits` read per step as
:func:`~rtgait.core.walk.velocity_command.stride_from_command` makes strides: widths within
``[min_width, step_width + lateral]``, and the share of the limits' ellipsoid ``(length / L)^2 + (D / Dmax)^2 +
(turn / (Tmax / 2))^2 <= 1``, which with the lengths and turns fixed bounds the sideways move linearly:
``D_i = Dmax sqrt(1 - (len_i / L)^2 - (turn_i / (Tmax / 2))^2)``. A step the walk already had beyond the limits keeps
its own value as its bound.

Why this and not a general footstep search: with ``s`` fixed the problem is convex (a quadratic cost, linear
constraints, a dozen unknowns), so its optimum is the least change, found exactly as Lawson and Hanson's
least-distance programme (one non-negative least squares, ``scipy.optimize.nnls``: 0.1 ms for 15 footprints; the
whole side, constraints and checks included, about 4 ms) and checked afterwards. Freeing the lengths as well would
make the set of footprints near the box depend on the unknowns (which step lands before it: a combinatorial choice)
for little gain sideways; lengths alone are the step-over candidate of a low box
(:mod:`rtgait.core.obstacle.step_over`, which tries each split). Each side is one candidate;
:mod:`rtgait.core.obstacle.avoid` weighs the candidates' ZMP margins and hands the chosen one to the planner. The
remaining path should be straight (or nearly): the detour is planned along the current heading and every changed
step is checked in its own stride frame afterwards (:func:`check_detour`), so a turning walk gets a detour only when
it passes that check.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.optimize import nnls

from rtgait.core.geometry.footsteps import Footstep, SoleRect, stride_between
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.walk.velocity_command import StepLimits

PassSide = Literal["left", "right", "over", "none"]

MOVED = 1e-6
"""A footprint moved by more than this (m) counts as changed."""
TOLERANCE = 1e-6
"""Slack (m) of the checks after a solve, which meets its constraints to round-off."""


@dataclass(frozen=True)
class StrideRules:
    """What a step may do (module docstring): the walk's step limits, its straight-walking stance ``step_width``
    (m) and its swing height ``step_height`` (m); ``margin`` (m) kept between a sole and the box, and ``clearance``
    (m) over the box when stepping over it."""

    limits: StepLimits
    step_width: float
    step_height: float
    margin: float = 0.03
    clearance: float = 0.03

    def __post_init__(self) -> None:
        for name in ("step_width", "step_height", "margin", "clearance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be a finite distance >= 0 m, got {value}")

    @property
    def narrowest(self) -> float:
        """Narrowest stance of a step (m)."""
        low = self.limits.min_width
        return self.step_width if low is None else min(low, self.step_width)

    @property
    def widest(self) -> float:
        """Widest stance of a step (m)."""
        return self.step_width + self.limits.lateral


@dataclass(frozen=True)
class Detour:
    """One way round the obstacle.

    Attributes:
        side: ``"left"`` or ``"right"`` of the box, ``"over"`` it (:mod:`rtgait.core.obstacle.step_over`), or
            ``"none"``: the walk was already clear of it.
        footprints: ``F[base..N + 1]`` after the change (m, rad).
        first_open: the first step whose landing could move (1-based); ``F[first_open + 1]`` is its landing.
        cost: ``sum_j |F_j - F_j^0|^2`` over the footprints (m^2).
        moved: footprints moved by more than :data:`MOVED`.
        largest_move: largest move of one footprint (m).
    """

    side: PassSide
    footprints: tuple[Footstep, ...]
    first_open: int
    cost: float
    moved: int
    largest_move: float


class NoDetourError(ValueError):
    """No detour on that side keeps the footsteps off the obstacle within the step limits (the message says why)."""


def frame(origin: Footstep) -> tuple[np.ndarray, np.ndarray]:
    """The origin (m) and rotation of the frame of ``origin`` (``s`` along its heading, ``l`` to its left)."""
    c, s = math.cos(origin.yaw), math.sin(origin.yaw)
    return np.array([origin.x, origin.y]), np.array([[c, -s], [s, c]])


def to_frame(points: np.ndarray, origin: Footstep) -> np.ndarray:
    """World points ``(..., 2)`` (m) as ``(s, l)`` in the frame of ``origin``."""
    o, R = frame(origin)
    return (np.asarray(points, dtype=float) - o) @ R


def blocked(
    footprints: Sequence[Footstep], first: int, obstacle: Obstacle, sole: SoleRect, rules: StrideRules
) -> list[int]:
    """Indices (into ``footprints``) from ``first`` on whose sole, or whose swing to it when the box cannot be stepped
    over, meets the obstacle's keep-out rectangle."""
    over = obstacle.can_step_over(rules.step_height, rules.clearance)
    hits = []
    for j in range(first, len(footprints)):
        foot = footprints[j]
        touching = obstacle.clearance(foot, sole, rules.margin - TOLERANCE) < 0.0
        if not touching and not over and j >= 2:
            touching = obstacle.segment_hits(footprints[j - 2], foot, sole, rules.margin - TOLERANCE)
        if touching:
            hits.append(j)
    return hits


def plan_detour(
    footprints: Sequence[Footstep],
    first_open: int,
    obstacle: Obstacle,
    sole: SoleRect,
    rules: StrideRules,
    side: Literal["left", "right"],
    base: int = 0,
) -> Detour:
    """The least change (module docstring) of ``footprints`` ``F[base..N + 1]`` passing ``obstacle`` on ``side``,
    the steps before ``first_open`` (1-based) committed. Raises :class:`NoDetourError` when there is none."""
    prints = list(footprints)
    k0 = first_open - base  # index of the stance foot of the first open step
    if not 1 <= k0 < len(prints) - 1:
        raise NoDetourError(f"no step is left to change (first open step {first_open}, {len(prints) - 2 + base} steps)")
    origin = prints[k0]
    sl = to_frame(np.array([[f.x, f.y] for f in prints]), origin)
    s, l0 = sl[:, 0], sl[:, 1]
    over = obstacle.can_step_over(rules.step_height, rules.clearance)
    bounds = LinearBounds(l0, k0, "a committed footstep already breaks a bound by {low:.3g} m")  # the unknowns l_j
    add, free = bounds.add, bounds.free

    # The obstacle: every footprint within its s range on the chosen side of its keep-out rectangle, and, when it
    # cannot be stepped over, every swing's straight path where it crosses that range (linear in its two ends).
    extents = []
    for j in range(len(prints)):
        box = to_frame(obstacle.keep_out_corners(prints[j], sole, rules.margin), origin)
        extents.append((box[:, 0].min(), box[:, 0].max(), box[:, 1].min(), box[:, 1].max()))
    sign = 1.0 if side == "left" else -1.0

    def keep_side(weights: dict[int, float], j: int) -> None:
        edge = extents[j][3] if side == "left" else -extents[j][2]
        add({i: sign * a for i, a in weights.items()}, edge)

    near = []
    for j in range(len(prints)):
        lo_s, hi_s = extents[j][:2]
        if lo_s < s[j] < hi_s:
            near.append(j)
            keep_side({j: 1.0}, j)
        a = j - 2  # the swing landing on F[j] lifts off from F[a]
        if over or a < 0 or (a <= k0 and j <= k0):
            continue
        lo_s, hi_s = min(extents[a][0], extents[j][0]), max(extents[a][1], extents[j][1])
        sa, sj = s[a], s[j]
        if abs(sj - sa) < 1e-12 or max(sa, sj) <= lo_s or min(sa, sj) >= hi_s:
            continue
        near.append(j)
        for edge in (lo_s, hi_s):
            lam = min(max((edge - sa) / (sj - sa), 0.0), 1.0)
            for k in (a, j):
                keep_side({a: 1.0 - lam, j: lam}, k)
    # The stride bounds of every open step i (landing F[i + 1], stance F[i], lift-off from F[i - 1]).
    limits = rules.limits
    for i in range(k0, len(prints) - 1):
        sigma = 1.0 if prints[i + 1].side == "left" else -1.0
        nominal_width = sigma * (l0[i + 1] - l0[i])
        add({i + 1: sigma, i: -sigma}, min(rules.narrowest, nominal_width))
        add({i + 1: -sigma, i: sigma}, -max(rules.widest, nominal_width))
        length = s[i + 1] - s[i]
        turn = math.remainder(prints[i + 1].yaw - prints[i].yaw, math.tau)
        share = 1.0 - (length / limits.length) ** 2 - (turn / (0.5 * limits.turn)) ** 2
        cap = max(limits.lateral * math.sqrt(max(share, 0.0)), abs(l0[i + 1] - l0[i - 1]))
        add({i + 1: 1.0, i - 1: -1.0}, -cap)
        add({i + 1: -1.0, i - 1: 1.0}, -cap)
    if not near:
        raise NoDetourError("no footstep comes near the obstacle")
    x, violation = bounds.least_change()
    if violation > TOLERANCE:
        raise NoDetourError(
            f"passing {side} needs more sideways reach than the step limits allow (short by {violation:.3g} m)"
        )
    o, R = frame(origin)
    moved_prints = list(prints)
    for j, lj in zip(free, x, strict=True):
        world = o + R @ np.array([s[j], lj])
        moved_prints[j] = Footstep(float(world[0]), float(world[1]), prints[j].yaw, prints[j].side)
    detour = make_detour(side, prints, moved_prints, first_open)
    check_detour(prints, detour, obstacle, sole, rules, base)
    return detour


class LinearBounds:
    """Bounds ``A x >= b`` on one coordinate of the open footprints ``x = (c_j)``, ``j = k0 + 1 ..``, built a row
    at a time over footprint indices; a committed footprint's share moves to the right-hand side at its value in
    ``start`` (m), and a row left with no open footprint must already hold.

    Args:
        start: the coordinate of every footprint now (m).
        k0: index of the last committed footprint.
        committed: what a broken row of committed footprints means, for the :class:`NoDetourError`'s message.
    """

    def __init__(self, start: np.ndarray, k0: int, committed: str) -> None:
        self.start, self.committed = start, committed
        self.free = list(range(k0 + 1, len(start)))
        self._column = {j: c for c, j in enumerate(self.free)}
        self._rows: list[np.ndarray] = []
        self._bounds: list[float] = []

    def add(self, coefficients: dict[int, float], low: float) -> None:
        """The row ``sum_j coefficients[j] c_j >= low`` (m)."""
        row = np.zeros(len(self.free))
        for j, a in coefficients.items():
            if j in self._column:
                row[self._column[j]] += a
            else:
                low -= a * self.start[j]
        if not row.any():
            if low > TOLERANCE:
                raise NoDetourError(self.committed.format(low=low))
            return
        self._rows.append(row)
        self._bounds.append(low)

    def least_change(self) -> tuple[np.ndarray, float]:
        """The open footprints' coordinates nearest their start that meet the rows (:func:`least_distance`), and by
        how much (m) the least met row still falls short (0 when all are met)."""
        A, b = np.array(self._rows), np.array(self._bounds)
        start = self.start[self.free[0] :]
        x = start + least_distance(A, b - A @ start)
        return x, float(np.max(b - A @ x, initial=0.0))


def least_distance(G: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The shortest ``z`` with ``G z >= h`` (Lawson and Hanson's least-distance programme, solved exactly by one
    non-negative least squares: with ``u >= 0`` minimising ``|E u - f|``, ``E = [G^T; h^T]``, ``f = (0, .., 0, 1)``,
    the residual ``r = E u - f`` gives ``z = -r[:n] / r[n]``; a zero residual means no ``z`` exists). Returns the
    zero vector's best effort (the checks then refuse it) when the constraints are incompatible."""
    n = G.shape[1]
    if np.all(h <= 0.0):
        return np.zeros(n)  # already feasible: no change is the least
    E = np.vstack([G.T, h[None, :]])
    f = np.zeros(n + 1)
    f[-1] = 1.0
    u, _ = nnls(E, f, maxiter=50 * E.shape[1])
    r = E @ u - f
    if abs(r[-1]) < 1e-12:
        return np.zeros(n)
    return -r[:n] / r[-1]


def make_detour(side: PassSide, before: Sequence[Footstep], after: Sequence[Footstep], first_open: int) -> Detour:
    """The :class:`Detour` from ``before`` to ``after`` (its cost and moves)."""
    moves = np.array([math.hypot(a.x - b.x, a.y - b.y) for a, b in zip(before, after, strict=True)])
    return Detour(side, tuple(after), first_open, float(np.sum(moves**2)), int(np.count_nonzero(moves > MOVED)),
                  float(moves.max(initial=0.0)))  # fmt: skip


def check_detour(
    before: Sequence[Footstep], detour: Detour, obstacle: Obstacle, sole: SoleRect, rules: StrideRules, base: int = 0
) -> None:
    """Raise :class:`NoDetourError` unless every footprint of ``detour`` from its first open step's landing on is off
    the obstacle (and, when it cannot be stepped over, so is every swing to it), and every changed step is within
    the stride bounds in its own stride frame (module docstring). ``before``: the footprints it changed."""
    prints = detour.footprints
    k0 = detour.first_open - base
    hits = blocked(prints, k0 + 1, obstacle, sole, rules)
    if hits:
        raise NoDetourError(f"footprint F[{hits[0] + base}] (or the swing to it) still meets the obstacle")
    limits = rules.limits
    for i in range(k0, len(prints) - 1):
        if all(prints[j] == before[j] for j in (i - 1, i, i + 1)):
            continue  # a step the walk already had
        stride = stride_between(prints[i], prints[i + 1])  # raises when the feet cross
        if not rules.narrowest - TOLERANCE <= stride.width <= rules.widest + TOLERANCE:
            raise NoDetourError(f"step {i + base} would stand {stride.width:.3f} m wide, outside the step limits")
        c, s = math.cos(prints[i].yaw), math.sin(prints[i].yaw)
        dx, dy = prints[i + 1].x - prints[i - 1].x, prints[i + 1].y - prints[i - 1].y
        sideways = -s * dx + c * dy
        share = math.hypot(stride.length / limits.length, sideways / limits.lateral, stride.turn / (0.5 * limits.turn))
        old = stride_between(before[i], before[i + 1])
        odx, ody = before[i + 1].x - before[i - 1].x, before[i + 1].y - before[i - 1].y
        old_share = math.hypot(old.length / limits.length, (-s * odx + c * ody) / limits.lateral,
                               old.turn / (0.5 * limits.turn))  # fmt: skip
        if share > max(1.0, old_share) + TOLERANCE:
            raise NoDetourError(f"step {i + base} would use {share:.3f} of the step limits' ellipsoid (at most 1)")


def no_detour(footprints: Sequence[Footstep], first_open: int) -> Detour:
    """The walk unchanged: already clear of the obstacle."""
    return make_detour("none", footprints, footprints, first_open)


__all__ = [
    "MOVED", "TOLERANCE", "Detour", "LinearBounds", "NoDetourError", "PassSide", "StrideRules", "blocked",
    "check_detour", "frame", "least_distance", "make_detour", "no_detour", "plan_detour", "to_frame",
]  # fmt: skip
