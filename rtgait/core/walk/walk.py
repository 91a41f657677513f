"""The walk as planned now: footprints, strides, the velocity command and which steps may still change.

This is the bookkeeping half of the online planner (:mod:`rtgait.core.planner.online` does the planning and sampling).
Footprints are numbered as in :mod:`rtgait.core.geometry.footsteps`: ``F[0]``, ``F[1]`` the standing feet, ``F[i + 1]``
where step ``i`` (1-based) lands. Strides are relative (each step lands relative to the footprint before it), so
a change of one step moves every later footprint with it.

What may change is decided by the latest phase the planner has reached (:meth:`Walk.reach`), never by an earlier
time sampled later: a committed step stays committed. Step ``k``'s deadline is the start of phase ``2k - 1`` (its
lift-off) in real-time mode and ``2k - 2`` (the double support before it) in quasi-real-time mode. In auto mode
(:mod:`rtgait.core.planner.auto`) a change of step ``k`` is accepted until its lift-off, as in real-time mode, and
:meth:`Walk.deadline_phase` is its *decision* deadline, ``2k - 2``: the last moment at which both connections are
still open, when scheduled changes are handed over.

Memory stays flat on an endless walk: footprints and strides more than ``history_steps`` steps behind the
latest phase are dropped (:attr:`Walk.base` is the index of the oldest footprint kept).

This module keeps what the planner reads (footprints, anchors, the timeline, deadlines: some of it on every new
phase); the changes (:meth:`Walk.change_step`, :meth:`Walk.set_velocity`, ...) are in
:mod:`rtgait.core.walk.changes`, and how a velocity command becomes strides in :mod:`rtgait.core.walk.velocity_command`.
"""

from __future__ import annotations

from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep, Side, Stride, Timeline, Timing, place_step, standing_feet
from rtgait.core.geometry.support_height import stance_support_height
from rtgait.core.walk.changes import (
    StepChangeTooLateError,
    StopCancelledWarning,
    WalkChanges,
    check_feet,
    check_walk_length,
)
from rtgait.core.walk.velocity_command import CommandClampedWarning, StepLimits, VelocityCommand, stride_from_command

ConnectionMode = str  # "real-time" | "quasi-real-time" | "auto" (see rtgait.core.planner.config.ALL_CONNECTION_MODES)


class Walk(WalkChanges):
    """Footprints, strides and the velocity command of one walk, and the deadlines of changes to it.

    Args:
        timing: phase durations (s).
        connection: ``"real-time"``, ``"quasi-real-time"`` or ``"auto"``: which deadline applies to a change.
        step_width: lateral distance between the feet when standing and in straight walking (m).
        limits: bounds on strides made from velocity commands.
        strides: one stride per step, or ``None`` to walk by velocity command until :meth:`stop`.
        feet: the standing feet ``(F[0], F[1])``: the foot that swings first, then the other; default side by
            side at the origin, heading +x, ``first_side`` swinging first.
        first_side: which foot swings first when ``feet`` is not given.
        history_steps: footprints kept behind the latest phase (``None``: all).

    Steps keep their own timing (``timing.per_step``) through every change of their strides; a walk by velocity
    command is uniform: it ignores ``per_step``, and :meth:`set_velocity` drops the per-step timing of the steps
    it replaces.
    """

    def __init__(
        self,
        timing: Timing,
        connection: ConnectionMode,
        step_width: float,
        limits: StepLimits,
        strides: Sequence[Stride] | None,
        *,
        feet: tuple[Footstep, Footstep] | None = None,
        first_side: Side = "right",
        history_steps: int | None = None,
    ) -> None:
        self.timing = timing
        self.connection = connection
        self.step_width = step_width
        self.limits = limits
        self.history_steps = history_steps
        if strides is None:
            self.command: VelocityCommand | None = VelocityCommand()
            self._strides: list[Stride] = []
            self.finite = False
        else:
            self._strides = list(strides)
            if not self._strides:
                raise ValueError("a walk needs at least one stride")
            check_walk_length(len(self._strides))
            self.command = None
            self.finite = True
        self.standing = standing_feet(step_width, first_side) if feet is None else check_feet(feet)
        self.base = 0  # F index of _prints[0]; _strides[0] is the stride of step base + 1
        self._prints: list[Footstep] = [*self.standing]
        self.latest_phase: int | None = None
        self.stopping = False
        self._step_timings: tuple[tuple[float, float], ...] = timing.per_step if self.finite else ()
        self._timeline = Timeline(timing, self.n_steps, self._step_timings)

    # ----- what the walk is -------------------------------------------------------------------------------
    @property
    def n_steps(self) -> int | None:
        """Number of steps, ``None`` while walking by command without a planned end."""
        return self.base + len(self._strides) if self.finite else None

    @property
    def timeline(self) -> Timeline:
        """Phase boundaries of the walk as planned now (s from its start)."""
        return self._timeline

    def footprint(self, index: int) -> Footstep:
        """``F[index]``, generating footprints from the velocity command if needed."""
        i = index - self.base
        prints = self._prints
        if 0 <= i < len(prints):
            return prints[i]
        if i < 0:
            raise IndexError(f"footprint {index} is no longer kept (history_steps = {self.history_steps})")
        self.ensure(index)
        if i >= len(self._prints):
            raise IndexError(f"footprint {index} does not exist: the walk has {self.n_steps} steps")
        return self._prints[i]

    def footprints(self, upto: int | None = None) -> list[Footstep]:
        """Footprints ``F[base..upto]`` (default: to the last one of a finite walk, or the last made so far)."""
        if upto is None:
            upto = self.n_steps + 1 if self.finite else self.base + len(self._prints) - 1
        self.ensure(upto)
        return self._prints[: upto + 1 - self.base]

    def stride(self, step: int) -> Stride:
        """The stride of ``step`` (1-based) as planned now."""
        self.ensure(step + 1)
        return self._strides[step - 1 - self.base]

    def ensure(self, index: int) -> None:
        """Make sure ``F[index]`` exists if the walk has it, generating strides from the velocity command."""
        prints, strides = self._prints, self._strides
        while self.base + len(prints) <= index:
            step = self.base + len(prints) - 1  # the step that lands on the next footprint
            if step > self.base + len(strides):
                if self.finite:
                    break
                strides.append(
                    stride_from_command(prints[-1], self.command, self.limits, self.timing.step_period, self.step_width)
                )
            prints.append(place_step(prints[-1], strides[step - 1 - self.base]))

    def contact_feet(self, q: int) -> list[Footstep]:
        """Footprints on the ground during phase ``q``."""
        if q % 2 == 1 and self._timeline.kind(q) == "single":
            return [self.footprint((q + 1) // 2)]
        n = self.n_steps
        i = q // 2 if n is None else min(q // 2, n)
        return [self.footprint(i), self.footprint(i + 1)]

    def anchor_sources(self, q: int, anchor_phases: Sequence[int]) -> list[tuple[int, int]]:
        """The footprints the reference ZMP rests on at the end of each anchor phase ``q + k`` of a plan: ``(i, i)``
        for ``F[i]``, ``(n, n + 1)`` for the point between the final feet.

        At the end of a double support ``2i`` it rests on ``F[i + 1]`` (the next stance foot); at the end of a
        single support ``2i - 1`` on its own stance foot ``F[i]``; from the final double support on, between the
        final feet.
        """
        n = self.n_steps
        sources = []
        for k in anchor_phases:
            p = q + k
            if (p & 1 == 0 and p >> 1 == n) or (n is not None and p == 2 * n + 1):
                sources.append((n, n + 1))
            else:
                i = (p >> 1) + 1 if p & 1 == 0 else (p + 1) >> 1
                sources.append((i, i))
        return sources

    def anchors(self, q: int, anchor_phases: Sequence[int]) -> list[float]:
        """Where the reference ZMP rests at the end of each anchor phase (:meth:`anchor_sources`), flat:
        ``[x_0, y_0, x_1, y_1, ...]`` (m)."""
        return self.anchors_from(q >> 1, self.relative_anchor_sources(q, anchor_phases))

    def relative_anchor_sources(self, q: int, anchor_phases: Sequence[int]) -> tuple[tuple[int, int], ...]:
        """:meth:`anchor_sources` relative to ``F[q // 2]``: the same for every plan of one shape, so a plan layout
        can keep it."""
        i0 = q >> 1
        return tuple((a - i0, b - i0) for a, b in self.anchor_sources(q, anchor_phases))

    def anchors_from(self, i0: int, relative: Sequence[tuple[int, int]]) -> list[float]:
        """Anchors ``[x_0, y_0, ...]`` (m) from sources relative to ``F[i0]`` (:meth:`relative_anchor_sources`)."""
        last = i0 + relative[-1][1]
        prints = self._prints
        if self.base + len(prints) <= last:
            self.ensure(last)
        start = i0 - self.base
        anchors = []
        for a, b in relative:
            fa = prints[start + a]
            if a == b:
                anchors += (fa.x, fa.y)
            else:
                fb = prints[start + b]
                anchors += (0.5 * (fa.x + fb.x), 0.5 * (fa.y + fb.y))
        return anchors

    def heights_from(self, i0: int, relative: Sequence[tuple[int, int]]) -> list[float] | None:
        """The support heights (m) under the anchors of :meth:`anchors_from`, ``None`` when all are 0 (level
        ground: the plan needs no vertical column): a stance foothold's height, lowered before a step down
        (:func:`~rtgait.core.geometry.support_height.stance_support_height`; a finite walk knows every landing, a
        walk by command the ones made so far), or the mean of the final feet's."""
        if self.finite:  # every stance's landing is known: make it, so the rule does not hang on what was made
            self.ensure(i0 + max(a for a, _ in relative) + 1)
        prints = self._prints
        start = i0 - self.base
        last = len(prints) - 1
        heights = []
        for a, b in relative:
            fa = prints[start + a]
            if a == b:
                landing = prints[start + a + 1] if start + a < last else None  # where the swing from F[a] lands
                heights.append(stance_support_height(fa, landing))
            else:
                heights.append(0.5 * (fa.z + prints[start + b].z))
        return heights if any(heights) else None

    # ----- deadlines ---------------------------------------------------------------------------------------
    def first_open_step(self) -> int:
        """The first step that may still be changed, given the latest phase reached."""
        q = self.latest_phase
        if q is None:
            return 1  # nothing sampled yet: even step 1's first plan is still to be made
        # The current phase q has started, so the open steps are those whose deadline phase lies after it.
        return (q + 1) // 2 + 1 if self.connection in ("real-time", "auto") else q // 2 + 2

    def deadline_phase(self, step: int) -> int:
        """The phase whose start is the deadline of a change of ``step`` (exclusive); in auto mode the decision
        deadline (module docstring), the change itself being accepted until ``2 step - 1``."""
        return 2 * step - 1 if self.connection == "real-time" else 2 * step - 2

    def reach(self, q: int) -> None:
        """The planner has reached phase ``q``: what it committed stays committed. Old history is dropped."""
        if self.latest_phase is not None and q <= self.latest_phase:
            return
        self.latest_phase = q
        keep = self.history_steps
        if keep is not None and q // 2 - self.base > 2 * keep:
            drop = q // 2 - keep - self.base
            del self._prints[:drop]
            del self._strides[: min(drop, len(self._strides))]
            self.base += drop


__all__ = [
    "CommandClampedWarning",
    "StepChangeTooLateError",
    "StepLimits",
    "StopCancelledWarning",
    "VelocityCommand",
    "Walk",
]
