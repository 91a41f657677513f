"""A family of straight walks that differ only in their stride lengths and widths, evaluated many at once.

Fix everything of a rollout (:func:`rtgait.core.analysis.rollout.rollout`) but the numbers: the timing, the control
period, the horizon, the number of steps, which steps change and when each change is handed to the planner. What is left
are the parameters ``theta = [1, step_length, step_width, change lengths..., change widths...]`` (m), and everything the
planner computes is affine in them:

* the footprints: a straight walk's strides are relative, so ``F[i] = F[i - 1] + (length_i, +-width_i)``;
* every plan: ``G @ y`` with ``y = [state, anchors]``, the anchors footprints (or midpoints of two) and the state
  the end state of the previous plan, itself ``S @ y_prev`` (:class:`~rtgait.core.planner.active_plan.PlanLayout`);
* so each segment's ZMP polynomial, whose coefficients are carried here as ``(2, P)`` arrays (axes by parameters).

Per phase the ZMP then has a shape two vectors describe. In a connecting (free) double support that starts at rest
(every double support does: the ZMP stands still in single support) the free quartic is the footsteps' cubic
``s(u) = 3u^2 - 2u^3`` plus ``beta b(u)``, ``b(u) = u^2 (1 - u)^2``, ``u = tau / T`` (the quadratic variant:
``u D + beta u (1 - u)``): relative to where it starts, ``zmp = s(u) D + b(u) beta`` with ``D`` the way to the next
anchor. The settling phase is its anchor plus the rest bump ``alpha b(u)``; single support is the stance ankle
itself, exactly. (The structure is checked on the operators; a walk without it is refused.) The margin at a tick is
``min_e (c_e - s_t n_e . D - b_t n_e . beta)`` over the 8 edge lines of the two soles' hull
(:func:`~rtgait.core.geometry.hull.two_box_hull`), and its minimum over the phase's ticks is, per edge, the maximum of a
linear function over the fixed points ``(s_t, b_t)``: a binary search on their hull
(:class:`~rtgait.core.geometry.hull.PointChain`). So a case costs a few dozen vector operations per phase, not one per
tick. Where a phase's minimum is negative (the ZMP leaves the polygon) the exact outside distance is computed at every
tick of that phase for those cases.

A family's key and the affine footprints of its parameters are in :mod:`rtgait.core.analysis.family_key`; its chain of
plans and, over height changes, the COG height of every tick as a linear map of the footholds' heights and the
stances' support heights (:meth:`WalkFamily.cog_heights`) in :mod:`rtgait.core.analysis.family_height`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rtgait.core.analysis.family_height import (
    TickRows,
    VerticalColumn,
    contact_feet,
    plan_chain,
    tick_rows,
    vertical_zmp_error,
)
from rtgait.core.analysis.family_key import FamilyKey, affine_footprints
from rtgait.core.geometry.footsteps import Stride
from rtgait.core.geometry.hull import (
    PointChain,
    outside_margin,
    point_chain,
    single_sole_margin,
    sole_extents,
    two_box_hull,
    two_box_vertices,
)
from rtgait.core.limits import MAX_ROLLOUT_TICKS, MIN_DT
from rtgait.core.planner.auto import AUTO_SAMPLES
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.online import OnlinePlanner

TIE = 1e-9
"""Margins (m) within this of the minimum are tied with it (``rtgait.viz.margin_marker.MARGIN_TIE_TOLERANCE``)."""
_STRUCTURE_TOLERANCE = 1e-9
CHUNK = 4096
"""Cases evaluated together: large enough to amortise numpy's call overhead, small enough to stay in cache."""


class FamilyResult(NamedTuple):
    """Per case: smallest signed ZMP margin (m), the tick index and time (s) of its first occurrence, largest
    ``|ZMP - reference|`` per axis in the connecting segments (m), and the predicted margins of requested windows."""

    margin: np.ndarray
    tick: np.ndarray
    time: np.ndarray
    deviation: np.ndarray
    predicted: np.ndarray


class _Phase(NamedTuple):
    q: int
    kind: str  # "single", "free" (a plan's first segment) or "settle"
    ticks: np.ndarray  # tick indices in the phase
    chain: PointChain | None  # (s_t, b_t) at the ticks
    points: np.ndarray | None
    predictor: PointChain | None  # (s, b) at AUTO_SAMPLES evenly spaced times (free segments)
    deviation: PointChain | None  # deviation shape at the ticks (connecting segments only)
    features: np.ndarray | None  # (8, P): o_A (2), o_B (2), D (2), beta (2), relative to the phase's start point
    boxes: tuple[np.ndarray, np.ndarray] | None  # sole extents (x0, x1, y0, y1) of the two feet


def _shapes(u: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """``(s, b)`` of a free segment at normalised times ``u``: the travelled share and the free bump."""
    if degree == 4:
        return u * u * (3.0 - 2.0 * u), (u * (1.0 - u)) ** 2
    return u.copy(), u * (1.0 - u)


class WalkFamily:
    """The affine map from parameters to every phase of a family of straight walks, and its batched evaluation.

    Build one per :class:`FamilyKey` (a few milliseconds: the planner's operators and one linear pass over its
    plans), then :meth:`evaluate` any number of parameter rows.
    """

    def __init__(self, key: FamilyKey) -> None:
        if not key.timing.uniform:
            raise ValueError("the batched evaluation needs one timing for every step: per-step timings are unsupported")

        self.key = key
        if not (math.isfinite(key.dt) and key.dt >= MIN_DT):
            raise ValueError(f"dt must be a finite period >= {MIN_DT:g} s, got {key.dt}")
        config = PlannerConfig(
            cog_height=key.cog_height, timing=key.timing, horizon_steps=key.horizon_steps, gravity=key.gravity,
            first_degree=key.first_degree, first_side=key.first_side,
        )  # fmt: skip
        n = key.steps + 1
        planner = OnlinePlanner(config, [Stride(0.1, 0.19)] * key.steps + [Stride(0.0, 0.19)])
        planner.start(0.0)
        self.n_steps = n
        starts = np.array([planner.phase_start(q) for q in range(2 * n + 2)])
        n_ticks = math.floor(planner.timeline.end_time / key.dt + 1e-9) + 1
        if n_ticks > MAX_ROLLOUT_TICKS:
            raise ValueError(f"a walk of {n_ticks} ticks is more than a rollout allows ({MAX_ROLLOUT_TICKS})")
        self.times = np.arange(n_ticks) * key.dt
        self._starts = starts
        tick_phase = np.clip(np.searchsorted(starts, self.times, side="right") - 1, 0, 2 * n + 1)
        replan_tick = {q: int(np.searchsorted(self.times, starts[q], side="left")) for q in range(0, 2 * n + 1, 2)}
        for change in key.changes:
            if not (1 <= change.step <= change.through <= key.steps) or not 0 <= change.decided_phase <= 2 * n:
                raise ValueError(f"change {change} does not fit a walk of {key.steps} steps")
        # The rollout hands changes over in deadline order (stable); a plan sees those handed over by its tick.
        order = sorted(range(len(key.changes)), key=lambda c: starts[key.changes[c].decided_phase])
        change_ticks = [int(np.searchsorted(self.times, starts[key.changes[c].decided_phase])) for c in order]
        versions = [affine_footprints(key, order[:v]) for v in range(len(order) + 1)]
        final, sides = versions[-1]
        self.replan_tick = replan_tick
        self._phases: list[_Phase] = []
        self._planner, self._tick_phase, self._final = planner, tick_phase, final
        self._vertical = VerticalColumn(planner, n, self.times, starts, tick_phase)
        self._horizontal: TickRows | None = None

        def prints_at(q: int) -> np.ndarray:  # the footprints with the changes handed over by the replan's tick
            return versions[sum(tick <= replan_tick[q] for tick in change_ticks)][0]

        plan_data = self._plans = plan_chain(planner, n, prints_at)
        for q in range(2 * n + 2):
            ticks = np.flatnonzero(tick_phase == q)
            if len(ticks):
                self._phases.append(self._phase(q, ticks, plan_data, starts, final, sides, planner))

    def _phase(self, q, ticks, plan_data, starts, prints, sides, planner) -> _Phase:
        """The shape of phase ``q``'s ZMP and support polygon (module docstring), checked on the coefficients."""
        key, n = self.key, self.n_steps
        plan_q = min(q - (q & 1), 2 * n)
        j = q - plan_q
        seg, layout = plan_data[plan_q]
        T = layout.durations[j]
        a = seg[12 * j : 12 * j + 5]  # ZMP coefficients (5, 2, P)
        tau = np.minimum(self.times[ticks] - starts[plan_q] - layout.offsets[j], T)
        u = tau / T
        kind = planner.timeline.kind(q)
        scale = 1.0 + float(np.abs(a).max())
        if kind == "single":
            _check(np.abs(a[1:]).max() <= _STRUCTURE_TOLERANCE * scale, q)
            return _Phase(q, "single", ticks, None, None, None, None, None, None)
        if kind == "settle":
            alpha = a[4] * T**4
            residual = max(np.abs(a[1]).max(), np.abs(a[2] * T**2 - alpha).max(), np.abs(a[3] * T**3 + 2 * alpha).max())
            D, beta, s, b = np.zeros_like(alpha), alpha, np.zeros_like(u), (u * (1.0 - u)) ** 2
            predictor = deviation = None
        else:
            if key.first_degree == 4:
                beta = a[4] * T**4
                D = (a[2] * T**2 - beta) / 3.0
                residual = max(np.abs(a[1]).max(), np.abs(a[3] * T**3 + 2.0 * D + 2.0 * beta).max())
            else:
                beta = -a[2] * T**2
                D = a[1] * T - beta
                residual = max(np.abs(a[3]).max(), np.abs(a[4]).max())
            s, b = _shapes(u, key.first_degree)
            samples = np.linspace(0.0, T, AUTO_SAMPLES) / T
            predictor = point_chain(np.stack(_shapes(samples, key.first_degree), axis=1))
            deviation = None
            if q >= 2:  # a connection (the first plan is not one): ZMP minus the footsteps' cubic
                reference = u * u * (3.0 - 2.0 * u)
                deviation = point_chain(np.stack([s - reference, b], axis=1))
        _check(residual <= _STRUCTURE_TOLERANCE * scale, q)
        i = min(q // 2, n)
        start = a[0]
        features = np.concatenate([prints[i] - start, prints[i + 1] - start, D, beta])  # (8, P)
        boxes = tuple(np.array(sole_extents(key.sole, sides[k] == "left")) for k in (i, i + 1))
        points = np.stack([s, b], axis=1)
        return _Phase(q, "free" if kind != "settle" else "settle", ticks, point_chain(points), points, predictor,
                      deviation, features, boxes)  # fmt: skip

    def cog_heights(self, heights: np.ndarray, support: np.ndarray | None = None) -> np.ndarray:
        """The planned COG height (m) at every tick ``(B, ticks)`` of walks whose footholds ``F[0..n+1]`` stand at
        ``heights`` ``(B, n + 2)`` (m) and whose stances hold the support heights ``support`` (same shape, m;
        default ``heights``: no step down): the vertical column (:mod:`rtgait.core.analysis.family_height`), the
        same for every case of the family whatever its strides and changes (a stride keeps its rise)."""
        return self._vertical.motion(*self._checked_heights(heights, support), self.key.cog_height)[0]

    def final_footprints(self, theta: np.ndarray) -> np.ndarray:
        """The footprints ``F[0..n+1]`` ``(B, n + 2, 2)`` (m) the walks ``theta`` end with, every change made."""
        return np.einsum("iap,bp->bia", self._final, np.atleast_2d(theta))

    def vertical_zmp_errors(
        self, theta: np.ndarray, heights: np.ndarray, planes: np.ndarray, support: np.ndarray | None = None
    ) -> np.ndarray:
        """The error ``(B, ticks)`` (m) the vertical motion adds to the horizontal ZMP
        (:func:`~rtgait.core.analysis.family_height.vertical_zmp_error`) of walks ``theta`` ``(B, P)`` with footholds
        at ``heights`` and stances' support heights ``support`` (:meth:`cog_heights`) on a terrain whose plane under
        each final footprint is ``planes`` ``(B, n + 2, 3)`` (height m, pitch, roll rad)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        vertical = self._vertical.motion(*self._checked_heights(heights, support), self.key.cog_height)
        if self._horizontal is None:
            self._horizontal = tick_rows(
                self._plans, self.n_steps, self.times, self._starts, self._tick_phase, self._planner.w
            )
        feet = contact_feet(self._tick_phase, self.n_steps)
        return vertical_zmp_error(self._horizontal, vertical, feet, theta, self.final_footprints(theta),
                                  np.asarray(planes, dtype=float), self.key.gravity)  # fmt: skip

    def _checked_heights(self, heights: np.ndarray, support: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        heights = np.atleast_2d(np.asarray(heights, dtype=float))
        support = heights if support is None else np.atleast_2d(np.asarray(support, dtype=float))
        want = self.n_steps + 2
        for name, values in (("heights", heights), ("support heights", support)):
            if values.shape != (len(heights), want) or not np.all(np.isfinite(values)):
                raise ValueError(f"{name} must be finite, {want} per walk (F[0..n+1]), got {values.shape}")
        return heights, support

    def phase_start(self, q: int) -> float:
        """Start of phase ``q`` (s), as the planner computes it."""
        return float(self._starts[q])

    # ----- evaluation -------------------------------------------------------------------------------------
    def evaluate(
        self, theta: np.ndarray, windows: tuple[tuple[int, int], ...] = (), change_time: float | None = None
    ) -> FamilyResult:
        """Margins, times and deviations for parameter rows ``theta`` ``(B, P)`` (m; column 0 is 1).

        ``windows``: phase ranges ``(first, last)`` (inclusive) over whose free segments the predicted margin of the
        auto connection is wanted (half-plane margin at :data:`AUTO_SAMPLES` samples per segment); ``predicted`` then
        has one column per window (``+inf`` for a window without free segments).

        The time is ``rtgait plan``'s (:func:`rtgait.viz.margin_marker.margin_marker`): the tick of the minimum, and
        when several ticks are within :data:`TIE` of it, the first of them at or after ``change_time`` (s; default the
        first change's hand-over), else the first of them.
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if theta.shape[1] != self.key.n_params:
            raise ValueError(f"theta must have {self.key.n_params} columns, got {theta.shape[1]}")
        if change_time is None and self.key.changes:
            change_time = min(self._starts[c.decided_phase] for c in self.key.changes)
        if len(theta) > CHUNK:  # blocks that keep the per-phase arrays in cache
            parts = [self.evaluate(theta[i : i + CHUNK], windows, change_time) for i in range(0, len(theta), CHUNK)]
            return FamilyResult(*(np.concatenate(field) for field in zip(*parts, strict=True)))
        B = len(theta)
        varying = np.any(theta != theta[:1], axis=0)
        m_single = single_sole_margin(self.key.sole)
        n_phases = len(self._phases)
        values, ticks, firsts = np.empty((B, n_phases)), np.empty((B, n_phases), dtype=int), np.empty((B, n_phases))
        features: list[np.ndarray | None] = []
        exact: list[tuple[np.ndarray, np.ndarray] | None] = []  # per phase: rows evaluated at every tick, margins
        deviation = np.zeros((B, 2))
        predicted = np.full((B, len(windows)), np.inf)
        for p, phase in enumerate(self._phases):
            if phase.kind == "single":
                values[:, p], ticks[:, p], firsts[:, p] = m_single, phase.ticks[0], m_single
                features.append(None)
                exact.append(None)
                continue
            # A phase none of whose features depends on what varies is the same for every case: evaluate it once.
            f = (theta if np.any(phase.features[:, varying]) else theta[:1]) @ phase.features.T
            value, tick, first, dev, windowed, ticked = self._free_phase(phase, f, windows)
            values[:, p], ticks[:, p], firsts[:, p] = value, tick, first
            features.append(f)
            exact.append(ticked)
            np.maximum(deviation, dev, out=deviation)
            np.minimum(predicted, windowed, out=predicted)
        best = values.min(axis=1)
        chosen = self._reported_ticks(best, values, ticks, firsts, features, exact, change_time)
        return FamilyResult(best, chosen, self.times[chosen], deviation, predicted)

    def _reported_ticks(self, best, values, ticks, firsts, features, exact, change_time) -> np.ndarray:
        """The tick ``rtgait plan`` reports for each case (:meth:`evaluate`): per phase, its first tied tick overall
        and its first tied tick at or after the change, then the earliest of those over the phases."""
        B = len(best)
        never = np.iinfo(int).max
        after = -np.inf if change_time is None else change_time - 1e-12
        limit = best + TIE
        first_tied = np.full(B, never)
        first_after = np.full(B, never)
        for p, phase in enumerate(self._phases):
            times = self.times[phase.ticks]
            tied = values[:, p] <= limit
            if phase.kind == "single":  # the same margin at every tick
                later = phase.ticks[times >= after]
                np.minimum(first_tied, np.where(tied, phase.ticks[0], never), out=first_tied)
                if len(later):
                    np.minimum(first_after, np.where(tied, later[0], never), out=first_after)
                continue
            # A free segment starting on the ankle ties at its first tick; otherwise (rare: a minimum so flat that
            # neighbouring ticks are within TIE of it) the margins at every tick of the phase, for those cases.
            at_first = tied & (firsts[:, p] <= limit)
            head = np.where(at_first, phase.ticks[0], never)
            head_after = np.where(at_first & (times[0] >= after), phase.ticks[0], never)
            search = np.flatnonzero(tied & ~at_first)
            if len(search):
                margins = self._search_margins(phase, search, features[p], exact[p])
                hit = margins <= limit[search, None]
                index = np.argmax(hit, axis=1)
                head[search] = phase.ticks[index]
                hit_after = hit & (times >= after)[None, :]
                found = hit_after.any(axis=1)
                head_after[search] = np.where(found, phase.ticks[np.argmax(hit_after, axis=1)], never)
            np.minimum(first_tied, head, out=first_tied)
            np.minimum(first_after, head_after, out=first_after)
        return np.where(first_after < never, first_after, first_tied)

    def _search_margins(self, phase: _Phase, rows: np.ndarray, f: np.ndarray, done) -> np.ndarray:
        """Margins at every tick of ``phase`` for case ``rows``: those the outside path computed, else anew."""
        if len(f) == 1:  # the phase is the same for every case
            f = np.repeat(f, int(rows.max()) + 1, axis=0)
        out = np.empty((len(rows), len(phase.ticks)))
        known = np.zeros(len(rows), dtype=bool)
        if done is not None and len(done[0]):
            where = np.clip(np.searchsorted(done[0], rows), 0, len(done[0]) - 1)
            known = done[0][where] == rows
            out[known] = done[1][where[known]]
        if not known.all():
            out[~known] = self._tick_margins(phase, f[rows[~known]])
        return out

    def _tick_margins(self, phase: _Phase, f: np.ndarray) -> np.ndarray:
        """Exact signed margins ``(R, T)`` (m) at every tick of a free phase, for feature rows ``f``."""
        box_a, box_b = phase.boxes
        o_a, o_b, D, beta = f[:, 0:2], f[:, 2:4], f[:, 4:6], f[:, 6:8]
        box_a, box_b = o_a[:, [0, 0, 1, 1]] + box_a, o_b[:, [0, 0, 1, 1]] + box_b
        nx, ny, offsets = two_box_hull(box_a, box_b)
        s, b = phase.points[:, 0], phase.points[:, 1]
        px = s * D[:, 0:1] + b * beta[:, 0:1]  # (R, T)
        py = s * D[:, 1:2] + b * beta[:, 1:2]
        hp = np.full(px.shape, np.inf)
        for e in range(offsets.shape[1]):
            np.minimum(hp, offsets[:, e : e + 1] - nx[:, e : e + 1] * px - ny[:, e : e + 1] * py, out=hp)
        if np.all(hp >= 0.0):
            return hp
        return np.where(hp >= 0.0, hp, outside_margin(px, py, two_box_vertices(box_a, box_b)))

    def _free_phase(self, phase: _Phase, f: np.ndarray, windows) -> tuple:
        """Minimum margin and its tick, deviation per axis and windowed predictions for feature rows ``f``."""
        box_a, box_b = phase.boxes
        o_a, o_b, D, beta = f[:, 0:2], f[:, 2:4], f[:, 4:6], f[:, 6:8]
        box_a, box_b = o_a[:, [0, 0, 1, 1]] + box_a, o_b[:, [0, 0, 1, 1]] + box_b
        nx, ny, offsets = two_box_hull(box_a, box_b)
        along_d = nx * D[:, 0:1] + ny * D[:, 1:2]
        along_beta = nx * beta[:, 0:1] + ny * beta[:, 1:2]
        top, index = phase.chain.maximum(along_d, along_beta)
        margins = offsets - top
        edge = np.argmin(margins, axis=1)
        rows = np.arange(len(f))
        value, tick = margins[rows, edge], index[rows, edge]
        outside = np.flatnonzero(value < 0.0)
        exact = None
        if len(outside):
            value, tick = value.copy(), tick.copy()
            # Outside the polygon the half-plane measure is only a bound: the exact distance at every tick.
            exact = self._tick_margins(phase, f[outside])
            tick[outside] = np.argmin(exact, axis=1)
            value[outside] = exact[np.arange(len(outside)), tick[outside]]
        tick = phase.ticks[tick]
        # The margin at the phase's first tick (the half-plane one: it only matters where it ties the minimum).
        s0, b0 = phase.points[0]
        first = np.min(offsets - (s0 * along_d + b0 * along_beta), axis=1)
        dev = np.zeros((len(f), 2))
        if phase.deviation is not None:
            for axis in range(2):
                v = np.stack([D[:, axis], beta[:, axis]])
                up = phase.deviation.maximum(v[0], v[1])[0]
                down = phase.deviation.maximum(-v[0], -v[1])[0]
                dev[:, axis] = np.maximum(np.abs(up), np.abs(down))
        windowed = np.full((len(f), len(windows)), np.inf)
        if phase.predictor is not None:
            hits = [k for k, (lo, hi) in enumerate(windows) if lo <= phase.q <= hi]
            if hits:
                top = phase.predictor.maximum(along_d, along_beta)[0]
                windowed[:, hits] = (offsets - top).min(axis=1)[:, None]
        return value, tick, first, dev, windowed, (outside, exact if exact is not None else np.zeros((0, 0)))


def _check(ok: bool, q: int) -> None:
    if not ok:
        raise ValueError(f"phase {q}: the plan's ZMP does not have the shape the batched evaluation needs")


__all__ = ["TIE", "FamilyResult", "WalkFamily"]
