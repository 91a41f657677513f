"""Step adjustment's choice of landing, decided in one vectorised batch through the plan's operator.

When the plan made from the measured state asks for a ZMP outside the support polygon (its free first segment is
the only part of a plan that may leave the footprints), the ankle alone cannot recover: the robot must step
elsewhere. The landing point of the next step that can still change is chosen among a grid of candidates:

* within limits a robot description can set: a stride box in the stance foot's frame (forward/backward reach,
  least and largest distance between the feet, so the feet never cross), the largest average swing speed over the
  time left, and no change in the last ``min_time_to_touchdown`` seconds before touch-down (the foot is landing);
* with the ZMP margin at least ``required_margin``, and among those the least departure from the commanded walk;
  if no candidate reaches it, the one with the largest margin (a capture step), after which the walk goes on or
  stops (``on_failure``), with the reason logged.

Why it is cheap: moving the landing ``F[k+1]`` by ``delta`` moves every later footprint by ``delta`` too (strides
are relative), so every anchor of the plan moves by ``w_a delta`` with ``w_a`` in {0, 1/2, 1}, and the ZMP of the
free segment at time ``t_i`` moves by ``g_i delta`` with ``g_i = sum_a M[i, a] w_a``. For ``C`` candidates and
``T`` sample times the margins are one ``(C, T, 2)`` array against the polygon's half-planes: a thousand
candidates in a few hundred microseconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import lru_cache
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, mean_heading

if TYPE_CHECKING:
    from rtgait.core.laws.step_timing import TimingOptions
    from rtgait.core.laws.stepping import StepAdjustment
    from rtgait.core.walk.walk import Walk

__all__ = ["LandingProposal", "candidate_landings", "choose_step", "propose_landing"]


def candidate_landings(adjust: StepAdjustment, stance: Footstep, nominal: Footstep) -> np.ndarray:
    """Grid of landing points ``(grid**2, 2)`` (m) in the stride box around ``stance``, oriented along the mean
    heading of the stance and the nominal landing (as :func:`~rtgait.core.geometry.footsteps.place_step` measures a
    stride)."""
    limits = adjust.limits
    local = _stride_box_grid(limits.max_length, limits.min_width, limits.max_width, adjust.grid, nominal.side)
    heading = mean_heading(stance.yaw, nominal.yaw)
    c, s = math.cos(heading), math.sin(heading)
    return local @ np.array([[c, s], [-s, c]]) + np.array([stance.x, stance.y])


@lru_cache(maxsize=64)
def _stride_box_grid(max_length: float, min_width: float, max_width: float, grid: int, side: str) -> np.ndarray:
    """The candidate grid in the stance foot's frame, ``(grid**2, 2)`` (m, read-only): along, then lateral
    (toward the landing's side)."""
    along = np.linspace(-max_length, max_length, grid)
    lateral = np.linspace(min_width, max_width, grid)
    if side == "right":
        lateral = -lateral
    a, b = np.meshgrid(along, lateral, indexing="ij")
    local = np.stack([a.ravel(), b.ravel()], axis=1)
    local.setflags(write=False)
    return local


def choose_step(
    adjust: StepAdjustment,
    candidates: np.ndarray,
    nominal: tuple[float, float],
    zmp: np.ndarray,
    gain: np.ndarray,
    halfplanes: tuple[np.ndarray, np.ndarray],
    swing_from: tuple[float, float],
    time_left: np.ndarray,
    time_change: np.ndarray,
) -> tuple[int, np.ndarray, float, bool] | None:
    """The timing and landing to take among ``D`` timings and ``candidates`` ``(C, 2)``: the timing's index, the
    landing, its margin (m) and whether that reaches ``required_margin``.

    Args:
        zmp: the free segment's ZMP with the nominal landing under each timing, ``(D, T, 2)`` (m).
        gain: how much that ZMP moves per metre the landing moves, under each timing, ``(D, T)``.
        time_left: until the touch-down under each timing (s), ``(D,)``: a landing is reachable if the swing foot
            covers the distance from ``swing_from`` (m) at ``max_swing_speed`` in that time.
        time_change: each timing's change of the single support (s, negative: sooner), ``(D,)``; 0 for the
            nominal one, which comes first (of equal departures the first candidate wins, so the nominal timing does).

    The margin of candidate ``(d, c)`` is ``min_t min_k b_k - n_k . (zmp[d, t] + gain[d, t] delta_c)``; among the
    candidates reaching ``required_margin`` the least departure ``|delta_c|^2 + (time_cost time_change_d)^2``
    wins; when none does, the largest margin among the timings no longer than the nominal one, and of candidates
    within a millimetre of it the least departure.
    Returns ``None`` when no candidate can be reached in time.
    """
    distance = np.hypot(candidates[:, 0] - swing_from[0], candidates[:, 1] - swing_from[1])
    reachable = distance[None, :] <= adjust.limits.max_swing_speed * np.asarray(time_left)[:, None]  # (D, C)
    if not reachable.any():
        return None
    delta = candidates - np.asarray(nominal)
    # margin(d, c, t, k) = b_k - n_k . (zmp_dt + g_dt delta_c) = A[d, t, k] - g_dt D[c, k]: two small products and
    # one broadcast per edge, instead of moving every (timing, candidate, time) point through the polygon.
    normals, offsets = halfplanes
    # Laid out (K, T, D, C) so that the minimum over the sample times is a reduction over the leading axis (fast
    # elementwise minima of contiguous rows, not a short reduction per candidate), one edge at a time (an edge's
    # (T, D, C) block stays in cache).
    base = np.ascontiguousarray((offsets - zmp @ normals.T).transpose(2, 1, 0))[..., None]  # (K, T, D, 1)
    along = np.ascontiguousarray((delta @ normals.T).T)  # (K, C)
    spread = np.ascontiguousarray(np.asarray(gain).T)[:, :, None]  # (T, D, 1)
    margin = np.full(reachable.shape, np.inf)
    block = np.empty((spread.shape[0], *reachable.shape))
    for k in range(base.shape[0]):
        np.multiply(spread, along[k], out=block)
        np.subtract(base[k], block, out=block)
        np.minimum(margin, np.minimum.reduce(block, axis=0), out=margin)
    margin[~reachable] = -np.inf
    timing_departure = (adjust.time_cost * np.asarray(time_change))[:, None] ** 2
    departure = np.einsum("cd,cd->c", delta, delta)[None, :] + timing_departure
    enough = margin >= adjust.required_margin
    if enough.any():
        best = int(np.argmin(np.where(enough, departure, np.inf)))
    else:
        # Nothing is enough: the largest margin, and of candidates within a millimetre of it the nearest one (the
        # margin is often flat along one axis of the box). Not a longer single support: held longer with its ZMP
        # still outside the sole, a stance only lets the fall grow (the sole tips about its edge); the step is the
        # answer then, and it comes no later than planned.
        later = np.asarray(time_change) > 0.0
        if later.any() and not later.all():
            margin[later] = -np.inf
        near_best = margin >= margin.max() - 1e-3
        best = int(np.argmin(np.where(near_best, departure, np.inf)))
    d, c = divmod(best, margin.shape[1])
    return d, candidates[c], float(margin[d, c]), bool(enough[d, c])


class LandingProposal(NamedTuple):
    """Where step adjustment would land ``step``: the landing ``(x, y)`` (m), the margin it predicts (m), whether
    that reaches the required margin, how many candidates were weighed, whether the step is swinging now, its
    single-support duration (s) and nominal one, and which of the planner's :class:`TimingOptions` it takes
    (``-1``: the nominal timing)."""

    step: int
    nominal: Footstep
    landing: tuple[float, float]
    margin: float
    enough: bool
    candidates: int
    swinging: bool
    single_support: float = math.nan
    nominal_single_support: float = math.nan
    timing: int = -1


def propose_landing(
    adjust: StepAdjustment,
    walk: Walk,
    q: int,
    t: float,
    phase_start: Callable[[int], float],
    rows: np.ndarray,
    zmp: np.ndarray,
    halfplanes: tuple[np.ndarray, np.ndarray],
    anchor_phases: Sequence[int],
    swing_position: Callable[[], tuple[float, float]],
    timings: Callable[[int, bool], TimingOptions | None] | None = None,
) -> LandingProposal | None:
    """The landing (and, with ``timings``, the single-support duration) of the next step that can still change,
    for a plan starting at phase ``q`` whose free segment's ZMP at the sample times is ``zmp = rows @ y`` (m);
    ``None`` if no step can move (the last one has landed, or no candidate can be reached in time).

    The step is the one swinging in a single support, unless it lands within ``min_time_to_touchdown`` of ``t``
    (s), else the next one to lift off. ``phase_start(p)`` is the absolute start of phase ``p`` (s);
    ``swing_position()`` where the swinging foot is now (m); ``timings(step, swinging)`` the other durations the
    planner offers for that step (:class:`TimingOptions`), or ``None``.
    """
    kind = walk.timeline.kind(q)
    k = (q + 1) // 2 if kind == "single" else q // 2 + 1
    touchdown = phase_start(2 * k)
    if kind == "single" and touchdown - t < adjust.limits.min_time_to_touchdown:
        k += 1
        touchdown = phase_start(2 * k)
    n = walk.n_steps
    if n is not None and k > n:
        return None
    swinging = kind == "single" and k == (q + 1) // 2
    if swinging:
        swing_from = swing_position()
    else:
        origin = walk.footprint(k - 1)
        swing_from = (origin.x, origin.y)
    nominal = walk.footprint(k + 1)
    # Every anchor resting on F[k + 1] or later moves with the landing; one between the final feet, half as much.
    weights = np.array([(a >= k + 1) + (b >= k + 1) for a, b in walk.anchor_sources(q, anchor_phases)]) * 0.5
    candidates = candidate_landings(adjust, walk.footprint(k), nominal)
    single = walk.timeline.duration(2 * k - 1)
    options = timings(k, swinging) if timings is not None else None
    if options is None:
        zmps, gains, singles = zmp[None], (rows[:, 4:] @ weights)[None], np.array([single])
    else:
        zmps = np.concatenate((zmp[None], options.zmp))
        gains = np.concatenate(((rows[:, 4:] @ weights)[None], options.rows[:, :, 4:] @ weights))
        singles = np.concatenate(([single], options.single_support))
    change = singles - single  # a shorter single support lands that much sooner
    choice = choose_step(
        adjust, candidates, (nominal.x, nominal.y), zmps, gains, halfplanes, swing_from, touchdown - t + change, change
    )
    if choice is None:
        return None
    d, landing, margin, enough = choice
    return LandingProposal(
        k, nominal, (float(landing[0]), float(landing[1])), margin, enough, len(candidates) * len(singles), swinging,
        float(singles[d]), single, d - 1,
    )  # fmt: skip
