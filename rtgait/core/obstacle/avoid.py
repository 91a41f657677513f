"""Reacting to an obstacle seen while walking: weigh the detours, hand the chosen one to the online planner.

When the obstacle is seen (a control tick at or after its ``seen_at``), :class:`ObstacleReaction` takes the walk as
planned then and the first step its connection mode still lets change (:meth:`Walk.first_open_step
<rtgait.core.walk.walk.Walk.first_open_step>`: in real-time mode the step about to lift off, in quasi-real-time mode
one double support earlier), makes the least detour on each side of the box (:mod:`rtgait.core.obstacle.detour`) and,
when the box is low enough, the least change of step lengths that steps over it
(:mod:`rtgait.core.obstacle.step_over`), predicts each one's smallest ZMP margin over the whole walk, and hands the
least change whose prediction keeps the ZMP inside the support polygons (margin >= 0) to the planner (the open steps'
strides, :meth:`~rtgait.core.planner.online.OnlinePlanner.set_strides`, connected by the mode's rule). When none
keeps it inside, the one with the best margin is taken (and the record says so): what the paper's real-time mode
risks (``docs/design`` method, section 5).

The predictions go through the batched operators (:mod:`rtgait.core.analysis.walk_family`): a straight walk whose
change keeps it straight (stride lengths and widths only) is one member of the family "the same walk with the length
and width of each step ``k0..N`` free, handed over at the phase the obstacle is seen", so every candidate of a mode is
one row of one evaluation, exactly what a rollout of it would give (a test compares them). A walk outside that family
(turns, footholds, per-step timing, an earlier change, footprints re-anchored to measured ones) gets no prediction:
the least change is taken.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from rtgait.core.analysis.batch import walk_family
from rtgait.core.analysis.family_key import ChangeShape, family_key
from rtgait.core.geometry.footsteps import Footstep, SoleRect, Stride, stride_between
from rtgait.core.obstacle.box import Obstacle
from rtgait.core.obstacle.detour import Detour, StrideRules, blocked, no_detour, plan_detour
from rtgait.core.obstacle.step_over import plan_step_over
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.walk.velocity_command import StepLimits

_SAME = 1e-9  # m: strides equal within this are the same stride


@dataclass(frozen=True)
class Candidate:
    """One detour weighed: its side, the change (``None`` when there is none, with the reason), and its predicted
    smallest ZMP margin over the walk (m, ``None``: not predicted)."""

    side: str
    detour: Detour | None
    zmp_margin: float | None
    reason: str = ""


@dataclass(frozen=True)
class Avoidance:
    """What the walk did on seeing the obstacle.

    Attributes:
        obstacle: the box.
        time: the tick it was seen and the change handed over (s).
        connection: the planner's connection mode.
        first_open: the first step that could still change.
        before: footprints ``F[base..N + 1]`` as planned just before (m, rad).
        candidates: every side weighed.
        chosen: the detour handed to the planner (``None``: none possible, the walk was left as it was).
        predicted_by: ``"batch"`` (the batched operators), or ``"none"``.
    """

    obstacle: Obstacle
    time: float
    connection: str
    first_open: int
    before: tuple[Footstep, ...]
    candidates: tuple[Candidate, ...]
    chosen: Candidate | None
    predicted_by: str

    @property
    def avoided(self) -> bool:
        """Whether the walk now keeps its footsteps off the obstacle."""
        return self.chosen is not None

    @property
    def predicted_inside(self) -> bool | None:
        """Whether the chosen detour's predicted ZMP stays inside the support polygons (``None``: not predicted)."""
        if self.chosen is None or self.chosen.zmp_margin is None:
            return None
        return self.chosen.zmp_margin >= 0.0


def stride_rules(planner: OnlinePlanner, margin: float, clearance: float) -> StrideRules:
    """The detour's rules from a planner's configuration: its step limits, stance and swing height."""
    config = planner.config
    limits = StepLimits(config.max_step_length, config.max_step_lateral, config.max_step_turn, config.min_step_width)
    return StrideRules(limits, config.step_width, config.step_height, margin, clearance)


@dataclass
class ObstacleReaction:
    """Called by a control loop at the tick ``t`` (s) the obstacle is first seen: changes the planner's walk
    (module docstring) and keeps what it did in :attr:`result`.

    Args:
        obstacle: the box.
        sole: the sole rectangle (m).
        dt: the loop's control period (s): the batched prediction samples the walk at it.
        margin: distance kept between a sole and the box (m).
        clearance: height kept over the box when stepping over it (m).
    """

    obstacle: Obstacle
    sole: SoleRect
    dt: float
    margin: float = 0.03
    clearance: float = 0.03
    result: Avoidance | None = field(default=None, init=False)

    def __call__(self, planner: OnlinePlanner, t: float) -> None:
        rules = stride_rules(planner, self.margin, self.clearance)
        base = planner.walk.base
        first_open = planner.first_open_step()
        k0 = first_open - base
        mode = planner.config.connection
        if planner.n_steps is None:  # a walk by velocity command has no remaining footsteps to change
            self.result = Avoidance(self.obstacle, t, mode, first_open, (), (), None, "none")
            return
        before = planner.footprints()
        candidates: list[Candidate] = []
        if not blocked(before, max(k0 + 1, 2), self.obstacle, self.sole, rules):
            chosen = Candidate("none", no_detour(before, first_open), None, "the walk is already clear of it")
            self.result = Avoidance(self.obstacle, t, planner.config.connection, first_open, tuple(before),
                                    (chosen,), chosen, "none")  # fmt: skip
            return
        detours: list[tuple[str, Detour | None, str]] = []
        sides = ("left", "right", "over") if self.obstacle.can_step_over(rules.step_height, rules.clearance) else (
            "left", "right")  # fmt: skip
        for side in sides:
            try:
                if side == "over":
                    detour = plan_step_over(before, first_open, self.obstacle, self.sole, rules, base)
                else:
                    detour = plan_detour(before, first_open, self.obstacle, self.sole, rules, side, base)
                detours.append((side, detour, ""))
            except ValueError as error:  # NoDetourError, or a change no stride can describe (feet crossing)
                detours.append((side, None, str(error)))
        margins = self._predict(planner, t, [d for _, d, _ in detours if d is not None])
        predicted_by = "batch" if margins is not None else "none"
        feasible = iter(margins if margins is not None else [])
        for side, detour, reason in detours:
            margin = next(feasible) if detour is not None and margins is not None else None
            candidates.append(Candidate(side, detour, margin, reason))
        chosen = _choose(candidates)
        if chosen is not None:
            # Strides are relative: the open steps' strides from the committed stance foot F[k0] on.
            prints = chosen.detour.footprints[k0:]
            try:
                planner.set_strides([stride_between(a, b) for a, b in itertools.pairwise(prints)], first_open)
            except ValueError as error:  # the walk is ending (its final double support has begun): too late
                candidates.append(Candidate(chosen.side, None, chosen.zmp_margin, f"refused by the planner: {error}"))
                chosen = None
        self.result = Avoidance(self.obstacle, t, mode, first_open, tuple(before), tuple(candidates), chosen,
                                predicted_by)  # fmt: skip

    # ----- the batched prediction ----------------------------------------------------------------------
    def _predict(self, planner: OnlinePlanner, t: float, detours: list[Detour]) -> list[float] | None:
        """Each detour's smallest ZMP margin over the walk (m), through one batched evaluation; ``None`` when the
        walk is not a member of the family (module docstring)."""
        if not detours:
            return []
        walk = _straight_walk(planner)
        if walk is None:
            return None
        steps, length, width = walk
        first_open = detours[0].first_open
        if first_open > steps:
            return None
        rel = t - planner.t0
        timeline = planner.timeline
        q = timeline.phase_at(rel)
        # Handed over at tick t: a plan made at or after t sees it, so the family hands it over at the start of the
        # first phase whose replan comes no earlier than t.
        decided = q if abs(timeline.start_time(q) - rel) < 1e-12 else q + 1
        if decided > 2 * (steps + 1):
            return None
        changed = tuple(ChangeShape(i, i, True, True, decided) for i in range(first_open, steps + 1))
        key = family_key(planner.config, self.sole, self.dt, steps, changed)
        rows = []
        for detour in detours:
            prints = detour.footprints
            widths = [stride_between(prints[i], prints[i + 1]) for i in range(first_open, steps + 2)]
            closing = widths[-1]
            if abs(closing.width - width) > _SAME or abs(closing.length) > _SAME or abs(closing.turn) > _SAME:
                return None  # the closing step moved: not a member of the family
            if any(abs(s.turn) > _SAME for s in widths[:-1]):
                return None
            rows.append([1.0, length, width, *(v for s in widths[:-1] for v in (s.length, s.width))])
        result = walk_family(key).evaluate(np.array(rows))
        return [float(m) for m in result.margin]


def _straight_walk(planner: OnlinePlanner) -> tuple[int, float, float] | None:
    """``(steps, step_length, step_width)`` when the planner's walk is a straight walk from the standing feet at the
    origin as the batched family makes it (uniform timing, no change yet), else ``None``."""
    walk = planner.walk
    n = walk.n_steps
    if n is None or walk.base != 0 or n < 2 or not planner.timeline.uniform:
        return None
    first = walk.stride(1)
    width = planner.config.step_width
    if any(abs(v) > _SAME for v in (first.turn,)) or abs(first.width - width) > _SAME:
        return None
    for k in range(1, n):
        s = walk.stride(k)
        if abs(s.length - first.length) > _SAME or abs(s.width - width) > _SAME or abs(s.turn) > _SAME:
            return None
    if walk.stride(n) != Stride(0.0, width, 0.0):
        return None
    standing = walk.standing
    half = 0.5 * width
    expected = {"left": half, "right": -half}
    if any(abs(f.x) > _SAME or abs(f.yaw) > _SAME or abs(f.y - expected[f.side]) > _SAME for f in standing):
        return None
    return n - 1, first.length, width


def _choose(candidates: list[Candidate]) -> Candidate | None:
    """The least change whose predicted margin is >= 0; else (none predicted inside) the best predicted margin;
    without predictions, the least change."""
    possible = [c for c in candidates if c.detour is not None]
    if not possible:
        return None
    inside = [c for c in possible if c.zmp_margin is None or c.zmp_margin >= 0.0]
    if inside:
        return min(inside, key=lambda c: c.detour.cost)
    return max(possible, key=lambda c: c.zmp_margin if c.zmp_margin is not None else -math.inf)


__all__ = ["Avoidance", "Candidate", "ObstacleReaction", "stride_rules"]
