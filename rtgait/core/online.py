"""The online planner: a control loop samples it every tick and changes footsteps while the robot walks.

Plans are made only when a double-support phase begins. Each plan covers that double support and the next
``horizon_steps`` steps, is connected to the plan being executed (COG position and velocity, ZMP position and
velocity continuous, see :mod:`rtgait.core.connect`), and costs one precomputed matrix product
(:mod:`rtgait.core.pattern`). Between replans, :meth:`OnlinePlanner.sample` evaluates the closed form.

Connection modes (method.md section 5), for a change of step ``k``:

* ``"real-time"``: accepted until step ``k`` lifts off. The swing foot goes to the new place at once; the COG
  takes the change into account at the double support that follows step ``k``'s touch-down.
* ``"quasi-real-time"``: accepted until the double support before step ``k``'s lift-off begins; the new plan is
  connected there, so the COG has the whole single support of step ``k`` to adapt.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np

from rtgait.core.footsteps import (
    Footstep,
    Side,
    SoleRect,
    Stride,
    Timeline,
    Timing,
    midpoint,
    other_side,
    place_step,
    standing_feet,
    stride_between,
)
from rtgait.core.lipm import GRAVITY, CogTrajectory, omega
from rtgait.core.pattern import DEGREE, MOVING_KINDS, PatternKey, PlanOperator
from rtgait.core.spline import PiecewisePolynomial
from rtgait.core.support import signed_margin, support_polygon
from rtgait.core.swing import swing_pose

ConnectionMode = Literal["real-time", "quasi-real-time"]
CONNECTION_MODES: tuple[ConnectionMode, ConnectionMode] = ("real-time", "quasi-real-time")


class StepChangeTooLateError(ValueError):
    """A footstep change arrived after the deadline of the planner's connection mode."""


@dataclass(frozen=True)
class PlannerConfig:
    """Parameters of the online planner.

    Attributes:
        cog_height: constant COG height above the ground ``zc`` (m).
        timing: phase durations (s).
        step_width: lateral distance between the feet when standing and in straight walking (m).
        step_height: peak swing-foot height (m).
        horizon_steps: steps covered by each plan after its first double support.
        connection: ``"real-time"`` or ``"quasi-real-time"``.
        gravity: (m/s^2).
        first_degree: degree of the free ZMP polynomial of the first segment, 4 (default) or 2.
        first_side: which foot swings first.
        max_step_length, max_step_lateral, max_step_turn: bounds applied to strides made from velocity
            commands (m, m, rad).
    """

    cog_height: float = 0.8
    timing: Timing = field(default_factory=lambda: Timing(0.8, 0.2))
    step_width: float = 0.19
    step_height: float = 0.05
    horizon_steps: int = 3
    connection: ConnectionMode = "real-time"
    gravity: float = GRAVITY
    first_degree: int = 4
    first_side: Side = "right"
    max_step_length: float = 0.3
    max_step_lateral: float = 0.1
    max_step_turn: float = 0.4

    def __post_init__(self) -> None:
        omega(self.cog_height, self.gravity)  # validates both
        if self.connection not in CONNECTION_MODES:
            raise ValueError(f"connection must be one of {CONNECTION_MODES}, got {self.connection!r}")
        if not isinstance(self.horizon_steps, int) or self.horizon_steps < 1:
            raise ValueError(f"horizon_steps must be an integer >= 1, got {self.horizon_steps!r}")
        for name in ("step_width", "max_step_length", "max_step_lateral", "max_step_turn"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value}")
        if not (math.isfinite(self.step_height) and self.step_height >= 0.0):
            raise ValueError(f"step_height must be finite and >= 0 m, got {self.step_height}")


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


SAMPLE_FIELDS = (
    "cog_x", "cog_y", "cog_z", "cog_vx", "cog_vy", "cog_vz", "cog_ax", "cog_ay", "cog_az",
    "zmp_x", "zmp_y", "zmp_ref_x", "zmp_ref_y",
    "lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw", "rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw",
)  # fmt: skip
"""Order of the values in :attr:`GaitSample.values` (SI units, yaw in rad)."""


class GaitSample(NamedTuple):
    """Everything a controller needs at one instant. ``values`` is ordered as :data:`SAMPLE_FIELDS`.

    ``support`` is ``"double"``, ``"left"`` or ``"right"`` (the foot on the ground); ``phase`` the phase index.
    An immutable tuple rather than a dataclass: one is made every control tick, and a tuple is made fastest.
    """

    t: float
    values: np.ndarray
    support: str
    phase: int

    @property
    def cog(self) -> np.ndarray:
        """COG position (m)."""
        return self.values[0:3]

    @property
    def cog_vel(self) -> np.ndarray:
        """COG velocity (m/s)."""
        return self.values[3:6]

    @property
    def cog_acc(self) -> np.ndarray:
        """COG acceleration (m/s^2)."""
        return self.values[6:9]

    @property
    def zmp(self) -> np.ndarray:
        """Planned ZMP on the ground (m)."""
        return self.values[9:11]

    @property
    def zmp_reference(self) -> np.ndarray:
        """ZMP the footsteps alone would ask for (m); differs from :attr:`zmp` in a connecting segment."""
        return self.values[11:13]

    @property
    def left_foot(self) -> np.ndarray:
        """Left foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[13:17]

    @property
    def right_foot(self) -> np.ndarray:
        """Right foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[17:21]


class PlanRecord(NamedTuple):
    """One replanning: when (s), at which phase, the first segment's reference ends, and its cost (s)."""

    t: float
    phase: int
    first_segment_end: float
    n_segments: int
    compute_time: float


EAGER_SEGMENTS = 2
"""Segments evaluated at replan time: the double support that begins and the single support after it. Replans
happen at every double-support start, so later segments are rarely sampled; they are evaluated on first use."""


class _ActivePlan:
    """The plan being executed, in the form the per-tick evaluation reads.

    ``segment(j)`` is ``(x, y)``, each ``[a0..a4, A0..A4, V, W]`` of segment ``j`` as Python floats: scalar
    arithmetic on floats beats numpy calls for one sample.
    """

    __slots__ = ("durations", "first_reference", "layout", "offsets", "phase0", "segments", "t_start", "y")

    def __init__(self, t_start: float, phase0: int, layout: _Layout, y: np.ndarray, first_reference) -> None:
        self.t_start = t_start
        self.phase0 = phase0
        self.layout = layout
        self.y = y
        self.durations = layout.durations
        self.offsets = layout.offsets  # segment starts relative to t_start (s)
        self.first_reference = first_reference  # [axis] -> cubic coefficients of segment 1's reference ZMP
        x_rows, y_rows = (layout.G_eager @ y).T.tolist()
        self.segments: list = [None] * len(layout.durations)
        for j in range(min(EAGER_SEGMENTS, len(self.segments))):
            self.segments[j] = (x_rows[12 * j : 12 * j + 12], y_rows[12 * j : 12 * j + 12])

    def segment(self, j: int) -> tuple[list[float], list[float]]:
        seg = self.segments[j]
        if seg is None:
            seg = self.segments[j] = tuple((self.layout.G[12 * j : 12 * j + 12] @ self.y).T.tolist())
        return seg


class _Layout:
    """What a replan needs to know about one plan shape: its operator and where its anchors come from."""

    __slots__ = ("G", "G_eager", "anchor_phases", "durations", "offsets")

    def __init__(self, operator: PlanOperator, kinds: tuple[str, ...]) -> None:
        self.G = operator.G
        self.G_eager = np.ascontiguousarray(operator.G[: 12 * EAGER_SEGMENTS])
        self.durations = operator.durations.tolist()
        self.offsets = np.concatenate(([0.0], np.cumsum(operator.durations[:-1]))).tolist()
        self.anchor_phases = tuple(k for k, kind in enumerate(kinds) if kind in MOVING_KINDS)


class _PhaseInfo(NamedTuple):
    """The phase being sampled: index, start and end relative to the walk's start (s), support label, the poses
    of the feet on the ground (both, left then right, in double support; the stance foot in single support) and
    the swing foot's start and landing footprints (``None`` in double support)."""

    index: int
    start: float
    end: float
    duration: float
    support: str
    feet: tuple[float, ...]
    swing_from: Footstep | None
    swing_to: Footstep | None


class OnlinePlanner:
    """Walking pattern generator that replans at every double-support start and can change steps on the fly.

    Args:
        config: planner parameters.
        strides: the walk, one stride per step (the last one usually brings the feet side by side); ``None``
            to walk by velocity commands (:meth:`set_velocity`) until :meth:`stop`.

    Typical loop::

        planner = OnlinePlanner(config, strides)
        planner.start(0.0)
        for k in range(n):
            s = planner.sample(k * dt)        # COG, ZMP, feet, support at this tick
            ...                               # feed s to whole-body control
        planner.change_step(5, length=0.15)   # at any time, within the connection mode's deadline
    """

    def __init__(self, config: PlannerConfig, strides: Sequence[Stride] | None = None) -> None:
        self.config = config
        self.w = omega(config.cog_height, config.gravity)
        self._standing = standing_feet(config.step_width, config.first_side)
        self._command: VelocityCommand | None = None
        if strides is None:
            self._command = VelocityCommand()
            self._strides: list[Stride] = []
            self._finite = False
        else:
            self._strides = list(strides)
            if not self._strides:
                raise ValueError("a walk needs at least one stride")
            self._finite = True
        self._prints = [*self._standing]
        self._layouts: dict[tuple[bool, int, bool], _Layout] = {}
        self._plan: _ActivePlan | None = None
        self._next_replan_time = math.inf
        self._t0 = math.nan
        self._time = -math.inf
        self._next_replan_phase: int | None = 0
        self._n = len(self._strides) if self._finite else None
        self._timeline = Timeline(config.timing, self._n)
        self._phase: _PhaseInfo | None = None  # cached facts about the phase last sampled
        self.plans: list[PlanRecord] = []
        self.change_log: list[tuple[float, int]] = []
        """(time, step) of every accepted change."""

    # ----- walk description -------------------------------------------------------------------------------
    @property
    def timeline(self) -> Timeline:
        """Phase boundaries of the walk as planned now (times relative to :attr:`t0`)."""
        return self._timeline

    def _walk_changed(self) -> None:
        """Keep the cached step count and timeline in step with the walk."""
        self._n = n = len(self._strides) if self._finite else None
        if self._timeline.n_steps != n:
            self._timeline = Timeline(self.config.timing, n)
            self._phase = None
            if self.started and self._next_replan_phase is not None:
                self._prepare_layouts(self._next_replan_phase)

    def _plan_span(self, q: int) -> int:
        """Last phase covered by the plan made at double-support phase ``q``."""
        n = self._n
        last = q + 2 * self.config.horizon_steps
        return 2 * n + 1 if n is not None and last >= 2 * n else last

    def _prepare_layouts(self, first_phase: int) -> None:
        """Build the operators of every plan shape still to come, so that no replan pays for one (they cost
        a dense solve, about a millisecond, once per shape)."""
        n = self._n
        last_replan = first_phase + 2 if n is None else 2 * n
        for q in range(first_phase, last_replan + 1, 2):
            self._layout(q, self._plan_span(q))

    @property
    def n_steps(self) -> int | None:
        """Number of steps of the walk, ``None`` while walking by command without a planned end."""
        return self._n

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
        """Footprints ``F[0..]`` (see :mod:`rtgait.core.footsteps`), as planned now."""
        if upto is None:
            upto = len(self._strides) + 1 if self._finite else len(self._prints) - 1
        self._ensure_prints(upto)
        return self._prints[: upto + 1]

    def phase_start(self, q: int) -> float:
        """Absolute start time of phase ``q`` (s)."""
        return self._t0 + self.timeline.start_time(q)

    def change_deadline(self, step: int) -> float:
        """Last absolute time (exclusive) at which a change of ``step`` (1-based) is accepted (s)."""
        phase = 2 * step - 1 if self.config.connection == "real-time" else 2 * step - 2
        return self.phase_start(phase)

    def first_open_step(self) -> int:
        """The first step that may still be changed at the current time."""
        if not self.started or self._time == -math.inf:
            return 1  # nothing sampled yet: even step 1's first plan is still to be made
        q = self.timeline.phase_at(max(self._time - self._t0, 0.0))
        # Step k's deadline is the start of phase 2k - 1 (real-time) or 2k - 2 (quasi-real-time); the current
        # phase q has started, so the open steps are those whose deadline phase lies after q.
        return (q + 1) // 2 + 1 if self.config.connection == "real-time" else q // 2 + 2

    def _ensure_prints(self, index: int) -> None:
        """Make sure ``F[index]`` exists, generating strides from the velocity command if needed."""
        while len(self._prints) <= index:
            step = len(self._prints) - 1
            if step > len(self._strides):
                if self._finite:
                    break
                self._strides.append(self._stride_from_command(step, self._prints[-1]))
            self._prints.append(place_step(self._prints[-1], self._strides[step - 1]))

    def _rebuild_prints(self, from_step: int) -> None:
        """Recompute the footprints that follow a change of ``from_step`` (``F[from_step + 1]`` on)."""
        self._phase = None  # the swing target of the phase being sampled may have moved
        known = len(self._prints) - 1
        del self._prints[from_step + 1 :]
        self._ensure_prints(known)

    def _stride_from_command(self, step: int, stance: Footstep) -> Stride:
        cfg, cmd = self.config, self._command or VelocityCommand()
        period = cfg.timing.step_period
        landing: Side = other_side(stance.side)
        toward = 1.0 if landing == "left" else -1.0
        length = min(max(cmd.vx * period, -cfg.max_step_length), cfg.max_step_length)
        # Only the foot on the side of motion opens the stance (or the turn); the other closes it again, so two
        # steps move the body by twice the per-step displacement without crossing the feet.
        lateral = min(max(2.0 * cmd.vy * period * toward, 0.0), cfg.max_step_lateral)
        turn = min(max(2.0 * cmd.wz * period * toward, 0.0), cfg.max_step_turn)
        return Stride(length=length, width=cfg.step_width + lateral, turn=turn * toward)

    # ----- changes --------------------------------------------------------------------------------------
    def _check_open(self, step: int) -> None:
        if not isinstance(step, int) or step < 1:
            raise ValueError(f"step must be a 1-based step number, got {step!r}")
        if self._finite and step > len(self._strides):
            raise ValueError(f"step {step} does not exist: the walk has {len(self._strides)} steps")
        if self.started and step < self.first_open_step():
            raise StepChangeTooLateError(
                f"step {step} can no longer change at t={self._time:.3f} s in {self.config.connection} mode "
                f"(deadline {self.change_deadline(step):.3f} s)"
            )

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

        Values not given are kept. Later footprints move with it (each lands relative to its predecessor).
        Raises :class:`StepChangeTooLateError` past the connection mode's deadline.
        """
        last = step if through is None else through
        if last < step:
            raise ValueError(f"through ({through}) must be >= step ({step})")
        self._check_open(step)
        if self._finite and last > len(self._strides):
            raise ValueError(f"step {last} does not exist: the walk has {len(self._strides)} steps")
        self._ensure_prints(last + 1)
        for k in range(step, last + 1):
            old = self._strides[k - 1]
            self._strides[k - 1] = Stride(
                length=old.length if length is None else length,
                width=old.width if width is None else width,
                turn=old.turn if turn is None else turn,
            )
        self._rebuild_prints(step)
        self.change_log.append((self._time, step))

    def _check_not_ending(self) -> None:
        """The phases from the final double support on depend on the walk's length: once the robot is in
        them, the length of the walk can no longer change."""
        n = self._n
        walking = n is not None and self.started and self._time != -math.inf
        if walking and self._timeline.phase_at(max(self._time - self._t0, 0.0)) >= 2 * n:
            raise StepChangeTooLateError("the walk is ending (final double support has begun); start a new walk")

    def set_strides(self, strides: Sequence[Stride], from_step: int | None = None) -> None:
        """Replace the walk from ``from_step`` (default: the first open step) on; the walk ends after them."""
        self._check_not_ending()
        start = self.first_open_step() if from_step is None else from_step
        if not isinstance(start, int) or start < 1:
            raise ValueError(f"from_step must be a 1-based step number, got {start!r}")
        if self.started and start < self.first_open_step():
            raise StepChangeTooLateError(f"step {start} can no longer change in {self.config.connection} mode")
        self._ensure_prints(start)
        if start > len(self._strides) + 1:
            raise ValueError(f"from_step {start} leaves a gap after step {len(self._strides)}")
        if not strides:
            raise ValueError("set_strides needs at least one stride: the walk's last step is still to come")
        self._strides = self._strides[: start - 1] + list(strides)
        self._finite = True
        self._command = None
        self._walk_changed()
        self._rebuild_prints(start)
        self.change_log.append((self._time, start))

    def set_footsteps(self, footsteps: Sequence[Footstep]) -> None:
        """Replace the walk by absolute landing footprints for steps 1..N (the first ones may already be walked:
        those must match what was walked, within 1 mm)."""
        if not footsteps:
            raise ValueError("set_footsteps needs at least one footstep")
        first_open = self.first_open_step()
        prints = self.footprints(max(first_open, 1))
        chain = list(self._standing)
        for i, landing in enumerate(footsteps, start=1):
            if i < first_open:
                walked = prints[i + 1]
                if math.hypot(walked.x - landing.x, walked.y - landing.y) > 1e-3 or walked.side != landing.side:
                    raise StepChangeTooLateError(f"footstep {i} is already committed and cannot move")
            chain.append(landing)
        strides = [stride_between(a, b) for a, b in itertools.pairwise(chain[1:])]
        self.set_strides(strides[first_open - 1 :], from_step=first_open)

    def set_velocity(self, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0) -> None:
        """Walk by command: forward and lateral speed (m/s), yaw rate (rad/s); open steps follow it."""
        command = VelocityCommand(vx, vy, wz)
        self._check_not_ending()
        self._command = command
        start = self.first_open_step()
        self._ensure_prints(start)
        del self._strides[start - 1 :]
        self._finite = False
        self._walk_changed()
        self._rebuild_prints(start)
        self.change_log.append((self._time, start))

    def stop(self) -> None:
        """End the walk: the first open step brings the feet side by side, then the COG comes to rest.

        Calling it again once the closing step is committed changes nothing, so a control loop may keep
        sending "stop"."""
        start = self.first_open_step()
        if self._n is not None and self._n < start:
            return
        self._ensure_prints(start)
        self.set_strides([Stride(0.0, self.config.step_width, 0.0)], from_step=start)

    # ----- planning ---------------------------------------------------------------------------------------
    def start(self, t0: float = 0.0) -> None:
        """Begin the walk at absolute time ``t0`` (s), standing still with the COG between the feet."""
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {t0}")
        self._t0 = float(t0)
        self._time = -math.inf
        self._phase = None
        self._plan = None
        self.plans.clear()
        self._next_replan_phase = 0  # the first plan is made by the first sample, like every later one
        self._next_replan_time = self._t0
        self._prepare_layouts(0)

    def _layout(self, first: int, last: int) -> _Layout:
        """Operator and anchor bookkeeping for the plan over phases ``first..last`` (cached by plan shape)."""
        n = self.n_steps
        # The phase kinds of a plan depend only on these three facts, so they key the cache cheaply.
        shape = (first == 0, last - first, n is not None and last == 2 * n + 1)
        layout = self._layouts.get(shape)
        if layout is None:
            timeline = self._timeline
            kinds = tuple(timeline.kind(q) for q in range(first, last + 1))
            key = PatternKey(
                kinds=kinds,
                durations=tuple(timeline.duration(q) for q in range(first, last + 1)),
                w=self.w,
                first_degree=self.config.first_degree,
            )
            layout = self._layouts[shape] = _Layout(PlanOperator(key), kinds)
        return layout

    def _anchors(self, q: int, layout: _Layout) -> list[float]:
        """Where the reference ZMP is at the end of each double support of a plan starting at phase ``q`` (m).

        After double support ``2i`` it rests on footprint ``F[i + 1]``; after the final one, between the feet.
        Returned flat: ``[x_0, y_0, x_1, y_1, ...]``.
        """
        n, prints = self._n, self._prints
        anchors = []
        for k in layout.anchor_phases:
            i = (q + k) >> 1
            if i == n:
                anchors.extend(midpoint(prints[n], prints[n + 1]))
            else:
                foot = prints[i + 1]
                anchors.append(foot.x)
                anchors.append(foot.y)
        return anchors

    def _current_state(self, q: int) -> list[float]:
        """``[p0x, p0y, dp0x, dp0y, c0x, c0y, dc0x, dc0y]`` at the start of phase ``q`` (m, m/s).

        The state comes from the plan being executed; the ZMP is its left limit (the end of the segment before).
        """
        if self._plan is None:
            cx, cy = midpoint(*self._standing)
            return [cx, cy, 0.0, 0.0, cx, cy, 0.0, 0.0]
        plan = self._plan
        j = q - 1 - plan.phase0
        tau = plan.durations[j]
        w = self.w
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        state = [0.0] * 8
        for axis, coeffs in enumerate(plan.segment(j)):
            a0, a1, a2, a3, a4, A0, A1, A2, A3, A4, V, W = coeffs
            state[axis] = a0 + tau * (a1 + tau * (a2 + tau * (a3 + tau * a4)))
            state[2 + axis] = a1 + tau * (2.0 * a2 + tau * (3.0 * a3 + tau * 4.0 * a4))
            state[4 + axis] = V * ch + W * sh + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4)))
            state[6 + axis] = w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4))
        return state

    def _replan(self) -> None:
        """Make and connect the plan of the double support that begins now (phase ``_next_replan_phase``)."""
        began = time.perf_counter()
        q = self._next_replan_phase
        assert q is not None
        n = self._n
        last = self._plan_span(q)
        if len(self._prints) < last // 2 + 3:
            self._ensure_prints(last // 2 + 2)
        layout = self._layout(q, last)
        state = self._current_state(q)
        y = state + self._anchors(q, layout)
        # Reference of the free segment: the cubic transfer the footsteps alone would ask for.
        duration = layout.durations[0]
        k2, k3 = 3.0 / duration**2, -2.0 / duration**3
        px, py, ax, ay = y[0], y[1], y[8], y[9]
        reference = ((px, 0.0, k2 * (ax - px), k3 * (ax - px)), (py, 0.0, k2 * (ay - py), k3 * (ay - py)))
        t_start = self._t0 + self._timeline.start_time(q)
        self._plan = _ActivePlan(t_start, q, layout, np.array(y).reshape(-1, 2), reference)
        if n is None or q + 2 <= 2 * n:
            self._next_replan_phase = q + 2
            self._next_replan_time = self.phase_start(q + 2)
        else:
            self._next_replan_phase, self._next_replan_time = None, math.inf
        elapsed = time.perf_counter() - began
        self.plans.append(PlanRecord(t_start, q, t_start + duration, len(layout.durations), elapsed))

    def _advance(self, t: float) -> None:
        """Replan at every double-support start up to ``t``, each from the state of the plan before it."""
        while self._next_replan_phase is not None and self.phase_start(self._next_replan_phase) <= t:
            self._replan()

    @property
    def current_plan(self) -> CogTrajectory:
        """The plan being executed as a :class:`CogTrajectory` (for analysis; sampling does not need it)."""
        if self._plan is None:
            raise RuntimeError("no plan yet: call start() and sample()")
        plan = self._plan
        data = (plan.layout.G @ plan.y).reshape(len(plan.durations), 12, 2)  # (m, 12, axes)
        zmp = PiecewisePolynomial(plan.t_start, np.array(plan.durations), data[:, : DEGREE + 1])
        return CogTrajectory(zmp=zmp, V=data[:, -2], W=data[:, -1], w=self.w)

    # ----- sampling -------------------------------------------------------------------------------------
    def sample(self, t: float) -> GaitSample:
        """COG (pos, vel, acc), ZMP, reference ZMP, feet poses and support at absolute time ``t`` (s)."""
        values, support, phase = self.sample_values(t)
        return GaitSample(t, np.array(values), support, phase)

    def sample_values(self, t: float) -> tuple[list[float], str, int]:
        """As :meth:`sample` but returns plain floats in :data:`SAMPLE_FIELDS` order (for tight loops)."""
        if t >= self._next_replan_time:
            self._advance(t)
        plan = self._plan
        if plan is None or not t >= plan.t_start:  # also rejects NaN
            if not self.started:
                raise RuntimeError("call start() before sample()")
            raise ValueError(f"t={t} s is before the plan being executed (starts at {self._earliest()} s)")
        self._time = t
        rel = t - self._t0
        phase = self._phase
        if phase is None or not phase.start <= rel < phase.end:
            phase = self._phase = self._phase_info(rel)
        q = phase.index
        j = q - plan.phase0
        if j < 0:  # t on a phase boundary, rounded to the phase before the plan's first
            j = 0
        elif j >= len(plan.durations):
            j = len(plan.durations) - 1
        tau = t - plan.t_start - plan.offsets[j]
        if tau > plan.durations[j]:  # past the end of the walk: hold the final state
            tau = plan.durations[j]
        w = self.w
        e = math.exp(w * tau)
        ch, sh = 0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e)
        out = [0.0] * 21
        out[2] = self.config.cog_height
        for axis, coeffs in enumerate(plan.segment(j)):
            a0, a1, a2, a3, a4, A0, A1, A2, A3, A4, V, W = coeffs
            hom = V * ch + W * sh
            out[axis] = hom + A0 + tau * (A1 + tau * (A2 + tau * (A3 + tau * A4)))
            out[3 + axis] = w * (V * sh + W * ch) + A1 + tau * (2.0 * A2 + tau * (3.0 * A3 + tau * 4.0 * A4))
            out[6 + axis] = w * w * hom + 2.0 * A2 + tau * (6.0 * A3 + tau * 12.0 * A4)
            zmp = a0 + tau * (a1 + tau * (a2 + tau * (a3 + tau * a4)))
            out[9 + axis] = zmp
            if j == 0:
                r0, r1, r2, r3 = plan.first_reference[axis]
                out[11 + axis] = r0 + tau * (r1 + tau * (r2 + tau * r3))
            else:
                out[11 + axis] = zmp
        if phase.swing_from is None:
            out[13:21] = phase.feet
        else:
            swing = swing_pose(
                phase.swing_from, phase.swing_to, (rel - phase.start) / phase.duration, self.config.step_height
            )
            if phase.support == "left":
                out[13:17], out[17:21] = phase.feet, swing
            else:
                out[13:17], out[17:21] = swing, phase.feet
        return out, phase.support, q

    def _earliest(self) -> float:
        return self._t0 if self._plan is None else self._plan.t_start

    def _phase_info(self, rel: float) -> _PhaseInfo:
        """What sampling needs to know about the phase containing ``rel`` (s from the start of the walk)."""
        timeline = self._timeline
        q = timeline.phase_at(rel)
        start = timeline.start_time(q)
        last = timeline.last_phase
        end = math.inf if q == last else timeline.start_time(q + 1)
        prints = self._prints
        if q & 1 and timeline.kind(q) == "single":
            i = (q + 1) >> 1
            stance = prints[i]
            pose = (stance.x, stance.y, 0.0, stance.yaw)
            return _PhaseInfo(q, start, end, end - start, stance.side, pose, prints[i - 1], prints[i + 1])
        i = min(q >> 1, len(prints) - 2)
        a, b = (prints[i], prints[i + 1]) if prints[i].side == "left" else (prints[i + 1], prints[i])
        feet = (a.x, a.y, 0.0, a.yaw, b.x, b.y, 0.0, b.yaw)
        return _PhaseInfo(q, start, end, end - start, "double", feet, None, None)

    def zmp_margin(self, sample: GaitSample, sole: SoleRect) -> float:
        """Signed distance (m) of the sample's planned ZMP to its support polygon; negative = outside."""
        polygon = support_polygon(self.contact_feet(sample.phase), sole)
        return float(signed_margin(sample.zmp, polygon)[0])

    def contact_feet(self, q: int) -> list[Footstep]:
        """Footprints on the ground during phase ``q``."""
        timeline = self.timeline
        self._ensure_prints(q // 2 + 2)
        if q % 2 == 1 and timeline.kind(q) == "single":
            return [self._prints[(q + 1) // 2]]
        i = min(q // 2, len(self._prints) - 2)
        return [self._prints[i], self._prints[i + 1]]


def straight_walk(config: PlannerConfig, steps: int, step_length: float) -> list[Stride]:
    """Strides of a straight walk: ``steps`` steps of ``step_length`` (m), then one closing the feet."""
    if not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    return [Stride(step_length, config.step_width)] * steps + [Stride(0.0, config.step_width)]


__all__ = [
    "CONNECTION_MODES",
    "SAMPLE_FIELDS",
    "GaitSample",
    "OnlinePlanner",
    "PlanRecord",
    "PlannerConfig",
    "StepChangeTooLateError",
    "VelocityCommand",
    "straight_walk",
]
