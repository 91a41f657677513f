"""Changing a walk: the edits of :class:`~rtgait.core.walk.walk.Walk`'s strides, footprints, command and step timing.

:class:`~rtgait.core.walk.walk.Walk` takes these methods from :class:`WalkChanges` (a mixin, like the online planner's
:class:`~rtgait.core.planner.measured.MeasuredPlanning`): each validates everything before it changes anything (a
refused change changes nothing), applies the deadline of the walk's connection mode
(:meth:`Walk.first_open_step <rtgait.core.walk.walk.Walk.first_open_step>`; module docstring of
:mod:`rtgait.core.walk.walk`), then recomputes the footprints after the first step changed. Strides are relative, so a
change of step ``k`` moves ``F[k + 1]`` and every later footprint. :meth:`WalkChanges.trial` undoes the changes made
inside a block, for predictions.

Two kinds of change have no deadline, being the controller's answer to a disturbance:
:meth:`~WalkChanges.move_landing` (step adjustment) and :meth:`~WalkChanges.set_single_support` (step timing
adaptation); they only need the step not to have landed yet. :meth:`~WalkChanges.retarget` replaces a footprint
by where the foot really is.

The mixin reads and writes the walk's state (its strides, footprints, history base, timeline); it has no state of
its own and is not meant to be used alone.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import warnings
from collections.abc import Iterator, Sequence
from typing import TypeVar

from rtgait.core.geometry.footsteps import Footstep, Stride, Timeline, stride_between
from rtgait.core.input_bounds import InputOutOfBoundsError, check_footstep
from rtgait.core.limits import MAX_STEPS
from rtgait.core.walk.velocity_command import VelocityCommand, warn_if_clamped

_Changes = TypeVar("_Changes", bound="WalkChanges")  # the walk the mixin is part of


class StepChangeTooLateError(ValueError):
    """A footstep change arrived after the deadline of the planner's connection mode."""


class StopCancelledWarning(UserWarning):
    """A new walking command arrived after :meth:`~rtgait.core.walk.walk.Walk.stop`: the walk goes on instead of
    stopping."""


class WalkChanges:
    """The change methods of :class:`~rtgait.core.walk.walk.Walk` (see the module docstring)."""

    # ----- undo, and the deadlines' checks -----------------------------------------------------------------
    @contextlib.contextmanager
    def trial(self: _Changes) -> Iterator[_Changes]:
        """Changes made inside the block are undone when it ends: for predicting what a change would do."""
        saved = self.snapshot()
        try:
            yield self
        finally:
            self.restore(saved)

    def snapshot(self) -> tuple:
        """Everything a change or :meth:`reach` may alter, for :meth:`restore` (lists copied, the rest immutable)."""
        return (
            list(self._strides), list(self._prints), self.base, self.finite, self.command, self.stopping,
            self._timeline, self.standing, self._step_timings, self.latest_phase,
        )  # fmt: skip

    def restore(self, saved: tuple) -> None:
        """Put the walk back as :meth:`snapshot` saw it."""
        strides, prints, self.base, self.finite, self.command, self.stopping = saved[:6]
        self._strides[:], self._prints[:] = strides, prints
        self._timeline, self.standing, self._step_timings, self.latest_phase = saved[6:]

    def _is_ending(self) -> bool:
        n = self.n_steps
        return n is not None and self.latest_phase is not None and self.latest_phase >= 2 * n

    def _check_not_ending(self) -> None:
        """From the final double support on, the phases depend on the walk's length: it can no longer change."""
        if self._is_ending():
            raise StepChangeTooLateError("the walk is ending (final double support has begun); start a new walk")

    def _check_open(self, step: int, what: str = "step") -> None:
        if not isinstance(step, int) or isinstance(step, bool) or step < 1:
            raise InputOutOfBoundsError(f"{what} must be a 1-based step number, got {step!r}")
        if step < self.first_open_step():
            raise StepChangeTooLateError(
                f"step {step} can no longer change in {self.connection} mode (first open step: "
                f"{self.first_open_step()})"
            )

    # ----- changes (each validates everything before it changes anything) ---------------------------------
    def change_step(
        self,
        step: int,
        *,
        length: float | None = None,
        width: float | None = None,
        turn: float | None = None,
        through: int | None = None,
    ) -> int:
        """Change the stride of ``step`` (and of every step up to ``through``). Returns the first step changed.

        Values not given are kept. Of two changes of the same step, the later one wins (an online planner is told
        its user's latest wish).
        """
        last = step if through is None else through
        if not isinstance(last, int) or isinstance(last, bool):
            raise InputOutOfBoundsError(f"through must be a 1-based step number, got {through!r}")
        if last < step:
            raise InputOutOfBoundsError(f"through ({through}) must be >= step ({step})")
        self._check_open(step)
        # Check the values before anything is generated: a refused change must change nothing.
        Stride(0.0 if length is None else length, 0.2 if width is None else width, 0.0 if turn is None else turn)
        n = self.n_steps
        if n is not None and last > n:
            raise InputOutOfBoundsError(f"step {last} does not exist: the walk has {n} steps")
        if n is None and last - self.first_open_step() > MAX_STEPS:
            raise InputOutOfBoundsError(f"through must be within {MAX_STEPS} steps of the first open step, got {last}")
        self.ensure(last + 1)
        old = [self._strides[k - 1 - self.base] for k in range(step, last + 1)]
        new = [
            Stride(
                length=s.length if length is None else length,
                width=s.width if width is None else width,
                turn=s.turn if turn is None else turn,
                rise=s.rise,  # a changed length or heading keeps the step's height and surface
                pitch=s.pitch,
                roll=s.roll,
            )
            for s in old
        ]
        self._strides[step - 1 - self.base : last - self.base] = new
        self._rebuild(step)
        return step

    def set_strides(self, strides: Sequence[Stride], from_step: int | None = None) -> int:
        """Replace the walk from ``from_step`` (default: the first open step) on; the walk ends after them."""
        self._check_not_ending()
        start = self.first_open_step() if from_step is None else from_step
        self._check_open(start, "from_step")
        strides = list(strides)
        if not strides:
            raise InputOutOfBoundsError("set_strides needs at least one stride: the walk's last step is still to come")
        if not all(isinstance(s, Stride) for s in strides):
            raise InputOutOfBoundsError("set_strides needs Stride values")
        check_walk_length(start - 1 + len(strides))
        n = self.n_steps
        if n is not None and start > n + 1:
            raise InputOutOfBoundsError(f"from_step {start} leaves a gap after step {n}")
        self.ensure(start)  # a walk by command: make its strides up to there
        self._strides[start - 1 - self.base :] = strides
        self.finite = True
        self.command = None
        self.stopping = False
        self._walk_changed()
        self._rebuild(start)
        return start

    def set_footsteps(self, footsteps: Sequence[Footstep]) -> int:
        """Replace the walk by absolute landing footprints for steps 1..N.

        The first ones may already be committed: those must match the walk within 1 mm (those no longer kept in
        the history are not checked). Raises :class:`StepChangeTooLateError` when none of them is still open.
        """
        footsteps = list(footsteps)
        if not footsteps:
            raise InputOutOfBoundsError("set_footsteps needs at least one footstep")
        if not all(isinstance(f, Footstep) for f in footsteps):
            raise InputOutOfBoundsError("set_footsteps needs Footstep values")
        for k, footstep in enumerate(footsteps):
            check_footstep(f"footsteps[{k}]", footstep)
        check_walk_length(len(footsteps))
        self._check_not_ending()
        first_open = self.first_open_step()
        if first_open > len(footsteps):
            raise StepChangeTooLateError(
                f"all {len(footsteps)} footsteps are already committed (first open step: {first_open})"
            )
        for i in range(max(1, self.base), first_open):
            walked = self.footprint(i + 1)
            landing = footsteps[i - 1]
            if math.hypot(walked.x - landing.x, walked.y - landing.y) > 1e-3 or walked.side != landing.side:
                raise StepChangeTooLateError(f"footstep {i} is already committed and cannot move")
        # Strides are relative: the open steps start from the committed footprint before them.
        chain = [self.footprint(first_open), *footsteps[first_open - 1 :]]
        strides = [stride_between(a, b) for a, b in itertools.pairwise(chain)]
        return self.set_strides(strides, from_step=first_open)

    def set_velocity(self, command: VelocityCommand) -> int:
        """Walk by command from the first open step on (forward/lateral speed m/s, yaw rate rad/s).

        The strides are made as :func:`~rtgait.core.walk.velocity_command.stride_from_command` says:
        ``|vx| <= limits.length / T``, ``|vy| <= limits.lateral / 2T`` and ``|wz| <= limits.turn / 2T`` over the
        step period ``T``, the squares of the three shares adding up to at most 1. A command beyond is scaled down
        onto that ellipsoid (:func:`~rtgait.core.walk.velocity_command.clamp_command`), with a
        :class:`~rtgait.core.walk.velocity_command.CommandClampedWarning`; a command after :meth:`stop` cancels the
        stop, with a :class:`StopCancelledWarning`.
        """
        self._check_not_ending()
        warn_if_clamped(command, self.limits, self.timing.step_period)
        if self.stopping:
            warnings.warn("set_velocity after stop(): the walk goes on", StopCancelledWarning, stacklevel=3)
        start = self.first_open_step()
        self.ensure(start)
        self.command = command
        del self._strides[start - 1 - self.base :]
        self.finite = False
        self.stopping = False
        self._step_timings = self._step_timings[: start - 1]  # steps by command are uniform
        self._walk_changed()
        self._rebuild(start)
        return start

    def stop(self) -> int | None:
        """End the walk: the first open step brings the feet side by side, then the COG comes to rest.

        Returns the closing step, or ``None`` when the walk already ends at or before the first open step (then
        nothing changes, so a control loop may keep sending "stop").
        """
        start = self.first_open_step()
        n = self.n_steps
        if n is not None and n < start:
            return None
        self.set_strides([Stride(0.0, self.step_width, 0.0)], from_step=start)
        self.stopping = True
        return start

    def move_landing(self, step: int, x: float, y: float, surface: tuple[float, float, float] | None = None) -> None:
        """Land ``step`` at ``(x, y)`` (m), keeping its heading: later footprints follow (strides unchanged).

        For step adjustment, which the controller decides past the connection mode's deadline (the robot must
        step there to keep its balance), so no deadline applies; the landing must not have happened yet. The
        landing keeps its height, pitch and roll, or takes ``surface`` ``(z, pitch, roll)`` (m, rad): the terrain's
        under its new place (:func:`~rtgait.core.geometry.terrain_landing.land_on_terrain`).
        """
        if self.latest_phase is not None and 2 * step <= self.latest_phase:
            raise StepChangeTooLateError(f"step {step} has already landed")
        stance, old = self.footprint(step), self.footprint(step + 1)
        z, pitch, roll = (old.z, old.pitch, old.roll) if surface is None else surface
        self._strides[step - 1 - self.base] = stride_between(stance, Footstep(x, y, old.yaw, old.side, z, pitch, roll))
        self._rebuild(step)

    def set_single_support(self, step: int, duration: float) -> None:
        """Give ``step`` (1-based) a single support of ``duration`` (s), keeping its double support: for step
        timing adaptation (:mod:`rtgait.core.laws.stepping`), which no deadline limits; the step must not have landed.
        The later phases shift with it (per-step timing, :class:`~rtgait.core.geometry.footsteps.Timeline`)."""
        if self.latest_phase is not None and 2 * step <= self.latest_phase:
            raise StepChangeTooLateError(f"step {step} has already landed")
        if not (math.isfinite(duration) and duration > 0.0):
            raise InputOutOfBoundsError(f"single support must be a finite duration > 0 s, got {duration}")
        timeline = self._timeline
        timings = [timeline.step_timing(k) for k in range(1, max(step, len(self._step_timings)) + 1)]
        timings[step - 1] = (float(duration), timings[step - 1][1])
        self._step_timings = tuple(timings)
        self._walk_changed()

    def retarget(self, index: int, footprint: Footstep) -> None:
        """Replace ``F[index]`` by ``footprint`` (where a foot really is); later footprints follow it, their
        strides unchanged, except after a foothold on sloped ground (``footprint`` pitched or rolled): there
        ``F[index + 1]`` and the rest stay where they were placed, the next stride taking up the difference.

        On a slope a foothold's height and tilt are those of the ground where it was placed: carried along the
        slope by the landings' errors it keeps them where the ground has others (``d tan(a)`` higher or lower for
        ``d`` along a ramp of angle ``a``), and at the slope's end a foothold planned level ends up with its heel or
        toe on the ramp. G1 landing 4 to 8 mm short at every step down ``slope-down-g1``'s ramp carried the level
        foothold after it 57 mm back, its heel on the ramp's last 6 cm: the sole stood on its heel edge and rolled
        back. A foothold on level ground (the floor, a stair tread) keeps its height where it moves, and the
        footprints after it follow it, as on the flat floor."""
        if footprint.side != self.footprint(index).side:
            raise InputOutOfBoundsError(
                f"footprint {index} is a {self.footprint(index).side} foot, got a {footprint.side} one"
            )
        if index < 2:
            standing = list(self.standing)
            standing[index] = footprint
            self.standing = (standing[0], standing[1])
        elif index - 1 >= self.base and index - 2 - self.base >= 0:
            # Keep the strides a record of what was walked: the step that landed here took this stride (unless the
            # measured feet cross, which no Stride can describe; the footprint itself is what counts).
            with contextlib.suppress(ValueError):
                self._strides[index - 2 - self.base] = stride_between(self._prints[index - 1 - self.base], footprint)
        self._prints[index - self.base] = footprint
        following = index + 1 - self.base
        if (footprint.pitch or footprint.roll) and index - 1 - self.base >= 0 and following < len(self._prints):
            # The next stride from where the foot is to the next foothold, kept in place (the walk's own feet
            # cannot cross there unless the landing crossed them: then the stride stays and it follows).
            with contextlib.suppress(ValueError):
                self._strides[index - 1 - self.base] = stride_between(footprint, self._prints[following])
        self._rebuild(max(index, 1))  # F[1] does not follow F[0]: both stand where they were measured

    def restart(self, feet: tuple[Footstep, Footstep] | None = None) -> None:
        """Forget what was reached (a new start); with ``feet``, the walk starts from them: ``(F[0], F[1])``, the
        foot that swings first, then the other. Strides are kept, so the footprints follow the new feet. A walk whose
        first footprints are no longer kept (:attr:`base` > 0) cannot start again: its first strides are gone."""
        if self.base:
            raise InputOutOfBoundsError(
                f"a walk whose history was trimmed (history_steps = {self.history_steps}) cannot start again: "
                f"make a new planner"
            )
        if feet is not None:
            self.standing = check_feet(feet)
            del self._prints[2:]
            self._prints[0:2] = self.standing
            self._rebuild(1)
        self.latest_phase = None

    # ----- internals ---------------------------------------------------------------------------------------
    def _walk_changed(self) -> None:
        n = self.n_steps
        timeline = self._timeline
        if timeline.n_steps != n or timeline.step_timings is not self._step_timings:
            self._timeline = Timeline(self.timing, n, self._step_timings)

    def _rebuild(self, from_step: int) -> None:
        """Recompute the footprints after a change of ``from_step`` (``F[from_step + 1]`` on)."""
        known = self.base + len(self._prints) - 1
        del self._prints[from_step + 1 - self.base :]
        self.ensure(known)


def check_walk_length(steps: int) -> None:
    if steps > MAX_STEPS:
        raise InputOutOfBoundsError(f"a walk may have at most {MAX_STEPS} steps, got {steps}")


def check_feet(feet: tuple[Footstep, Footstep]) -> tuple[Footstep, Footstep]:
    if len(feet) != 2 or not all(isinstance(f, Footstep) for f in feet):
        raise InputOutOfBoundsError("feet must be two Footstep values: (the foot that swings first, the other)")
    first, second = feet
    if first.side == second.side:
        raise InputOutOfBoundsError("feet must be one left and one right foot")
    distance = math.hypot(first.x - second.x, first.y - second.y)
    if distance > 2.0:
        raise InputOutOfBoundsError(f"the standing feet are {distance:.2f} m apart: at most 2 m")
    return first, second


__all__ = ["StepChangeTooLateError", "StopCancelledWarning", "WalkChanges", "check_feet", "check_walk_length"]
