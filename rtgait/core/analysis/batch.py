"""Many plans at once: stacked inputs through one precomputed operator, and whole walks evaluated in batches.

Everything in a plan is linear in its inputs ``y = [p0, dp0, c0, dc0, anchors...]`` (per axis), so a family of
plans that share a timing (candidate landing points, perturbed states, a sweep over step changes) is one operator
applied to a stack of inputs. The first three functions here stay numpy-only and allocation-light so that a decision
over a thousand candidates takes well under a millisecond.

Margins use the half-planes of the convex support polygon: ``min_k (b_k - n_k . p)`` over its edges, the signed
distance to the boundary when ``p`` is inside (exact) and a lower bound of it, negative, when outside. That is
all a feasibility test or a ranking needs, at a fraction of the cost of the exact outside distance
(:func:`rtgait.core.geometry.support.signed_margin`).

Whole walks (:func:`evaluate_walks`, :func:`evaluate_parameters`): straight walks whose step lengths and widths
change while walking, rolled out exactly as :func:`rtgait.core.analysis.rollout.rollout` does (``rtgait plan``: sampled
every ``dt``, each change handed over at its deadline), give per case the smallest signed ZMP margin
``min_t signed_margin(zmp(t), polygon(t))`` (m), the time of its first occurrence (s) and the largest
``|zmp - zmp_ref|`` per axis in the connecting segments (m), the same numbers as ``summary.json`` to round-off
(:mod:`rtgait.core.analysis.walk_family` explains how: per timing the walk is affine in its stride lengths and widths,
and per phase the ZMP has a two-vector shape whose extreme over the phase's ticks is a binary search). Cases are grouped
by everything but those numbers (one :class:`~rtgait.core.analysis.walk_family.WalkFamily` per group, cached), each
group evaluated in one vectorised pass. The ``"auto"`` connection is evaluated by the rule of
:mod:`rtgait.core.planner.auto`, its predictions made the same way.

Off the flat floor a walk's footholds carry heights ``z = (z_0 .. z_n+1)`` (m) and its stances support heights ``h``
(``z`` but before a step down, :mod:`rtgait.core.geometry.support_height`): the horizontal numbers do not change (the
3D-DCM/VRP form keeps the horizontal equation, ``docs/method.md``) and the planned COG height is linear in ``z`` and
``h`` (:mod:`rtgait.core.analysis.family_height`), so a walk given them (:attr:`StraightWalk.heights` and
:attr:`StraightWalk.support`, or ``heights`` and ``support`` rows next to ``theta``) also gets the range of its COG
height, ``cog_z_min`` and ``cog_z_max`` (m), the numbers
``rtgait plan`` reports as ``cog_height_range``; given the terrain too, the error the vertical motion adds to the
horizontal ZMP, ``zmp_error_max`` and ``zmp_error_rms`` (m, the full point-mass ZMP against the planned one on the
terrain's plane under the nearest contact foot, :mod:`rtgait.core.analysis.height_error`), as ``rtgait plan``
reports them.

When the smallest margin is reached at several ticks (a walk whose ZMP stays inside has its minimum, the ankle's
distance to its sole's edge, in every single support), the time reported follows ``rtgait plan``'s rule: the first
tick within :data:`~rtgait.core.analysis.walk_family.TIE` of the minimum at or after the first change is handed over,
else the first such tick.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from rtgait.core.analysis.family_key import ChangeShape, FamilyKey, family_key
from rtgait.core.analysis.walk_family import WalkFamily
from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.terrain import Terrain, surface
from rtgait.core.planner.auto import auto_options

if TYPE_CHECKING:
    from rtgait.core.analysis.rollout import ScheduledChange
    from rtgait.core.planner.config import PlannerConfig


_HEIGHT_CHUNK = 256  # walks whose COG heights (one row of ticks each) are evaluated together
_ERROR_CHUNK = 32  # walks whose ZMP errors (a few rows of ticks each) are evaluated together

# ----- whole walks ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StraightWalk:
    """One walk as ``rtgait plan`` rolls it out: ``steps`` forward steps of ``step_length`` (m) at the config's
    step width, one closing step, no turning, and ``changes`` of lengths and widths handed over at their deadline.

    ``config.connection`` may be ``"real-time"``, ``"quasi-real-time"`` or ``"auto"``; ``dt`` is the sampling
    period (s) and ``sole`` the sole rectangle of the support polygons (m). ``heights``: the footholds' heights
    ``F[0..steps+2]`` (m, the closing step's too) on a terrain, ``None`` on the flat floor; ``support``: the support
    height each of them holds as a stance (m, :func:`~rtgait.core.geometry.support_height.support_heights`),
    ``None``: its own height.
    """

    config: PlannerConfig
    sole: SoleRect
    dt: float
    steps: int
    step_length: float
    changes: tuple[ScheduledChange, ...] = ()
    heights: tuple[float, ...] | None = None
    support: tuple[float, ...] | None = None

    def shapes(self) -> tuple[ChangeShape, ...]:
        """The changes as :class:`~rtgait.core.analysis.family_key.ChangeShape` s, each handed over at its mode's
        deadline (auto: the quasi-real-time one, where its decision is made)."""
        mode = self.config.connection
        out = []
        for change in self.changes:
            if change.turn not in (None, 0.0):
                raise ValueError(f"change of step {change.step}: batched evaluation needs straight walks (no turn)")
            if change.length is None and change.width is None:
                raise ValueError(f"change of step {change.step} changes nothing")
            phase = 2 * change.step - 1 if mode == "real-time" else 2 * change.step - 2
            through = change.step if change.through is None else change.through
            out.append(ChangeShape(change.step, through, change.length is not None, change.width is not None, phase))
        return tuple(out)

    def parameters(self) -> np.ndarray:
        """``theta = [1, step_length, step_width, change values...]`` (m), the family's parameters."""
        values = [1.0, self.step_length, self.config.step_width]
        for change in self.changes:
            values += [v for v in (change.length, change.width) if v is not None]
        return np.array(values)


@dataclass(frozen=True)
class BatchResult:
    """Per case (arrays of length ``B``): ``zmp_margin_min`` (m, signed, > 0 inside), ``zmp_margin_min_time`` (s),
    ``zmp_deviation_max`` ``(B, 2)`` (m, x and y), and for auto walks the connection each change took
    (``decisions``: one string per case, the changes' kinds joined by ``,``; empty for other modes); for walks given
    their footholds' heights, the range of the planned COG height ``cog_z_min``, ``cog_z_max`` (m; ``None``
    otherwise), and given the terrain too, the vertical motion's ZMP error ``zmp_error_max``, ``zmp_error_rms`` (m)."""

    zmp_margin_min: np.ndarray
    zmp_margin_min_time: np.ndarray
    zmp_deviation_max: np.ndarray
    decisions: np.ndarray
    cog_z_min: np.ndarray | None = None
    cog_z_max: np.ndarray | None = None
    zmp_error_max: np.ndarray | None = None
    zmp_error_rms: np.ndarray | None = None

    @property
    def zmp_outside(self) -> np.ndarray:
        """Whether the ZMP leaves the support polygon anywhere, per case."""
        return self.zmp_margin_min < 0.0

    def __len__(self) -> int:
        return len(self.zmp_margin_min)


@lru_cache(maxsize=256)
def walk_family(key: FamilyKey) -> WalkFamily:
    """The (cached) family of ``key``: building one costs a few milliseconds, evaluating a case microseconds."""
    return WalkFamily(key)


def evaluate_parameters(
    walk: StraightWalk,
    theta: np.ndarray,
    heights: np.ndarray | None = None,
    terrain: Terrain | None = None,
    support: np.ndarray | None = None,
) -> BatchResult:
    """Evaluate the walks that are ``walk`` with the parameters ``theta`` ``(B, P)`` (:meth:`StraightWalk.parameters`
    layout: ``[1, step_length, step_width, change values...]``, m): one family, the fastest path. ``heights``
    ``(B, steps + 3)`` (m): each walk's footholds' heights (default: ``walk.heights`` for every row, if any);
    ``terrain``: the ground they walk on, for the vertical motion's ZMP error (needs heights); ``support``
    ``(B, steps + 3)`` (m): the support height each foothold holds as a stance (default: ``walk.support`` given
    ``walk.heights``, else ``heights``)."""
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    if not np.all(np.isfinite(theta)):
        raise ValueError("theta must be finite")
    if heights is None and walk.heights is not None:
        heights = np.repeat(np.asarray(walk.heights, dtype=float)[None], len(theta), axis=0)
        if support is None and walk.support is not None:
            support = np.repeat(np.asarray(walk.support, dtype=float)[None], len(theta), axis=0)
    if (terrain is not None or support is not None) and heights is None:
        raise ValueError("the vertical motion (ZMP error, support heights) needs the footholds' heights")
    shapes = walk.shapes()
    if walk.config.connection != "auto":
        family = walk_family(family_key(walk.config, walk.sole, walk.dt, walk.steps, shapes))
        result = family.evaluate(theta)
        decisions = np.full(len(theta), "", dtype=object)
        batch = BatchResult(result.margin, result.time, result.deviation, decisions)
        finals = [(family, np.arange(len(theta)), theta)]
    else:
        batch, finals = _evaluate_auto(walk, shapes, theta)
    if heights is None:
        return batch
    heights = np.atleast_2d(np.asarray(heights, dtype=float))
    support = heights if support is None else np.atleast_2d(np.asarray(support, dtype=float))
    low, high = cog_height_range(walk, heights, support)
    batch = replace(batch, cog_z_min=low, cog_z_max=high)
    if terrain is None:
        return batch
    worst, rms = np.empty(len(theta)), np.empty(len(theta))
    planes: dict[tuple[float, float], tuple[float, float, float]] = {}  # the terrain under a footprint, once
    for family, rows, family_theta in finals:
        for start in range(0, len(rows), _ERROR_CHUNK):
            part = slice(start, start + _ERROR_CHUNK)
            part_theta, part_rows = family_theta[part], rows[part]
            prints = family.final_footprints(part_theta)
            under = np.array([[_plane(planes, terrain, x, y) for x, y in row.tolist()] for row in prints])
            error = family.vertical_zmp_errors(part_theta, heights[part_rows], under, support[part_rows])
            worst[part_rows], rms[part_rows] = error.max(axis=1), np.sqrt(np.mean(error**2, axis=1))
    return replace(batch, zmp_error_max=worst, zmp_error_rms=rms)


def _plane(known: dict, terrain: Terrain, x: float, y: float) -> tuple[float, float, float]:
    """The terrain's ``(z, pitch, roll)`` under a footprint at ``(x, y)`` heading +x (cached in ``known``)."""
    plane = known.get((x, y))
    if plane is None:
        plane = known[(x, y)] = surface(terrain, x, y, 0.0)
    return plane


def cog_height_range(
    walk: StraightWalk, heights: np.ndarray, support: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``(cog_z_min, cog_z_max)`` (m, each ``(B,)``) of ``walk`` with its footholds at ``heights`` ``(B, steps + 3)``
    (m) and its stances' support heights ``support`` (same shape, m; default ``heights``): the planned COG height
    over every tick (:meth:`~rtgait.core.analysis.walk_family.WalkFamily.cog_heights`; the vertical column does not
    depend on the walk's changes, so the family without them gives it)."""
    heights = np.atleast_2d(np.asarray(heights, dtype=float))
    support = heights if support is None else np.atleast_2d(np.asarray(support, dtype=float))
    family = walk_family(family_key(walk.config, walk.sole, walk.dt, walk.steps, ()))
    low, high = np.empty(len(heights)), np.empty(len(heights))
    for start in range(0, len(heights), _HEIGHT_CHUNK):
        part = slice(start, start + _HEIGHT_CHUNK)
        cog_z = family.cog_heights(heights[part], support[part])
        low[part], high[part] = cog_z.min(axis=1), cog_z.max(axis=1)
    return low, high


def evaluate_walks(walks: Sequence[StraightWalk]) -> BatchResult:
    """Evaluate every walk of ``walks`` (grouped by family, each group in one pass); results in input order."""
    groups: dict[tuple, list[int]] = {}
    thetas = []
    for index, walk in enumerate(walks):
        groups.setdefault((_group_key(walk), walk.config.connection == "auto"), []).append(index)
        thetas.append(walk.parameters())
    n = len(walks)
    margin, time, deviation = np.empty(n), np.empty(n), np.empty((n, 2))
    decisions = np.full(n, "", dtype=object)
    for members in groups.values():
        first = walks[members[0]]
        result = evaluate_parameters(first, np.stack([thetas[i] for i in members]))
        margin[members], time[members] = result.zmp_margin_min, result.zmp_margin_min_time
        deviation[members], decisions[members] = result.zmp_deviation_max, result.decisions
    result = BatchResult(margin, time, deviation, decisions)
    placed = [i for i, walk in enumerate(walks) if walk.heights is not None]
    if not placed:
        return result
    # The COG height of the walks given their heights (NaN for the others), grouped by length of walk.
    low, high = np.full(n, np.nan), np.full(n, np.nan)
    by_family: dict[tuple, list[int]] = {}
    for i in placed:
        by_family.setdefault(_group_key(walks[i]), []).append(i)
    for members in by_family.values():
        heights = np.array([walks[i].heights for i in members], dtype=float)
        support = np.array([walks[i].support or walks[i].heights for i in members], dtype=float)
        low[members], high[members] = cog_height_range(walks[members[0]], heights, support)
    return replace(result, cog_z_min=low, cog_z_max=high)


def _group_key(walk: StraightWalk) -> tuple:
    config = walk.config
    auto = (config.auto_margin,) if config.connection == "auto" else ()
    return (family_key(config, walk.sole, walk.dt, walk.steps, walk.shapes()), *auto)


def _evaluate_auto(walk: StraightWalk, shapes: tuple[ChangeShape, ...], theta: np.ndarray) -> tuple[BatchResult, list]:
    """Auto walks: each change decided in deadline order by :mod:`rtgait.core.planner.auto`'s rule, its options
    predicted on the families they make (cases that made the same earlier choices share them), then the walks
    evaluated; with the family each group of rows ended in, those rows and their parameters in its layout."""

    config, n = walk.config, walk.steps + 1
    B = len(theta)
    # Decide in deadline order; reorder the parameter columns the same way, so that the parameters of the changes
    # decided so far are always the first columns.
    order = sorted(range(len(shapes)), key=lambda c: shapes[c].decided_phase)
    blocks, column = [], 3
    for s in shapes:
        width = int(s.length) + int(s.width)
        blocks.append(list(range(column, column + width)))
        column += width
    theta = theta[:, [0, 1, 2, *(c for i in order for c in blocks[i])]]
    shapes = tuple(shapes[i] for i in order)
    chosen: list[list[ChangeShape]] = [[] for _ in range(B)]
    kinds: list[list[str]] = [[] for _ in range(B)]
    for shape in shapes:
        arrival = shape.decided_phase  # the quasi-real-time deadline, 2k - 2: the next plan is that phase's
        options = auto_options(shape.step, shape.through, arrival, n, config.horizon_steps)
        histories: dict[tuple[ChangeShape, ...], list[int]] = {}
        for row in range(B):
            histories.setdefault(tuple(chosen[row]), []).append(row)
        for history, rows in histories.items():
            predicted = np.empty((len(rows), len(options)))
            for k, option in enumerate(options):
                commit = arrival if option.commit_phase is None else option.commit_phase
                candidate = (*history, shape._replace(step=option.step, through=option.through, decided_phase=commit))
                family = walk_family(family_key(config, walk.sole, walk.dt, walk.steps, candidate))
                result = family.evaluate(_columns(theta[rows], candidate, shapes), (option.window,))
                predicted[:, k] = result.predicted[:, 0]
            reach = predicted >= config.auto_margin
            pick = np.where(reach.any(axis=1), np.argmax(reach, axis=1), np.argmax(predicted, axis=1))
            for row, k in zip(rows, pick.tolist(), strict=True):
                option = options[k]
                commit = arrival if option.commit_phase is None else option.commit_phase
                chosen[row].append(shape._replace(step=option.step, through=option.through, decided_phase=commit))
                kinds[row].append(option.kind)
    margin, time, deviation = np.empty(B), np.empty(B), np.empty((B, 2))
    finals: dict[tuple[ChangeShape, ...], list[int]] = {}
    for row in range(B):
        finals.setdefault(tuple(chosen[row]), []).append(row)
    families = []
    for final, rows in finals.items():
        family = walk_family(family_key(config, walk.sole, walk.dt, walk.steps, final))
        # rtgait plan's time rule counts from the first change's hand-over: its arrival, whatever was chosen.
        arrival = family.phase_start(shapes[0].decided_phase) if shapes else None
        columns = _columns(theta[rows], final, shapes)
        result = family.evaluate(columns, change_time=arrival)
        margin[rows], time[rows], deviation[rows] = result.margin, result.time, result.deviation
        families.append((family, np.array(rows), columns))
    decisions = np.array([",".join(k) for k in kinds], dtype=object)
    return BatchResult(margin, time, deviation, decisions), families


def _columns(theta: np.ndarray, chosen: tuple[ChangeShape, ...], original: tuple[ChangeShape, ...]) -> np.ndarray:
    """``theta``'s columns for a family of the first ``len(chosen)`` changes (their parameters come first)."""
    used = 3 + sum(int(s.length) + int(s.width) for s in original[: len(chosen)])
    return theta[:, :used]


__all__ = [
    "BatchResult",
    "StraightWalk",
    "cog_height_range",
    "evaluate_parameters",
    "evaluate_walks",
    "walk_family",
]
