"""The online planner's walk: what it tells of the walk under way and the changes it accepts while walking.

:class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from :class:`PlannerWalk` (a mixin, like
:class:`~rtgait.core.planner.measured.MeasuredPlanning` and :class:`~rtgait.core.planner.layouts.PlanShapes`): the
walk's queries (:class:`WalkQueries`, which :class:`~rtgait.core.analysis.preview.PreviewPlanner` shares): footprints,
phase start times (absolute, s: the walk's start time :attr:`~PlannerWalk.t0` plus the timeline's), change deadlines and
the first step still open, all read from the planner's :class:`~rtgait.core.walk.walk.Walk`; and the changes
(:meth:`~PlannerWalk.change_step`, :meth:`~PlannerWalk.set_strides`, :meth:`~PlannerWalk.set_footsteps`,
:meth:`~PlannerWalk.set_velocity`, :meth:`~PlannerWalk.stop`), each made on the walk (:mod:`rtgait.core.walk.changes`,
which checks the deadline), then the planner's state that depends on it is refreshed (the cached phase, the plan layouts
prepared ahead) and the change is logged (:attr:`~rtgait.core.planner.online.OnlinePlanner.change_log`). In auto mode
:meth:`~PlannerWalk.change_step` hands the change to the auto connection (:mod:`rtgait.core.planner.auto`), which
decides it.

The per-tick path (:meth:`~rtgait.core.planner.online.OnlinePlanner.sample_values`) reads only
:attr:`~PlannerWalk.timeline`
of these, when a new phase begins (the replan that may follow reads :attr:`~PlannerWalk.n_steps` and
:meth:`~PlannerWalk.phase_start`). The mixin reads and writes the planner's state; it has no state of its own and is
not meant to be used alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rtgait.core.geometry.footsteps import Footstep, Stride, Timeline
from rtgait.core.planner.auto import ChangeRecord
from rtgait.core.walk.velocity_command import VelocityCommand
from rtgait.core.walk.walk import Walk


class WalkQueries:
    """What a planner tells of its walk, read from its :class:`~rtgait.core.walk.walk.Walk` (``self._walk``) and its
    start time (``self._t0``, s): shared by :class:`~rtgait.core.planner.online.OnlinePlanner` (through
    :class:`PlannerWalk`) and :class:`~rtgait.core.analysis.preview.PreviewPlanner`."""

    _walk: Walk
    _t0: float

    @property
    def walk(self) -> Walk:
        """Footprints, strides, command and deadlines (changed through the planner's methods)."""
        return self._walk

    @property
    def timeline(self) -> Timeline:
        """Phase boundaries of the walk as planned now (times relative to :attr:`t0`)."""
        return self._walk.timeline

    @property
    def n_steps(self) -> int | None:
        """Number of steps of the walk, ``None`` while walking by command without a planned end."""
        return self._walk.n_steps

    @property
    def started(self) -> bool:
        return math.isfinite(self._t0)

    @property
    def t0(self) -> float:
        """Absolute time of the start of the walk (s)."""
        return self._t0

    @property
    def end_time(self) -> float:
        """Absolute time at which the walk has come to rest (s); ``inf`` while walking by command."""
        return self._t0 + self.timeline.end_time

    def footprints(self, upto: int | None = None) -> list[Footstep]:
        """Footprints ``F[0..]`` (see :mod:`rtgait.core.geometry.footsteps`), as planned now.

        On a walk longer than ``history_steps`` the oldest are no longer kept: the list then starts at
        ``F[planner.walk.base]``.
        """
        return self._walk.footprints(upto)

    def phase_start(self, q: int) -> float:
        """Absolute start time of phase ``q`` (s)."""
        return self._t0 + self.timeline.start_time(q)

    def change_deadline(self, step: int) -> float:
        """Last absolute time (exclusive) at which a change of ``step`` (1-based) is accepted (s); in auto mode, at
        which both connections are still open (the change itself is accepted until the step lifts off)."""
        return self.phase_start(self._walk.deadline_phase(step))

    def first_open_step(self) -> int:
        """The first step that may still be changed, given the latest time sampled."""
        return self._walk.first_open_step()

    def contact_feet(self, q: int) -> list[Footstep]:
        """Footprints on the ground during phase ``q``."""
        return self._walk.contact_feet(q)


class PlannerWalk(WalkQueries):
    """The walk methods of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring): the queries of
    :class:`WalkQueries`, the latest time sampled and the changes."""

    @property
    def latest_time(self) -> float:
        """The latest time sampled (s); ``-inf`` before the first sample."""
        return self._latest

    # ----- changes ----------------------------------------------------------------------------------------
    def _changed(self, step: int | None, record: ChangeRecord | None = None) -> None:
        """After any change of the walk: refresh what depends on it and log it."""
        self._phase = None  # the swing target of the phase being sampled may have moved
        if step is None:
            return
        if self.started and self._next_replan_phase is not None:
            self._prepare_layouts(self._next_replan_phase)  # no-op unless the walk's length changed
        if record is None:
            record = ChangeRecord(self._latest, step, self.config.connection, step, step, self._latest, (), "")
        self.change_log.append(record)

    def _replaced(self) -> None:
        """The walk is replaced (set_strides, set_footsteps, set_velocity, stop): pending changes are dropped."""
        self._auto.clear()
        self._commit_time = math.inf

    def change_step(
        self,
        step: int,
        *,
        length: float | None = None,
        width: float | None = None,
        turn: float | None = None,
        through: int | None = None,
    ) -> None:
        """Change the stride of ``step`` (and of every step up to ``through``, inclusive) while walking.

        Values not given are kept; of two changes of one step the later wins. Later footprints move with it (each
        lands relative to its predecessor). Raises :class:`StepChangeTooLateError` past the connection mode's
        deadline; a refused change changes nothing. In auto mode the change is decided here
        (:mod:`rtgait.core.planner.auto`): applied now, deferred to a later step, or held until step ``step`` lifts off.
        """
        with self._atomic():
            if self.config.connection == "auto":
                first, record = self._auto.change(step, {"length": length, "width": width, "turn": turn}, through)
                self._commit_time = self._auto.next_commit
                self._changed(first, record)
                return
            self._changed(self._walk.change_step(step, length=length, width=width, turn=turn, through=through))

    def set_strides(self, strides: Sequence[Stride], from_step: int | None = None) -> None:
        """Replace the walk from ``from_step`` (default: the first open step) on; the walk ends after them."""
        with self._atomic():
            self._replaced()
            self._changed(self._walk.set_strides(strides, from_step))

    def set_footsteps(self, footsteps: Sequence[Footstep]) -> None:
        """Replace the walk by absolute landing footprints for steps 1..N (the first ones may already be walked:
        those must match what was walked, within 1 mm). Raises :class:`StepChangeTooLateError` when every one
        of them is committed."""
        with self._atomic():
            self._replaced()
            self._changed(self._walk.set_footsteps(footsteps))

    def set_velocity(self, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0) -> None:
        """Walk by command: forward and lateral speed (m/s), yaw rate (rad/s); open steps follow it.

        Commands beyond ``max_step_*`` per step are clamped with a :class:`CommandClampedWarning`; a command after
        :meth:`stop` cancels the stop with a :class:`StopCancelledWarning`."""
        command = VelocityCommand(vx, vy, wz)
        with self._atomic():
            self._replaced()
            self._changed(self._walk.set_velocity(command))

    def stop(self) -> None:
        """End the walk: the first open step brings the feet side by side, then the COG comes to rest.

        Calling it again once the closing step is committed changes nothing, so a control loop may keep
        sending "stop"."""
        with self._atomic():
            self._replaced()
            self._changed(self._walk.stop())


__all__ = ["PlannerWalk"]
