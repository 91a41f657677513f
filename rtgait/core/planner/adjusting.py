"""Step adjustment after a replan: the part of the online planner that moves a landing (and its timing) when the
plan's free segment asks for a ZMP outside the support polygon.

:class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from :class:`StepAdjusting` (a mixin, like
:class:`~rtgait.core.planner.measured.MeasuredPlanning`, whose replans call :meth:`StepAdjusting._adjust_step`). The
candidates are weighed by :func:`rtgait.core.laws.landing_choice.propose_landing`; the equations are in
``docs/closed_loop.md`` ("Step adjustment"). The mixin reads and writes the planner's state (the plan under way, the
walk, the logs); it has no state of its own and is not meant to be used alone.
"""

from __future__ import annotations

import math

import numpy as np

from rtgait.core.geometry.footsteps import Stride
from rtgait.core.geometry.halfplanes import halfplane_margin, polygon_halfplanes
from rtgait.core.geometry.support import support_polygon
from rtgait.core.geometry.terrain_landing import land_on_terrain
from rtgait.core.laws.landing_choice import propose_landing
from rtgait.core.laws.step_timing import TimingOptions, remainder_options, single_support_options
from rtgait.core.laws.stepping import StepAdjustment, StepDecision
from rtgait.core.lipm.pattern import MOVING_KINDS
from rtgait.core.planner.active_plan import PlanLayout


class StepAdjusting:
    """The step-adjustment methods of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring)."""

    def _free_segment_margin(self, halfplanes, samples: int) -> tuple[np.ndarray, np.ndarray, float]:
        """The plan's free segment: its layout's ZMP rows ``M`` at ``samples`` times, its ZMP then and its margin."""
        plan = self._plan
        rows = plan.layout.zmp_rows(samples)
        zmp = rows @ plan.y
        return rows, zmp, float(halfplane_margin(zmp, *halfplanes).min())

    def _adjust_step(self, t: float, planned: list[float] | None, adjust: StepAdjustment) -> StepDecision | None:
        """After a replan: if its free segment asks for a ZMP outside the support polygon, move the landing of the
        next step that can still change to the candidate that keeps it inside with the least departure
        (:mod:`rtgait.core.laws.stepping`).

        With none, ``StepAdjustment.on_failure`` decides: ``"continue"`` takes the landing with the largest margin
        all the same (a capture step) and walks on, ``"stop"`` takes it and stops after that step, ``"keep"`` keeps
        the walk as planned (footprints and timing). A plan made from the measured state is then replaced by the
        one from the planned state ``planned``, with the new landing: a plan no foot can realise would ask the
        feedback law to follow it, while from the planned state it asks only for what the ankle can do and the law,
        saturated at the sole's edge, recovers the rest.
        """
        plan = self._plan
        q = plan.phase0
        walk = self._walk
        if self.timeline.kind(q) in ("end", "settle"):
            return None
        halfplanes = polygon_halfplanes(support_polygon(walk.contact_feet(q), adjust.sole))
        rows, zmp, before = self._free_segment_margin(halfplanes, adjust.samples)
        if before >= adjust.required_margin:
            return None
        timings = None
        if self._adapts_timing(adjust):

            def timings(k: int, swinging: bool) -> TimingOptions | None:
                return self._timing_options(k, swinging, adjust)

        proposal = propose_landing(
            adjust, walk, q, t, self.phase_start, rows, zmp, halfplanes, plan.layout.anchor_phases,
            lambda: self._freeze_swing(t)[:2], timings,
        )  # fmt: skip
        if proposal is None:
            if planned is not None:
                self._connect(plan.t_start, q, plan.layout, planned, plan.elapsed)
            return None
        k, nominal, landing = proposal.step, proposal.nominal, proposal.landing
        if not proposal.enough and adjust.on_failure == "keep":
            return self._keep_walk(t, planned, proposal, before, halfplanes, adjust)
        surface = kept = None
        if adjust.terrain is not None:  # on its foothold's own tread or stone, at the terrain's height and tilt there
            placed = land_on_terrain(adjust.terrain, nominal, *landing, adjust.sole)
            foot = placed.footprint
            landing, surface = (foot.x, foot.y), (foot.z, foot.pitch, foot.roll)
            kept = placed.asked if placed.clamped else None
        walk.move_landing(k, *landing, surface=surface)
        moved = math.hypot(landing[0] - nominal.x, landing[1] - nominal.y)
        reason = f"ZMP margin {before * 1e3:+.1f} mm: step {k} lands {moved:.3f} m away"
        if kept is not None:
            reason += f" (kept on its foothold's surface: {kept:.3f} m asked)"
        layout = None
        if proposal.timing >= 0:
            layout = self._timing_layouts(k, proposal.swinging, adjust)[proposal.timing]
            walk.set_single_support(k, proposal.single_support)
            if self._next_replan_phase is not None:  # the phases after step k's single support moved
                self._next_replan_time = self.phase_start(self._next_replan_phase)
            change = proposal.single_support - proposal.nominal_single_support
            reason += (
                f", {abs(change):.3f} s {'later' if change > 0 else 'sooner'} "
                f"(single support {proposal.single_support:.3f} s)"
            )
        n = walk.n_steps
        if not proposal.enough:
            reason += f"; no landing keeps the ZMP inside (best {proposal.margin * 1e3:+.1f} mm)"
            if adjust.on_failure == "stop" or planned is None:
                if n is None or k < n:
                    walk.set_strides([Stride(0.0, self.config.step_width, 0.0)], from_step=k + 1)
                reason += ": emergency stop after it"
            else:
                reason += ": walking on from the planned state, the feedback law recovers"
        self._phase = None
        self._reconnect(planned if planned is not None and not proposal.enough else None, layout)
        after = self._free_segment_margin(halfplanes, adjust.samples)[2]
        decision = StepDecision(
            t, k, (nominal.x, nominal.y), landing, before, after, proposal.candidates, not proposal.enough, reason,
            proposal.single_support, proposal.nominal_single_support,
        )  # fmt: skip
        return self._log_decision(decision)

    def _keep_walk(self, t: float, planned: list[float] | None, proposal, before: float, halfplanes, adjust):
        """``on_failure="keep"`` and no candidate is enough: the footprints and timing stay as planned; a plan from
        the measured state gives way to the one from the planned state (as when no step can move)."""
        plan = self._plan
        if planned is not None:
            self._connect(plan.t_start, plan.phase0, plan.layout, planned, plan.elapsed)
        nominal = proposal.nominal
        after = self._free_segment_margin(halfplanes, adjust.samples)[2]
        reason = (
            f"ZMP margin {before * 1e3:+.1f} mm; no landing keeps the ZMP inside (best {proposal.margin * 1e3:+.1f} "
            f"mm): step {proposal.step} kept as planned"
        )
        decision = StepDecision(
            t, proposal.step, (nominal.x, nominal.y), (nominal.x, nominal.y), before, after, proposal.candidates, True,
            reason, proposal.nominal_single_support, proposal.nominal_single_support, kept=True,
        )  # fmt: skip
        return self._log_decision(decision)

    def _log_decision(self, decision: StepDecision) -> StepDecision:
        """Log ``decision`` (once: a disturbance that persists re-decides the same capture step) and return it."""
        k, landing = decision.step, decision.landing
        last = self.step_adjustments[-1] if self.step_adjustments else None
        repeated = last is not None and last.step == k and math.dist(last.landing, landing) < 1e-3 and last.emergency
        if not repeated:  # a disturbance that persists re-decides the same capture step: log it once
            self.step_adjustments.append(decision)
            self.step_adjustment_count += 1
        return decision

    def _timing_durations(
        self, k: int, swinging: bool, adjust: StepAdjustment
    ) -> tuple[int, tuple[float, ...], np.ndarray] | None:
        """The candidate timings of step ``k`` for the plan under way: the plan's segment whose duration changes,
        its candidate durations (s) and the step's single support under each (s); ``None`` when the step's timing
        cannot change. Swinging, the segment is the free one, the rest of the single support
        (:func:`~rtgait.core.laws.step_timing.remainder_options`); else the step's whole single support
        (:func:`~rtgait.core.laws.step_timing.single_support_options`)."""
        plan = self._plan
        if swinging:
            durations = remainder_options(adjust, plan.elapsed, plan.durations[0])
            return None if durations is None else (0, durations, plan.elapsed + np.array(durations))
        segment = 2 * k - 1 - plan.phase0
        if segment >= len(plan.durations) or plan.layout.kinds[segment] != "single":
            return None
        durations = single_support_options(adjust, plan.durations[segment])
        return None if durations is None else (segment, durations, np.array(durations))

    def _adapts_timing(self, adjust: StepAdjustment | None = None) -> bool:
        """Step adjustment (``adjust``, default the config's) may change step timings (not with the auto
        connection: it needs uniform timing)."""
        adjust = adjust if adjust is not None else self.config.step_adjustment
        return adjust is not None and adjust.adapt_timing and self.config.connection != "auto"

    def _timing_layouts(self, k: int, swinging: bool, adjust: StepAdjustment) -> list[PlanLayout]:
        """The plan under way's layout under each candidate timing of step ``k`` (:meth:`_timing_durations`)."""
        segment, durations, _ = self._timing_durations(k, swinging, adjust)
        return self._plan.layout.variants(segment, durations)

    def _timing_options(self, k: int, swinging: bool, adjust: StepAdjustment) -> TimingOptions | None:
        """What :func:`~rtgait.core.laws.landing_choice.propose_landing` weighs for a new timing of step ``k``: the
        plans under the candidate timings, from the same inputs ``y`` (the state and the footprints do not change; the
        operators do: built ahead for the plans of double-support starts, in one batch per plan shape)."""
        found = self._timing_durations(k, swinging, adjust)
        if found is None:
            return None
        segment, durations, singles = found
        plan = self._plan
        rows = plan.layout.variant_zmp_rows(segment, durations, adjust.samples)
        return TimingOptions(singles, rows, rows @ plan.y)

    def _reconnect(self, state: list[float] | None = None, layout: PlanLayout | None = None) -> None:
        """Remake the plan under way at its own start, after its footprints (or the walk's length) changed at that
        instant: from its own initial state, or from ``state`` (``[p0x, p0y, dp0x, dp0y, c0x, c0y, dc0x, dc0y]``);
        with ``layout`` (after a new step timing), in that shape."""
        plan = self._plan
        q, elapsed = plan.phase0, plan.elapsed
        if self._next_replan_phase is not None:
            self._prepare_layouts(self._next_replan_phase)
        first = plan.durations[0] if layout is None else layout.durations[0]
        if layout is not None:
            timeline, last = self.timeline, self._plan_span(q)
            if layout.kinds != tuple(timeline.kind(p) for p in range(q, last + 1)):
                layout = None  # a timing variant of the walk before an emergency stop shortened it: remade below
        if layout is None and elapsed == 0.0 and self.timeline.kind(q) in MOVING_KINDS:
            layout = self._layout(q, self._plan_span(q))
        elif layout is None:
            layout = self._midphase_layout(q, first)
        self._connect(plan.t_start, q, layout, plan.y[:4].ravel().tolist() if state is None else state, elapsed)


__all__ = ["StepAdjusting"]
