"""Run the online planner as a control loop would and record every tick.

Scheduled footstep changes are handed to the planner at the latest moment its connection mode allows (the
paper's experiments: real-time changes at the changed step's lift-off, quasi-real-time ones at the start of
the double support before it), so a rollout shows what each mode can absorb.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, SoleRect
from rtgait.core.geometry.support import signed_margin, support_polygon
from rtgait.core.limits import MAX_ROLLOUT_TICKS, MIN_DT
from rtgait.core.planner.online import SAMPLE_FIELDS, OnlinePlanner, PlanRecord
from rtgait.core.planner.sample import SampleColumns


@dataclass(frozen=True)
class ScheduledChange:
    """A change of the stride of ``step`` (and of the steps up to ``through``), decided at the mode's deadline.

    ``None`` leaves a value as it was. Lengths and widths in m, turn in rad.
    """

    step: int
    length: float | None = None
    width: float | None = None
    turn: float | None = None
    through: int | None = None


@dataclass(frozen=True)
class Rollout:
    """Every control tick of a walk.

    Attributes:
        times: tick times (s), shape ``(k,)``.
        values: samples in :data:`~rtgait.core.planner.online.SAMPLE_FIELDS` order, shape ``(k, 23)``; a quantity's
            columns are :class:`~rtgait.core.planner.sample.SampleColumns`, one value's :meth:`column`.
        support: ``"double"``, ``"left"`` or ``"right"`` per tick.
        phase: phase index per tick.
        margin: signed ZMP margin to the support polygon per tick (m, positive inside).
        footprints: the footprints ``F[0..N+1]`` as walked.
        contacts: the footprints on the ground in each phase that was sampled.
        polygons: the support polygon of each phase that was sampled (counter-clockwise vertices, m).
        phase_starts: start time (s) of each phase that was sampled, by phase index.
        plans: every replanning, in order.
        changes: ``(decision time (s), step)`` of every change handed to the planner.
    """

    times: np.ndarray
    values: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    margin: np.ndarray
    footprints: list[Footstep]
    contacts: dict[int, list[Footstep]]
    polygons: dict[int, np.ndarray]
    phase_starts: dict[int, float]
    plans: list[PlanRecord]
    changes: list[tuple[float, int]]

    def column(self, name: str) -> np.ndarray:
        """One sampled quantity by its :data:`SAMPLE_FIELDS` name."""
        return self.values[:, SAMPLE_FIELDS.index(name)]

    @property
    def worst_index(self) -> int:
        """Tick with the smallest ZMP margin."""
        return int(np.argmin(self.margin))

    @property
    def zmp_margin_min(self) -> float:
        """Smallest signed ZMP margin over the walk (m)."""
        return float(self.margin[self.worst_index])

    @property
    def zmp_outside(self) -> bool:
        """Whether the planned ZMP leaves the support polygon anywhere."""
        return self.zmp_margin_min < 0.0

    @property
    def connections(self) -> list[PlanRecord]:
        """Replannings that connected to a running plan (all but the initial plan)."""
        return self.plans[1:]

    def phase_breaks(self) -> np.ndarray:
        """Boundaries (s) of the sampled phases, with the end of the rollout last: the segments of the walk."""
        starts = [self.phase_starts[q] for q in sorted(self.phase_starts)]
        return np.array([*starts, max(float(self.times[-1]), starts[-1] + 1e-9)])

    def free_segment_mask(self, plans: Sequence[PlanRecord] | None = None) -> np.ndarray:
        """Ticks inside the free first segment of ``plans`` (default: the connections), where the ZMP may leave
        the footsteps' reference to absorb a change."""
        mask = np.zeros(len(self.times), dtype=bool)
        for plan in self.connections if plans is None else plans:
            mask |= (self.times >= plan.t) & (self.times <= plan.first_segment_end)
        return mask


def rollout(
    planner: OnlinePlanner,
    dt: float,
    sole: SoleRect,
    changes: Sequence[ScheduledChange] = (),
    duration: float | None = None,
    progress: Callable[[float], None] | None = None,
    reactions: Sequence[tuple[float, Callable[[OnlinePlanner, float], object]]] = (),
) -> Rollout:
    """Start ``planner`` at t = 0 and sample it every ``dt`` (s) until the walk has come to rest.

    Args:
        planner: a planner for a finite walk (not yet started).
        dt: control period (s).
        sole: sole rectangle for the support polygons.
        changes: footstep changes, each handed over at its connection-mode deadline.
        duration: how long to run (s); default: until the walk has settled.
        progress: called now and then with the fraction done, for long runs.
        reactions: ``(time, react)`` pairs: ``react(planner, t)`` is called at the first tick ``t`` at or after
            ``time`` (s), before that tick is sampled (an obstacle seen then: :mod:`rtgait.core.obstacle.avoid`).
    """
    if not (math.isfinite(dt) and dt >= MIN_DT):
        raise ValueError(f"dt must be a finite period >= {MIN_DT:g} s, got {dt}")
    if duration is not None and not (math.isfinite(duration) and duration >= 0.0):
        raise ValueError(f"duration must be a finite time >= 0 s, got {duration}")
    end = planner.timeline.end_time if duration is None else duration
    if not math.isfinite(end):
        raise ValueError("a rollout needs a finite duration: the walk has no planned end")
    n_ticks = math.floor(end / dt + 1e-9) + 1
    if n_ticks > MAX_ROLLOUT_TICKS:
        raise ValueError(
            f"a rollout of {end:g} s at dt = {dt:g} s would take {n_ticks} ticks: at most {MAX_ROLLOUT_TICKS}"
        )
    planner.start(0.0)
    pending = sorted(changes, key=lambda c: planner.change_deadline(c.step))
    waiting = sorted(reactions, key=lambda r: r[0])
    values = np.empty((n_ticks, len(SAMPLE_FIELDS)))
    support = np.empty(n_ticks, dtype=object)
    phase = np.empty(n_ticks, dtype=int)
    times = np.arange(n_ticks) * dt
    applied: list[tuple[float, int]] = []
    report_every = max(n_ticks // 20, 1)
    # Collected as the walk goes: on a walk longer than the planner's history, the oldest would be gone.
    plans: list[PlanRecord] = []
    contacts: dict[int, list[Footstep]] = {}
    last_phase = -1
    for k in range(n_ticks):
        t = float(times[k])
        while waiting and t >= waiting[0][0]:
            waiting.pop(0)[1](planner, t)
        while pending and t >= planner.change_deadline(pending[0].step):
            change = pending.pop(0)
            planner.change_step(
                change.step, length=change.length, width=change.width, turn=change.turn, through=change.through
            )
            applied.append((planner.change_deadline(change.step), change.step))
        row, support[k], q = planner.sample_values(t)
        phase[k] = q
        values[k] = row
        if q != last_phase:
            last_phase = q
            contacts.setdefault(q, planner.contact_feet(q))
        new_plans = planner.replan_count - len(plans)
        if new_plans:
            plans.extend(planner.plans[-i] for i in range(new_plans, 0, -1))
        if progress is not None and k % report_every == 0:
            progress(k / n_ticks)
    if progress is not None:
        progress(1.0)
    zmp = values[:, SampleColumns.zmp]
    # Footprints may still move until their step is committed: take the ones the walk ended with.
    contacts = {q: _final_contacts(planner, q, feet) for q, feet in contacts.items()}
    polygons = {q: support_polygon(feet, sole) for q, feet in contacts.items()}
    margin = np.empty(n_ticks)
    for q, polygon in polygons.items():
        mask = phase == q
        margin[mask] = signed_margin(zmp[mask], polygon)
    return Rollout(
        times=times,
        values=values,
        support=support.astype(str),
        phase=phase,
        margin=margin,
        footprints=planner.footprints(),
        contacts=contacts,
        polygons=polygons,
        phase_starts={q: planner.phase_start(q) for q in contacts},
        plans=plans,
        changes=applied,
    )


def _final_contacts(planner: OnlinePlanner, q: int, seen: list[Footstep]) -> list[Footstep]:
    """The feet on the ground in phase ``q`` as the walk ended (those first seen if no longer kept)."""
    try:
        return planner.contact_feet(q)
    except IndexError:
        return seen
