"""Planning from the robot: the part of the online planner that listens to the measured state.

:class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from :class:`MeasuredPlanning` (a mixin, so that
the per-tick path stays one object with no indirection): ``observe`` (the measured COG state, and a replan by itself
when the DCM error grows), ``touchdown`` (re-anchoring on a real foothold), ``replan_now`` (a plan whose free first
segment is the remainder of the phase under way) and the connection from the measured state; step adjustment after a
replan is :mod:`rtgait.core.planner.adjusting`'s. The equations are in ``docs/closed_loop.md``.

The mixin reads and writes the planner's state (the plan under way, the walk, the phase being sampled); it has no
state of its own and is not meant to be used alone.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Literal

from rtgait.core.geometry.foot_tilt import surface_rise
from rtgait.core.geometry.footsteps import SIDES, Footstep, Side
from rtgait.core.input_bounds import MAX_YAW, InputOutOfBoundsError, check_position
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.lipm.pattern import PatternKey, PlanOperator
from rtgait.core.planner.active_plan import PlanLayout
from rtgait.core.planner.config import FEEDBACK_MODES, FeedbackMode
from rtgait.core.planner.sample import PlanRecord

MIN_REMAINDER = 0.05
"""Shortest remainder of a phase (s) that :meth:`MeasuredPlanning.replan_now` plans over: closer to the phase's end
the free ZMP polynomial would need implausible speeds (its coefficients grow as ``1/T^4``; from 50 ms down the
connection conditions hold only to ~1e-7 m), and the next phase's replan is imminent anyway."""

OBSERVATION_MAX_AGE = 0.5
"""Oldest observation (s before the connection instant) a measured-state replan still uses."""

AUTO_MIN_REMAINDER = 0.1
"""Shortest remainder of a phase (s) over which a DCM error triggers a replan by itself; closer to the phase's end
the replan waits for the next phase (the error persists until a plan starts from the measured state)."""

AUTO_REPLAN_INTERVAL = 0.05
"""Least time (s) between two replans triggered by a DCM error (``PlannerConfig.replan_dcm_error``): a replan
from the measured state zeroes the error, so a new one means a new disturbance."""

OPERATOR_CACHE_SIZE = 256
"""Operators kept for plans that start mid-phase (their first duration varies continuously)."""


class MeasuredPlanning:
    """The measured-state methods of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring)."""

    # ----- the measured robot -----------------------------------------------------------------------------
    def observe(self, t: float, cog: Sequence[float], cog_vel: Sequence[float]) -> None:
        """The latest estimate of the horizontal COG position (m) and velocity (m/s) at absolute time ``t`` (s).

        With ``feedback="measured"`` each new plan connects from it, propagated to the connection instant by the
        pendulum (the planned ZMP drives both, so the deviation from the plan evolves as the free pendulum).

        Bounds (:mod:`rtgait.core.input_bounds`): every value finite; ``cog`` within
        ``COM_REACH_HEIGHTS * cog_height`` (plus half the feet's distance) of the midpoint of the feet on the
        ground; ``|cog_vel|`` at most ``COM_SPEED_FROUDE * sqrt(gravity * cog_height)``; any ``t`` (an observation
        more than :data:`OBSERVATION_MAX_AGE` from a connection is not used), but a replan it triggers (a DCM error,
        only for ``t`` not before the latest sample) takes ``t`` as :meth:`replan_now` does.
        """
        t, cx, cy, vx, vy = values = (float(t), float(cog[0]), float(cog[1]), float(cog_vel[0]), float(cog_vel[1]))
        # The per-tick path: a few float comparisons. A NaN or an infinity makes the sum non-finite (and so may an
        # overflow of huge finite values: the values are then tested one by one); the centre of reach is kept per
        # phase sampled.
        reach = self._reach
        phase = self._phase
        if phase is None or reach is None or reach[0] is not phase:
            reach = self._reach_now()
        dx, dy = cx - reach[1], cy - reach[2]
        if (
            not math.isfinite(t + cx + cy + vx + vy)
            or dx * dx + dy * dy > reach[3]
            or vx * vx + vy * vy > self._max_com_speed2
        ):
            self._refuse_observation(values)
        threshold = self.config.replan_dcm_error
        plan = self._plan
        if threshold is None or plan is None or self.config.feedback != "measured" or t < self._latest:
            self._observed = values
            return
        w = self.w
        planned = plan.cog_at(t, w)
        px, py, pvx, pvy = planned
        ex = cx + vx / w - px - pvx / w
        ey = cy + vy / w - py - pvy / w
        if ex * ex + ey * ey > threshold * threshold and t - self._last_auto_replan >= AUTO_REPLAN_INTERVAL:
            rel = t - self._t0
            if not (phase is not None and phase.start <= rel < phase.end and phase.end - rel < AUTO_MIN_REMAINDER):
                # Not within the last moments of a phase (a free segment that short would need wild ZMP swings:
                # the next phase's first tick replans): replan now, all of it undone if the replan refuses t.
                with self._atomic():
                    self._observed, self._observed_on_plan = values, (plan, t, planned)
                    self._last_auto_replan = t
                    self.replan_now(t, "dcm-error")
                return
        self._observed = values
        self._observed_on_plan = (plan, t, planned)  # the connection from this observation needs it again

    def touchdown(self, t: float, side: Side, x: float, y: float, yaw: float) -> int:
        """A foot is on the ground at ``(x, y)`` (m) with heading ``yaw`` (rad): where a swing foot really landed,
        or where a stance foot slipped to. Its footprint is replaced and every later footprint follows it (strides
        stay relative), so errors never accumulate; after a foothold on sloped ground the later ones stay where they
        were placed (:meth:`~rtgait.core.walk.changes.WalkChanges.retarget`). Off the flat floor the footprint keeps
        its planned surface (height, pitch, roll), its height taken on that surface's plane where the foot landed
        (:func:`~rtgait.core.geometry.foot_tilt.surface_rise`: ``d tan(a)`` lower for a landing ``d`` short up a ramp of
        angle ``a``; a tread's height unchanged). Returns the footprint index replaced.

        The plan under way is remade at once from its own state at ``t`` (:meth:`replan_now`, reason
        ``"touchdown"``), so the ZMP rests on the new footprint from the end of the phase under way on (unless the
        phase ends within :data:`MIN_REMAINDER`: then the replan at the next double-support start does it).

        Bounds (:mod:`rtgait.core.input_bounds`): ``t`` within ``MAX_TIME``, not before the latest sample and, like
        a sample's, at most :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` double supports ahead; ``x``, ``y``
        within ``MAX_POSITION``, ``yaw`` within ``MAX_YAW``; the footprint within the landing box
        (:class:`~rtgait.core.input_bounds.LandingBounds`, :func:`~rtgait.core.planner.bounded.landing_bounds`) of
        the foot it stepped from: turned less than a quarter turn, within the walk's and step adjustment's stride
        limits (or the stride planned there, if longer) plus :data:`~rtgait.core.input_bounds.LANDING_TOLERANCE`.
        """
        if not self.started:
            raise RuntimeError("call start() before touchdown()")
        t = float(t)
        self._check_time("t", t)
        self._check_not_before_latest("t", t)
        if side not in SIDES:
            raise InputOutOfBoundsError(f"side must be 'left' or 'right', got {side!r}")
        x, y, yaw = float(x), float(y), float(yaw)
        check_position("touchdown (x, y)", x, y)
        if not abs(yaw) <= MAX_YAW:  # also refuses NaN
            raise InputOutOfBoundsError(f"yaw must be finite and within +-{MAX_YAW:g} rad, got {yaw}")
        with self._atomic():  # which footprint landed is known once t is sampled: a refused landing undoes that
            return self._touchdown(t, Footstep(x, y, yaw, side))

    def _touchdown(self, t: float, footprint: Footstep) -> int:
        side = footprint.side
        if self._plan is not None:
            self.sample_values(t)  # the landing may begin a double support: make its plan, then re-anchor it
        q = self._walk.latest_phase or 0
        kind = self.timeline.kind(q)
        if kind == "single":
            i = (q + 1) // 2  # stance F[i], the swing foot lands on F[i + 1]
            index = i if self._walk.footprint(i).side == side else i + 1
        else:
            n = self.n_steps
            i = q // 2 if n is None else min(q // 2, n)
            index = i if self._walk.footprint(i).side == side else i + 1
        self._check_landing(index, footprint)
        planned = self._walk.footprint(index)
        if not planned.level:  # a touch-down measures x, y, yaw: the height is the planned surface's there
            rise = surface_rise(planned, footprint.x - planned.x, footprint.y - planned.y)
            footprint = Footstep(
                footprint.x, footprint.y, footprint.yaw, footprint.side, planned.z + rise, planned.pitch, planned.roll
            )
        if kind == "single" and index == (q + 1) // 2 + 1:
            self._freeze_swing(t)
        self._walk.retarget(index, footprint)
        self._phase = None
        if self._plan is not None and self._next_replan_time > t:
            self.replan_now(t, "touchdown")  # re-anchor now, unless the replan due at t will
        return index

    def _freeze_swing(self, t: float) -> tuple[float, float, float]:
        """The landing of the foot swinging now is about to move: remember its pose and velocity at ``t`` so the
        swing continues smoothly from there (:func:`~rtgait.core.geometry.swing.retargeted_swing`). Returns the pose."""
        self.sample_values(t)
        phase = self._phase
        if phase is None or phase.swing_from is None:
            raise RuntimeError(f"no foot is swinging at t={t} s")
        rel = t - self._t0
        pose, vel = phase.swing_state(rel, self.config.step_height)
        self._swing_retarget = (phase.index, (rel, pose, vel, phase.lift_progress(rel)))
        return pose

    def _midphase_layout(self, q: int, remainder: float) -> PlanLayout:
        """Layout of a plan that starts ``remainder`` (s) before the end of phase ``q`` (cached, bounded)."""
        timeline = self.timeline
        last = self._plan_span(q)
        kinds = tuple(timeline.kind(k) for k in range(q, last + 1))
        durations = (round(remainder, 9), *(timeline.duration(k) for k in range(q + 1, last + 1)))
        key = PatternKey(kinds=kinds, durations=durations, w=self.w, first_degree=self.config.first_degree)
        cache = self._midphase_layouts
        layout = cache.get(key)
        if layout is None:
            if len(cache) >= OPERATOR_CACHE_SIZE:
                del cache[next(iter(cache))]  # the oldest: dicts keep insertion order
            layout = cache[key] = PlanLayout(PlanOperator(key), kinds)
        return layout

    def _measured_cog(self, t: float, state: list[float]) -> None:
        """Replace the COG part of ``state`` (the planned state at ``t``) by the observed one carried to ``t``.

        Between the observation and ``t`` both the plan and the robot are driven by the planned ZMP, so their
        difference ``e`` obeys the free pendulum ``e'' = w^2 e``: ``e(t) = e cosh(w d) + e'/w sinh(w d)``."""
        observed, plan = self._observed, self._plan
        if observed is None or plan is None:
            return
        t_obs, cx, cy, vx, vy = observed
        d = t - t_obs
        if abs(d) > OBSERVATION_MAX_AGE:
            return
        w = self.w
        known = self._observed_on_plan
        if known is not None and known[0] is plan and known[1] == t_obs:
            px, py, pvx, pvy = known[2]
        else:
            px, py, pvx, pvy = plan.cog_at(t_obs, w)
        ch, sh = math.cosh(w * d), math.sinh(w * d)
        e, de = cx - px, vx - pvx
        state[4] += e * ch + de / w * sh
        state[6] += e * w * sh + de * ch
        e, de = cy - py, vy - pvy
        state[5] += e * ch + de / w * sh
        state[7] += e * w * sh + de * ch

    def replan_now(
        self,
        t: float,
        reason: str = "request",
        *,
        feedback: FeedbackMode | None = None,
        step_adjustment: StepAdjustment | Literal[False] | None = None,
    ) -> PlanRecord | None:
        """Replan at absolute time ``t`` (s), inside any phase: the free first segment is the remainder of the
        phase under way (``docs/closed_loop.md`` gives the equations). The plan starts from the measured state
        with ``feedback="measured"`` (else from the plan itself, which reproduces it).

        Args:
            feedback: for this replan only, ``"planned"`` or ``"measured"`` instead of ``config.feedback`` (so a
                controller that replans from the measured state only on a disturbance need not swap the config).
            step_adjustment: for this replan only, a :class:`~rtgait.core.laws.stepping.StepAdjustment` instead of
                ``config.step_adjustment``, or ``False`` for none; ``None``: the config's.

        Returns the new plan's record, or ``None`` when the phase ends within :data:`MIN_REMAINDER` (the regular
        replan at the next double-support start is imminent) or the walk is settling.

        Bounds: ``t`` finite, not before the latest sample and at most
        :data:`~rtgait.core.limits.MAX_REPLANS_PER_SAMPLE` double supports ahead (as a sample's).
        """
        began = time.perf_counter()
        t = float(t)
        self._check_time("t", t)
        if feedback is None:
            feedback = self.config.feedback
        elif feedback not in FEEDBACK_MODES:
            raise InputOutOfBoundsError(f"feedback must be one of {FEEDBACK_MODES} or None, got {feedback!r}")
        if step_adjustment is None:
            adjust = self.config.step_adjustment
        elif step_adjustment is False or isinstance(step_adjustment, StepAdjustment):
            adjust = step_adjustment or None
        else:
            raise InputOutOfBoundsError(
                f"step_adjustment must be a StepAdjustment, False or None, got {step_adjustment!r}"
            )
        if self._plan is None:
            raise RuntimeError("replan_now needs a plan under way: call start() and sample() first")
        self._check_not_before_latest("t", t)
        with self._atomic():  # nothing is left to refuse: undone only if the replanning itself fails
            return self._replan_now(t, reason, feedback, adjust, began)

    def _replan_now(
        self, t: float, reason: str, feedback: FeedbackMode, adjust: StepAdjustment | None, began: float
    ) -> PlanRecord | None:
        self.sample_values(t)  # replans up to t if due, and fixes the phase
        phase = self._phase
        assert phase is not None
        q = phase.index
        rel = t - self._t0
        remainder = phase.end - rel
        if remainder < MIN_REMAINDER or self.timeline.kind(q) == "settle":
            return None
        state = self._plan.state(*self._plan.locate(t), self.w)
        planned = None
        if feedback == "measured":
            if adjust is not None:
                planned = list(state)  # step adjustment may fall back to the planned state
            self._measured_cog(t, state)
        layout = self._midphase_layout(q, remainder)
        self._connect(t, q, layout, state, rel - phase.start)
        self._record(t, q, layout, began, reason)
        record = self.plans[-1]
        if adjust is not None:
            self._adjust_step(t, planned, adjust)
        return record
