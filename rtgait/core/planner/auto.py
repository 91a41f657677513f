"""The ``"auto"`` connection: per change, the latest connection that keeps the ZMP inside, or a later step.

What a *change* is. One call ``change_step(k, length=..., width=..., turn=..., through=...)`` (one
``[[walk.change]]`` of a scenario) asks for new strides from step ``k`` (1-based) to ``through``. In auto mode it
is accepted until step ``k`` lifts off (the real-time deadline) and decided at once, when it arrives, among:

1. ``"real-time"``: the change is committed at step ``k``'s lift-off (start of phase ``2k - 1``): plans made before
   keep the old footprints (so the change may still be revised until then), the plan of the double support after
   ``k`` lands (phase ``2k``) absorbs it. If it arrives after the double support before ``k`` began, this is simply
   "now".
2. ``"quasi-real-time"``, only while its deadline (the start of phase ``2k - 2``) has not passed, i.e. while the plan
   of that double support is still to be made: committed now, so that plan absorbs it over the whole single support
   of step ``k``.
3. ``"deferred"``: committed now as a change of a later step ``j = k + 1, ..., k + horizon_steps`` (the same new
   strides from ``j`` on: ``through`` stays, or moves with ``j`` for a one-step change), never past ``through`` nor
   onto the closing step.

Each option is *predicted* with the plan operators: the planner makes, from the plan being executed, the plans it
would make at the coming double-support starts with the footprints the option gives, and takes the smallest
half-plane ZMP margin (:func:`~rtgait.core.geometry.halfplanes.halfplane_margin`, against each phase's support polygon)
at :data:`~AUTO_SAMPLES` evenly spaced times over the free first segment of each plan in the option's *window*: from the
first plan that sees the change through ``horizon_steps + 1`` double supports later (:func:`window`). The first option,
in the order above, whose prediction reaches ``auto_margin`` is taken; if none does, the one with the largest prediction
(ties: the earliest). With a single change and no other input this prediction is exactly what the rollout then walks,
which is how the batched evaluation (:mod:`rtgait.core.analysis.batch`) reproduces the planner's choice.

Scheduled changes (:func:`rtgait.core.analysis.rollout.rollout`, ``rtgait plan``) are handed to an auto planner at the
quasi-real-time deadline (``OnlinePlanner.change_deadline``): the latest moment at which all three options are open.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple, Protocol

import numpy as np

from rtgait.core.geometry.halfplanes import halfplane_margin, polygon_halfplanes
from rtgait.core.geometry.support import support_polygon

if TYPE_CHECKING:
    from rtgait.core.planner.active_plan import PlanLayout
    from rtgait.core.planner.config import PlannerConfig
    from rtgait.core.walk.walk import Walk

AUTO_SAMPLES = 33
"""Samples per free segment at which the auto connection predicts a plan's ZMP margin (both ends included)."""

AUTO_KINDS = ("real-time", "quasi-real-time", "deferred")


class AutoOption(NamedTuple):
    """One way to carry out a change: its kind, the strides it sets (``step..through``), the phase at whose start it
    is committed (``None``: now) and the window of plans (first and last phase, inclusive) its prediction covers."""

    kind: str
    step: int
    through: int
    commit_phase: int | None
    window: tuple[int, int]


class ChangeRecord(NamedTuple):
    """One accepted change, as the planner logs it (:attr:`~rtgait.core.planner.online.OnlinePlanner.change_log`).

    Attributes:
        time: when it arrived (s; the latest time sampled then).
        step: the step it asked for (1-based).
        connection: how it is connected: the planner's mode, or in auto mode the option taken (:data:`AUTO_KINDS`).
        committed_step, through: the strides it sets (``committed_step`` differs from ``step`` when deferred).
        commit_time: when it is applied to the walk (s): on arrival, or at the step's lift-off when held.
        predicted: auto mode: ``(kind, step, margin)`` of every option weighed (margin in m).
        reason: auto mode: why that option, in one line.
    """

    time: float
    step: int
    connection: str
    committed_step: int
    through: int
    commit_time: float
    predicted: tuple[tuple[str, int, float], ...]
    reason: str


class AutoDecision(NamedTuple):
    """The choice for one change: the option taken, every option's predicted margin (m) and a one-line reason."""

    option: AutoOption
    predicted: tuple[tuple[AutoOption, float], ...]
    reason: str


def window(first: int, horizon_steps: int, n_steps: int | None) -> tuple[int, int]:
    """Phases of the plans an option's prediction covers: the double supports from ``first`` through
    ``horizon_steps + 1`` later ones, ending at the final double support ``2 n`` of a finite walk."""
    last = first + 2 * (horizon_steps + 1)
    return first, last if n_steps is None else min(last, 2 * n_steps)


def auto_options(
    step: int, through: int, next_replan: int, n_steps: int | None, horizon_steps: int
) -> list[AutoOption]:
    """The options of a change of ``step..through`` arriving when the next plan to be made is the one of phase
    ``next_replan`` (module docstring), in order of preference."""
    options = [
        AutoOption(
            "real-time", step, through, 2 * step - 1 if next_replan <= 2 * step - 2 else None,
            window(max(2 * step, next_replan), horizon_steps, n_steps),
        )
    ]  # fmt: skip
    now = window(next_replan, horizon_steps, n_steps)
    if next_replan <= 2 * step - 2:
        options.append(AutoOption("quasi-real-time", step, through, None, now))
    last = step + horizon_steps
    if through > step:
        last = min(last, through)
    if n_steps is not None:
        last = min(last, n_steps - 1)  # the closing step keeps the walk's end
    for later in range(step + 1, last + 1):
        options.append(AutoOption("deferred", later, max(through, later), None, now))
    return options


def choose(options: list[AutoOption], predicted: list[float], auto_margin: float) -> AutoDecision:
    """The first option whose predicted margin (m) reaches ``auto_margin`` (m), else the one with the largest."""
    pairs = tuple(zip(options, predicted, strict=True))
    for option, margin in pairs:
        if margin >= auto_margin:
            return AutoDecision(option, pairs, _describe(option, margin, f">= auto_margin {auto_margin * 1e3:g} mm"))
    best = max(range(len(pairs)), key=lambda i: (pairs[i][1], -i))
    option, margin = pairs[best]
    return AutoDecision(option, pairs, _describe(option, margin, f"below auto_margin {auto_margin * 1e3:g} mm for "
                                                 "every option: the largest"))  # fmt: skip


def _describe(option: AutoOption, margin: float, why: str) -> str:
    where = f" to step {option.step}" if option.kind == "deferred" else ""
    return f"{option.kind}{where}: predicted ZMP margin {margin * 1e3:+.1f} mm {why}"


class AutoPlanner(Protocol):
    """What the auto connection reads of its planner (:class:`~rtgait.core.planner.online.OnlinePlanner`): its
    settings, its walk (changed through the walk's own methods) and the plan it would make at a phase's start."""

    config: PlannerConfig
    w: float

    @property
    def walk(self) -> Walk: ...

    @property
    def started(self) -> bool: ...

    @property
    def latest_time(self) -> float: ...

    @property
    def next_replan_phase(self) -> int | None: ...

    def phase_start(self, q: int) -> float: ...

    def state_at_phase_start(self, q: int) -> np.ndarray | list[float]: ...

    def layout_for_replan(self, q: int) -> PlanLayout: ...


class AutoConnection:
    """The auto connection of one planner: decides each change (module docstring) with the planner's own
    operators, and holds the changes that wait for their step's lift-off.

    It changes the planner's walk (:attr:`AutoPlanner.walk`) and nothing else of it: the planner logs the
    :class:`ChangeRecord` that :meth:`change` returns and asks :attr:`next_commit` when to call :meth:`commit`.
    """

    def __init__(self, planner: AutoPlanner) -> None:
        if planner.config.connection == "auto" and not planner.config.timing.uniform:
            # Its predictions assume one timing for every step (the windows of later plans): refuse, not guess.
            raise ValueError("connection 'auto' needs one timing for every step: per-step timings are not supported")
        self.planner = planner
        self.held: dict[int, tuple[float, AutoOption, dict[str, float | None]]] = {}

    def clear(self) -> None:
        """Forget the changes held (the walk is replaced)."""
        self.held.clear()

    @property
    def next_commit(self) -> float:
        """When the next held change is to be applied (s), ``inf`` when none is held."""
        return min((entry[0] for entry in self.held.values()), default=math.inf)

    def change(
        self, step: int, values: dict[str, float | None], through: int | None
    ) -> tuple[int | None, ChangeRecord]:
        """Decide and carry out one change: predict each option, take the first that keeps the margin (else the
        best), apply it to the walk now or hold it until the step lifts off.

        Returns:
            The step whose stride the change sets (``None``: it changed nothing, there is nothing to refresh or
            log) and the record of the decision, for the planner to refresh what depends on the walk and log it.
        """
        planner = self.planner
        walk = planner.walk
        last = step if through is None else through
        with walk.trial():  # every check of a plain change first: a refused change changes nothing
            walk.change_step(step, **values, through=through)
        q = planner.next_replan_phase
        if not planner.started or q is None:
            # Before the walk starts every plan is still to be made; after its last replan none is left to choose.
            first = walk.change_step(step, **values, through=through)
            kind, why = (
                ("quasi-real-time", "before the walk starts")
                if not planner.started
                else ("real-time", "no replan left")
            )
            return first, ChangeRecord(planner.latest_time, step, kind, step, last, planner.latest_time, (), why)
        self.held.pop(step, None)  # a newer wish for the same step replaces the one held
        options = auto_options(step, last, q, walk.n_steps, planner.config.horizon_steps)
        predicted: list[float] = []
        for option in options:  # in order of preference: the first that keeps the margin ends the search
            predicted.append(self.predict(option, values))
            if predicted[-1] >= planner.config.auto_margin:
                break
        decision = choose(options[: len(predicted)], predicted, planner.config.auto_margin)
        option = decision.option
        if option.commit_phase is None:
            walk.change_step(option.step, **values, through=option.through)
            commit = planner.latest_time
        else:
            commit = planner.phase_start(option.commit_phase)
            self.held[step] = (commit, option, values)
        weighed = tuple((o.kind, o.step, m) for o, m in decision.predicted)
        record = ChangeRecord(planner.latest_time, step, option.kind, option.step, option.through, commit, weighed,
                              decision.reason)  # fmt: skip
        return option.step, record

    def commit(self, t: float) -> bool:
        """Apply to the walk the held changes whose step lifts off by ``t`` (s), before anything is sampled at
        ``t``; returns whether any was (the walk under the phase being sampled may then have moved)."""
        applied = False
        for step, (when, option, values) in sorted(self.held.items()):
            if when <= t:
                del self.held[step]
                self.planner.walk.change_step(option.step, **values, through=option.through)
                applied = True
        return applied

    def predict(self, option: AutoOption, values: dict[str, float | None]) -> float:
        """The smallest half-plane ZMP margin (m) of the free segments of the plans in ``option``'s window, made
        from the plan being executed with the footprints the option gives (held changes are not included)."""
        planner = self.planner
        walk, sole, q0 = planner.walk, planner.config.sole, planner.next_replan_phase
        assert sole is not None and q0 is not None
        first, last = option.window
        state = list(planner.state_at_phase_start(q0))
        margin = math.inf
        with walk.trial():
            applied = False
            for p in range(q0, last + 1, 2):
                if p >= first and not applied:  # the plans before `first` are made without it
                    walk.change_step(option.step, **values, through=option.through)
                    applied = True
                layout = planner.layout_for_replan(p)
                sources = walk.relative_anchor_sources(p, layout.anchor_phases)
                y = np.array(state + walk.anchors_from(p >> 1, sources)).reshape(-1, 2)
                if applied:
                    zmp = layout.zmp_rows(AUTO_SAMPLES) @ y
                    halfplanes = polygon_halfplanes(support_polygon(walk.contact_feet(p), sole))
                    margin = min(margin, float(halfplane_margin(zmp, *halfplanes).min()))
                if p + 2 <= last:
                    state = (layout.end_state_rows(1, planner.w) @ y).ravel().tolist()
        return margin


__all__ = [
    "AUTO_KINDS", "AUTO_SAMPLES", "AutoConnection", "AutoDecision", "AutoOption", "AutoPlanner", "ChangeRecord",
    "auto_options", "choose", "window",
]  # fmt: skip
