"""The online planner: a control loop samples it every tick and changes footsteps while the robot walks.

Plans are made when a double-support phase begins (the paper's replanning) and, when the controller asks, at any
instant (:meth:`OnlinePlanner.replan_now`). Each plan covers the phase under way and the next ``horizon_steps``
steps, is connected to the plan being executed (ZMP position and velocity continuous, COG position and velocity
continuous or, with ``feedback="measured"``, starting from the measured COG state; see
:mod:`rtgait.core.lipm.connect` and ``docs/closed_loop.md``), and costs one precomputed matrix product
(:mod:`rtgait.core.lipm.pattern`). Between replans, :meth:`OnlinePlanner.sample` evaluates the closed form.

Connection modes (method.md section 5), for a change of step ``k``:

* ``"real-time"``: accepted until step ``k`` lifts off. The swing foot goes to the new place at once; the COG
  takes the change into account at the double support that follows step ``k``'s touch-down.
* ``"quasi-real-time"``: accepted until the double support before step ``k``'s lift-off begins; the new plan is
  connected there, so the COG has the whole single support of step ``k`` to adapt.
* ``"auto"``: accepted until step ``k`` lifts off; each change is decided when it arrives, by predicting its ZMP
  margin with the plan operators: the real-time connection if it keeps the margin, else the quasi-real-time one
  while its deadline has not passed, else the change moves to a later step (:mod:`rtgait.core.planner.auto`). Every
  decision, with the predictions and the reason, is in :attr:`OnlinePlanner.change_log`.

The walk's footprints, strides, velocity command and deadlines live in :class:`~rtgait.core.walk.walk.Walk`. The
planner's methods are in seven modules: this one makes plans (and the replans sampling triggers);
:mod:`rtgait.core.planner.sampling` samples them (the per-tick path, :meth:`OnlinePlanner.sample_values`);
:mod:`rtgait.core.planner.planner_walk` tells of the walk and takes the changes; :mod:`rtgait.core.planner.measured`
plans from the measured state; :mod:`rtgait.core.planner.adjusting` adjusts steps after a replan;
:mod:`rtgait.core.planner.layouts` builds the plan shapes ahead; :mod:`rtgait.core.planner.bounded` checks the
closed-loop calls' arguments and undoes a refused call.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Sequence

import numpy as np

from rtgait.core.geometry.footsteps import Footstep, Stride, check_step_timings, midpoint
from rtgait.core.input_bounds import MAX_TIME, MAX_TURN, InputOutOfBoundsError, check_footstep
from rtgait.core.laws.stepping import StepDecision
from rtgait.core.limits import MAX_STEPS
from rtgait.core.lipm.closed_form import omega
from rtgait.core.lipm.pattern import MOVING_KINDS, PatternKey
from rtgait.core.planner.active_plan import ActivePlan, PlanLayout, height_column
from rtgait.core.planner.adjusting import StepAdjusting
from rtgait.core.planner.auto import AutoConnection, ChangeRecord
from rtgait.core.planner.bounded import BoundedCalls, measured_pair
from rtgait.core.planner.config import (
    ALL_CONNECTION_MODES,
    CONNECTION_MODES,
    FEEDBACK_MODES,
    ConnectionMode,
    FeedbackMode,
    PlannerConfig,
)
from rtgait.core.planner.layouts import PlanShapes
from rtgait.core.planner.measured import MeasuredPlanning
from rtgait.core.planner.planner_walk import PlannerWalk
from rtgait.core.planner.sample import SAMPLE_FIELDS, GaitSample, PlanRecord, SampleColumns, SampleValues
from rtgait.core.planner.sampling import PlanSampling
from rtgait.core.walk.changes import StepChangeTooLateError, StopCancelledWarning
from rtgait.core.walk.phases import PhaseInfo, SwingRetarget
from rtgait.core.walk.velocity_command import CommandClampedWarning, StepLimits, VelocityCommand
from rtgait.core.walk.walk import Walk


class OnlinePlanner(PlannerWalk, MeasuredPlanning, StepAdjusting, PlanShapes, BoundedCalls, PlanSampling):
    """Walking pattern generator that replans at every double-support start and can change steps on the fly.

    Args:
        config: planner parameters.
        strides: the walk, one stride per step (the last one usually brings the feet side by side); ``None``
            to walk by velocity commands (:meth:`set_velocity`) until :meth:`stop`. At most
            :data:`~rtgait.core.limits.MAX_STEPS` steps.

    Typical loop::

        planner = OnlinePlanner(config, strides)
        planner.start(0.0)
        for k in range(n):
            s = planner.sample(k * dt)        # COG, ZMP, DCM, feet, support at this tick
            ...                               # feed s to whole-body control
        planner.change_step(5, length=0.15)   # at any time, within the connection mode's deadline

    Closing the loop (``docs/closed_loop.md``): ``start(t0, feet=..., cog=..., cog_vel=...)`` from where the robot
    stands, ``observe(t, cog, cog_vel)`` every tick, ``touchdown(t, side, x, y, yaw)`` at each landing, and with
    ``PlannerConfig(feedback="measured")`` every new plan starts from the measured COG state.

    Samples may be asked for in any order within the plan being executed; what is committed (which steps may
    still change) is decided by the latest time sampled. One call replans at most
    :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` times: sample at least once per step.

    Every argument of the closed-loop calls is checked against its bound (:mod:`rtgait.core.input_bounds`,
    ``docs/closed_loop.md``) before anything changes: a refused call raises
    :class:`~rtgait.core.input_bounds.InputOutOfBoundsError` (a ``ValueError``) naming the argument and the bound, or
    :class:`StepChangeTooLateError` past a deadline, and leaves the planner exactly as it was. Calls out of order
    (``sample`` or ``touchdown`` before :meth:`start`, ``replan_now`` before the first sample) raise
    ``RuntimeError``: a programming error, not a measurement.
    """

    def __init__(self, config: PlannerConfig, strides: Sequence[Stride] | None = None) -> None:
        if not isinstance(config, PlannerConfig):
            raise ValueError(f"config must be a PlannerConfig, got {type(config).__name__}")
        self.config = config
        self.w = omega(config.cog_height, config.gravity)
        self._init_bounds()
        check_step_timings(config.timing, self.w)
        self._walk = Walk(
            config.timing,
            config.connection,
            config.step_width,
            StepLimits(config.max_step_length, config.max_step_lateral, config.max_step_turn, config.min_step_width),
            strides,
            first_side=config.first_side,
            history_steps=config.history_steps,
        )
        self._layouts: dict[tuple, PlanLayout] = {}
        self._layout_at: dict[int, PlanLayout] = {}  # the layout of each regular replan still to come, by phase
        self._prepared: tuple | None = None  # (first phase, timeline, config) _layout_at was prepared for
        self._midphase_layouts: dict[PatternKey, PlanLayout] = {}
        self._plan: ActivePlan | None = None
        self._next_replan_time = math.inf
        self._next_replan_phase: int | None = 0
        self._t0 = math.nan
        self._latest = -math.inf
        self._phase: PhaseInfo | None = None  # cached facts about the phase last sampled
        self._start_state: list[float] | None = None
        self._observed: tuple[float, float, float, float, float] | None = None
        self._observed_on_plan: tuple | None = None  # (plan, t, its COG state then) from observe's DCM check
        history = config.history_steps
        self.plans: deque[PlanRecord] = deque(maxlen=history)
        """Every replanning, oldest first (the last ``history_steps`` of them)."""
        self.change_log: deque[ChangeRecord] = deque(maxlen=history)
        """Every accepted change, oldest first (the last ``history_steps`` of them): when it arrived, the step it
        asked for, how it is connected and, in auto mode, the predictions and the reason
        (:class:`~rtgait.core.planner.auto.ChangeRecord`; its first two fields are ``(time, step)``)."""
        self._auto = AutoConnection(self)  # the auto connection's decisions and held changes
        self._commit_time = math.inf  # earliest commit of a held (auto, real-time) change
        self.replan_count = 0
        """Replannings since :meth:`start` (not bounded by the history)."""
        self.step_adjustments: deque[StepDecision] = deque(maxlen=history)
        """Every step adjustment (:mod:`rtgait.core.laws.stepping`), oldest first."""
        self.step_adjustment_count = 0
        """Step adjustments since :meth:`start`."""
        self._swing_retarget: tuple[int, SwingRetarget] | None = None  # the last swing whose landing moved
        self._last_auto_replan = -math.inf

    # ----- planning ---------------------------------------------------------------------------------------
    def start(
        self,
        t0: float = 0.0,
        *,
        feet: tuple[Footstep, Footstep] | None = None,
        cog: Sequence[float] | None = None,
        cog_vel: Sequence[float] | None = None,
    ) -> None:
        """Begin the walk at absolute time ``t0`` (s).

        Args:
            feet: the measured standing feet, ``(left, right)`` as :class:`Footstep`s at any position and heading
                (within :data:`~rtgait.core.input_bounds.MAX_POSITION` of the origin, headings within
                :data:`~rtgait.core.input_bounds.MAX_YAW`, at most 2 m apart, turned less than a quarter turn from
                each other); default: side by side at the origin heading +x. The walk heads where the feet point:
                strides and velocity commands are relative to them.
            cog: the measured horizontal COG position (m), within reach of the feet (``docs/closed_loop.md``);
                default: between the feet.
            cog_vel: the measured horizontal COG velocity (m/s), below the speed bound; default: at rest.

        The first plan starts with the ZMP under the COG (at rest, they coincide).
        """
        if not abs(t0) <= MAX_TIME:  # also refuses NaN
            raise InputOutOfBoundsError(f"t0 must be finite and within +-{MAX_TIME:g} s, got {t0}")
        walk = self._walk
        if feet is not None:
            left, right = feet
            if not (isinstance(left, Footstep) and isinstance(right, Footstep)):
                raise InputOutOfBoundsError("feet must be two Footstep values (left, right)")
            if left.side != "left" or right.side != "right":
                raise InputOutOfBoundsError(f"feet must be (left, right), got ({left.side}, {right.side})")
            for foot in (left, right):
                check_footstep(f"feet ({foot.side})", foot)
            if not abs(math.remainder(left.yaw - right.yaw, math.tau)) < MAX_TURN:
                raise InputOutOfBoundsError(
                    f"feet must be turned less than {MAX_TURN:.4f} rad from each other, got yaws {left.yaw} and "
                    f"{right.yaw}"
                )
            ordered = (left, right) if self.config.first_side == "left" else (right, left)
        else:
            ordered = None
        c = measured_pair("cog", cog, None)
        v = measured_pair("cog_vel", cog_vel, (0.0, 0.0))
        if c is not None or v != (0.0, 0.0):
            self._check_com(c if c is not None else midpoint(*(ordered or walk.standing)), v, ordered or walk.standing)
        walk.restart(ordered)  # after every check: a refused start changes nothing
        if c is None:
            c = midpoint(*walk.standing)
        self._start_state = [c[0], c[1], 0.0, 0.0, c[0], c[1], v[0], v[1]]
        self._t0 = float(t0)
        self._latest = -math.inf
        self._phase = None
        self._plan = None
        self._observed = None
        self._observed_on_plan = None
        self._reach = None
        self.plans.clear()
        self.replan_count = 0
        self._replaced()
        self._next_replan_phase = 0  # the first plan is made by the first sample, like every later one
        self._next_replan_time = self._t0
        self._prepared = None
        self._prepare_layouts(0)

    @property
    def next_replan_phase(self) -> int | None:
        """The phase whose start makes the next regular plan (a double support), ``None`` when no replan is left."""
        return self._next_replan_phase

    def state_at_phase_start(self, q: int) -> np.ndarray | list[float]:
        """``[p0x, p0y, dp0x, dp0y, c0x, c0y, dc0x, dc0y]`` at the start of phase ``q`` (m, m/s): where a plan made
        then starts from.

        The state comes from the plan being executed; the ZMP is its left limit (the end of the segment before).
        """
        if self._plan is None:
            return list(self._start_state or [0.0] * 8)
        plan = self._plan
        return plan.end_state(q - 1 - plan.phase0, self.w)

    def _connect(self, t_start: float, q: int, layout: PlanLayout, state: list[float], elapsed: float) -> None:
        """Make the plan of ``layout`` from ``state`` at ``t_start`` (``elapsed`` s into phase ``q``)."""
        sources = layout.anchor_sources
        if sources is None:
            sources = layout.anchor_sources = self._walk.relative_anchor_sources(q, layout.anchor_phases)
        anchors = self._walk.anchors_from(q >> 1, sources)
        y = np.array([*state, *anchors])  # one conversion of Python floats, then viewed as (inputs, axes)
        y.shape = (4 + len(sources), 2)
        # Reference of the free segment: the cubic transfer the footsteps alone would ask for over the whole
        # phase (for a plan made mid-phase: the one of the plan made when the phase began). Python floats: the
        # samples of the segment evaluate it.
        px, py, ax, ay = float(state[0]), float(state[1]), anchors[0], anchors[1]
        offset = 0.0
        previous = self._plan
        if elapsed == 0.0 and layout.first_kind in MOVING_KINDS:
            k2, k3 = layout.transfer
            reference = ((px, 0.0, k2 * (ax - px), k3 * (ax - px)), (py, 0.0, k2 * (ay - py), k3 * (ay - py)))
        elif layout.first_kind in MOVING_KINDS and previous is not None and previous.phase0 == q:
            reference, offset = previous.first_reference, elapsed
        else:
            reference = ((ax, 0.0, 0.0, 0.0), (ay, 0.0, 0.0, 0.0))
        self._plan = ActivePlan(
            t_start, q, layout, y, reference, offset, elapsed, self._height_column(t_start, q, sources)
        )

    def _height_column(self, t_start: float, q: int, sources) -> np.ndarray | None:
        """The vertical column of a plan starting at ``t_start`` in phase ``q`` (:func:`height_column`)."""
        heights = self._walk.heights_from(q >> 1, sources)
        return height_column(self._plan, t_start, self.w, heights, len(sources), self._walk.standing)

    def _replan(self, t: float) -> None:
        """Make and connect the plan of the double support that begins now (phase ``_next_replan_phase``), for
        the sample at ``t`` (s)."""
        began = time.perf_counter()
        q = self._next_replan_phase
        assert q is not None
        n = self.n_steps
        # Prepared in start() (and again whenever the walk's length or timing changes): a lookup, not a build.
        layout = self._layout_at.pop(q, None) or self._layout(q, self._plan_span(q))
        state = self.state_at_phase_start(q)
        t_start = self._next_replan_time
        planned = None
        if self.config.feedback == "measured":
            if self.config.step_adjustment is not None:
                planned = list(state)  # step adjustment may fall back to the planned state
            self._measured_cog(t_start, state)
        self._connect(t_start, q, layout, state, 0.0)
        if n is None or q + 2 <= 2 * n:
            self._next_replan_phase = q + 2
            self._next_replan_time = self.phase_start(q + 2)
        else:
            self._next_replan_phase, self._next_replan_time = None, math.inf
        self._record(t_start, q, layout, began, "start" if q == 0 else "double-support")
        if self.config.step_adjustment is not None:
            self._adjust_step(t, planned, self.config.step_adjustment)

    def _record(self, t_start: float, q: int, layout: PlanLayout, began: float, reason: str) -> None:
        elapsed = time.perf_counter() - began
        end = t_start + layout.durations[0]
        self.plans.append(PlanRecord(t_start, q, end, len(layout.durations), elapsed, reason))
        self.replan_count += 1

    def _catch_up(self, t: float) -> None:
        """Before sampling ``t`` (s): commit the held changes whose step has lifted off and replan at every
        double-support start up to ``t``, each from the state of the plan before it; ``t`` checked first
        (:meth:`_check_time`: at most :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` replans)."""
        self._check_time("t", t)
        if t >= self._commit_time:
            if self._auto.commit(t):
                self._phase = None  # the swing target of the phase being sampled may have moved
            self._commit_time = self._auto.next_commit
        while self._next_replan_time <= t:
            self._replan(t)


def straight_walk(config: PlannerConfig, steps: int, step_length: float) -> list[Stride]:
    """Strides of a straight walk: ``steps`` steps of ``step_length`` (m), then one closing the feet."""
    if not isinstance(steps, int) or isinstance(steps, bool) or not 1 <= steps < MAX_STEPS:
        raise ValueError(f"steps must be an integer in 1..{MAX_STEPS - 1}, got {steps!r}")
    return [Stride(step_length, config.step_width)] * steps + [Stride(0.0, config.step_width)]


__all__ = [
    "ALL_CONNECTION_MODES",
    "CONNECTION_MODES",
    "FEEDBACK_MODES",
    "SAMPLE_FIELDS",
    "CommandClampedWarning",
    "ConnectionMode",
    "FeedbackMode",
    "GaitSample",
    "InputOutOfBoundsError",
    "OnlinePlanner",
    "PlanRecord",
    "PlannerConfig",
    "SampleColumns",
    "SampleValues",
    "StepChangeTooLateError",
    "StopCancelledWarning",
    "VelocityCommand",
    "straight_walk",
]
