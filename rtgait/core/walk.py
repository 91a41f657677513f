"""The walk as planned now: footprints, strides, the velocity command and which steps may still change.

This is the bookkeeping half of the online planner (:mod:`rtgait.core.online` does the planning and sampling).
Footprints are numbered as in :mod:`rtgait.core.footsteps`: ``F[0]``, ``F[1]`` the standing feet, ``F[i + 1]``
where step ``i`` (1-based) lands. Strides are relative (each step lands relative to the footprint before it), so
a change of one step moves every later footprint with it.

What may change is decided by the latest phase the planner has reached (:meth:`Walk.reach`), never by an earlier
time sampled later: a committed step stays committed. Step ``k``'s deadline is the start of phase ``2k - 1`` (its
lift-off) in real-time mode and ``2k - 2`` (the double support before it) in quasi-real-time mode. In auto mode
(:mod:`rtgait.core.auto`) a change of step ``k`` is accepted until its lift-off, as in real-time mode, and
:meth:`Walk.deadline_phase` is its *decision* deadline, ``2k - 2``: the last moment at which both connections are
still open, when scheduled changes are handed over.

Memory stays flat on an endless walk: footprints and strides more than ``history_steps`` steps behind the
latest phase are dropped (:attr:`Walk.base` is the index of the oldest footprint kept).
"""

from __future__ import annotations

import contextlib
import itertools
import math
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from rtgait.core.footsteps import (
    Footstep,
    Side,
    Stride,
    Timeline,
    Timing,
    other_side,
    place_step,
    standing_feet,
    stride_between,
)
from rtgait.core.limits import MAX_STEPS

ConnectionMode = str  # "real-time" | "quasi-real-time" | "auto" (see rtgait.core.config.ALL_CONNECTION_MODES)


class StepChangeTooLateError(ValueError):
    """A footstep change arrived after the deadline of the planner's connection mode."""


class CommandClampedWarning(UserWarning):
    """A velocity command asked for steps beyond the configured step limits; they were clamped."""


class StopCancelledWarning(UserWarning):
    """A new walking command arrived after :meth:`Walk.stop`: the walk goes on instead of stopping."""


@dataclass(frozen=True)
class VelocityCommand:
    """Joystick-like walking command: forward (m/s), lateral (m/s, positive left) and yaw rate (rad/s)."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0

    def __post_init__(self) -> None:
        for name in ("vx", "vy", "wz"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"velocity command {name} must be finite, got {getattr(self, name)}")


@dataclass(frozen=True)
class StepLimits:
    """Bounds on the strides made from velocity commands (:meth:`Walk.set_velocity`): forward stride (m), lateral
    displacement per pair of steps (m), heading change per pair of steps (rad), and the narrowest stance a sideways
    walk may close to (m; ``None``: the walk's ``step_width``)."""

    length: float
    lateral: float
    turn: float
    min_width: float | None = None


class Walk:
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
            _check_walk_length(len(self._strides))
            self.command = None
            self.finite = True
        self.standing = standing_feet(step_width, first_side) if feet is None else _check_feet(feet)
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
                strides.append(self._stride_from_command(prints[-1]))
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

    @contextlib.contextmanager
    def trial(self) -> Iterator[Walk]:
        """Changes made inside the block are undone when it ends: for predicting what a change would do."""
        saved = (list(self._strides), list(self._prints), self.base, self.finite, self.command, self.stopping)
        timeline, standing, step_timings = self._timeline, self.standing, self._step_timings
        try:
            yield self
        finally:
            strides, prints, self.base, self.finite, self.command, self.stopping = saved
            self._strides[:], self._prints[:] = strides, prints
            self._timeline, self.standing, self._step_timings = timeline, standing, step_timings

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

    def _is_ending(self) -> bool:
        n = self.n_steps
        return n is not None and self.latest_phase is not None and self.latest_phase >= 2 * n

    def _check_not_ending(self) -> None:
        """From the final double support on, the phases depend on the walk's length: it can no longer change."""
        if self._is_ending():
            raise StepChangeTooLateError("the walk is ending (final double support has begun); start a new walk")

    def _check_open(self, step: int, what: str = "step") -> None:
        if not isinstance(step, int) or isinstance(step, bool) or step < 1:
            raise ValueError(f"{what} must be a 1-based step number, got {step!r}")
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
            raise ValueError(f"through must be a 1-based step number, got {through!r}")
        if last < step:
            raise ValueError(f"through ({through}) must be >= step ({step})")
        self._check_open(step)
        # Check the values before anything is generated: a refused change must change nothing.
        Stride(0.0 if length is None else length, 0.2 if width is None else width, 0.0 if turn is None else turn)
        n = self.n_steps
        if n is not None and last > n:
            raise ValueError(f"step {last} does not exist: the walk has {n} steps")
        if n is None and last - self.first_open_step() > MAX_STEPS:
            raise ValueError(f"through must be within {MAX_STEPS} steps of the first open step, got {last}")
        self.ensure(last + 1)
        old = [self._strides[k - 1 - self.base] for k in range(step, last + 1)]
        new = [
            Stride(
                length=s.length if length is None else length,
                width=s.width if width is None else width,
                turn=s.turn if turn is None else turn,
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
            raise ValueError("set_strides needs at least one stride: the walk's last step is still to come")
        if not all(isinstance(s, Stride) for s in strides):
            raise ValueError("set_strides needs Stride values")
        _check_walk_length(start - 1 + len(strides))
        n = self.n_steps
        if n is not None and start > n + 1:
            raise ValueError(f"from_step {start} leaves a gap after step {n}")
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
            raise ValueError("set_footsteps needs at least one footstep")
        if not all(isinstance(f, Footstep) for f in footsteps):
            raise ValueError("set_footsteps needs Footstep values")
        _check_walk_length(len(footsteps))
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

        The strides are made as :meth:`_stride_from_command` says: ``|vx| <= limits.length / T``,
        ``|vy| <= limits.lateral / 2T`` and ``|wz| <= limits.turn / 2T`` over the step period ``T``. A command
        beyond them is clamped to them, with a :class:`CommandClampedWarning`; a command after :meth:`stop`
        cancels the stop, with a :class:`StopCancelledWarning`.
        """
        self._check_not_ending()
        self._warn_if_clamped(command)
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

    def move_landing(self, step: int, x: float, y: float) -> None:
        """Land ``step`` at ``(x, y)`` (m), keeping its heading: later footprints follow (strides unchanged).

        For step adjustment, which the controller decides past the connection mode's deadline (the robot must
        step there to keep its balance), so no deadline applies; the landing must not have happened yet.
        """
        if self.latest_phase is not None and 2 * step <= self.latest_phase:
            raise StepChangeTooLateError(f"step {step} has already landed")
        stance, old = self.footprint(step), self.footprint(step + 1)
        self._strides[step - 1 - self.base] = stride_between(stance, Footstep(x, y, old.yaw, old.side))
        self._rebuild(step)

    def set_single_support(self, step: int, duration: float) -> None:
        """Give ``step`` (1-based) a single support of ``duration`` (s), keeping its double support: for step
        timing adaptation (:mod:`rtgait.core.stepping`), which no deadline limits; the step must not have landed.
        The later phases shift with it (per-step timing, :class:`~rtgait.core.footsteps.Timeline`)."""
        if self.latest_phase is not None and 2 * step <= self.latest_phase:
            raise StepChangeTooLateError(f"step {step} has already landed")
        if not (math.isfinite(duration) and duration > 0.0):
            raise ValueError(f"single support must be a finite duration > 0 s, got {duration}")
        timeline = self._timeline
        timings = [timeline.step_timing(k) for k in range(1, max(step, len(self._step_timings)) + 1)]
        timings[step - 1] = (float(duration), timings[step - 1][1])
        self._step_timings = tuple(timings)
        self._walk_changed()

    def retarget(self, index: int, footprint: Footstep) -> None:
        """Replace ``F[index]`` by ``footprint`` (where a foot really is); later footprints follow it, their
        strides unchanged."""
        if footprint.side != self.footprint(index).side:
            raise ValueError(f"footprint {index} is a {self.footprint(index).side} foot, got a {footprint.side} one")
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
        self._rebuild(index)

    def restart(self, feet: tuple[Footstep, Footstep] | None = None) -> None:
        """Forget what was reached (a new start); with ``feet``, the walk starts from them: ``(F[0], F[1])``, the
        foot that swings first, then the other. Strides are kept, so the footprints follow the new feet."""
        if feet is not None:
            if self.base:
                raise ValueError("a walk whose history was trimmed cannot start again from new feet")
            self.standing = _check_feet(feet)
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

    def _stride_from_command(self, stance: Footstep) -> Stride:
        """The stride of the next step from ``stance`` under the velocity command, within :attr:`limits`.

        Over a step period ``T`` a command ``(vx, vy, wz)`` asks per step a forward stride ``vx T`` and per pair of
        steps (one by each foot) a lateral displacement ``D = 2 vy T`` and a heading change ``2 wz T``:

        - Forward: every step ``vx T``, within ``+-limits.length``.
        - Sideways: the feet cannot cross, so only the step toward the motion can carry the body sideways: it lands
          ``D`` wider than the step after it, and the two widths are spread evenly around the straight-walking
          stance ``w0``, ``w0 + D/2`` and ``w0 - D/2``, the narrow one never below ``limits.min_width`` (whatever it
          cannot close goes to the wide one). Over a pair of steps the body moves ``D``; the stance opens at most
          ``D/2`` beyond ``w0`` where the robot allows narrowing, instead of ``D`` (the leg's sideways lean and
          the hip's abduction are what limit a sideways walk). ``D <= limits.lateral``.
        - Turning: every step turns ``wz T`` (both feet alike), so the feet alternate between toeing out and in by
          ``wz T`` rather than one foot turning ``2 wz T`` and the other closing: half the angle between the feet
          (their heels or toes, and the hips' yaw, are what limit a turn). ``2 |wz| T <= limits.turn``.
        """
        limits = self.limits
        command = self.command or VelocityCommand()
        period = self.timing.step_period
        landing: Side = other_side(stance.side)
        length = min(max(command.vx * period, -limits.length), limits.length)
        shift = min(2.0 * abs(command.vy) * period, limits.lateral)
        nominal = self.step_width
        narrowest = nominal if limits.min_width is None else min(limits.min_width, nominal)
        narrow = max(nominal - 0.5 * shift, narrowest)
        toward = "left" if command.vy > 0.0 else "right"
        width = narrow + shift if landing == toward else narrow
        half_turn = 0.5 * limits.turn
        turn = min(max(command.wz * period, -half_turn), half_turn)
        return Stride(length=length, width=width, turn=turn)

    def _warn_if_clamped(self, command: VelocityCommand) -> None:
        limits, period = self.limits, self.timing.step_period
        asked = (abs(command.vx) * period, 2.0 * abs(command.vy) * period, 2.0 * abs(command.wz) * period)
        allowed = (limits.length, limits.lateral, limits.turn)
        if any(a > b * (1.0 + 1e-12) for a, b in zip(asked, allowed, strict=True)):
            warnings.warn(
                f"velocity command ({command.vx:g} m/s, {command.vy:g} m/s, {command.wz:g} rad/s) exceeds the step "
                f"limits (step length {limits.length:g} m per {period:g} s step; lateral {limits.lateral:g} m and "
                f"turn {limits.turn:g} rad per pair of steps): clamped",
                CommandClampedWarning,
                stacklevel=3,
            )


def _check_walk_length(steps: int) -> None:
    if steps > MAX_STEPS:
        raise ValueError(f"a walk may have at most {MAX_STEPS} steps, got {steps}")


def _check_feet(feet: tuple[Footstep, Footstep]) -> tuple[Footstep, Footstep]:
    if len(feet) != 2 or not all(isinstance(f, Footstep) for f in feet):
        raise ValueError("feet must be two Footstep values: (the foot that swings first, the other)")
    first, second = feet
    if first.side == second.side:
        raise ValueError("feet must be one left and one right foot")
    distance = math.hypot(first.x - second.x, first.y - second.y)
    if distance > 2.0:
        raise ValueError(f"the standing feet are {distance:.2f} m apart: at most 2 m")
    return first, second


__all__ = [
    "CommandClampedWarning",
    "StepChangeTooLateError",
    "StepLimits",
    "StopCancelledWarning",
    "VelocityCommand",
    "Walk",
]
