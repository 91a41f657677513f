"""The shapes of the plans a walk needs: each plan's operator and anchor bookkeeping, built ahead and cached.

:class:`~rtgait.core.planner.online.OnlinePlanner` takes these methods from :class:`PlanShapes` (a mixin, like
:class:`~rtgait.core.planner.measured.MeasuredPlanning`): which phases a plan made in phase ``q`` covers, the layout
(:class:`~rtgait.core.planner.active_plan.PlanLayout`) of every regular replan still to come, built in ``start()`` and
whenever the walk's length or timing changes, so that no replan builds an operator. The mixin reads the planner's
configuration, timeline and caches; it has no state of its own.
"""

from __future__ import annotations

from rtgait.core.laws.step_timing import single_support_options
from rtgait.core.lipm.pattern import PatternKey, PlanOperator
from rtgait.core.planner.active_plan import PlanLayout


class PlanShapes:
    """The plan-shape methods of :class:`~rtgait.core.planner.online.OnlinePlanner` (see the module docstring)."""

    def _plan_span(self, q: int) -> int:
        """Last phase covered by a plan made in phase ``q`` (a plan made mid-step looks as far ahead as the one
        made when the step began, so that a plan from a state on it reproduces it)."""
        n = self.n_steps
        last = (q - (q & 1)) + 2 * self.config.horizon_steps
        return 2 * n + 1 if n is not None and last >= 2 * n else last

    def layout_for_replan(self, q: int) -> PlanLayout:
        """The layout of the plan made when double support ``q`` begins (its operator and anchor phases), as
        :meth:`sample` uses it; for evaluating many walks of this shape at once (:mod:`rtgait.core.analysis.batch`)."""
        if not self.started:
            raise RuntimeError("call start() before layout_for_replan()")
        return self._layout(q, self._plan_span(q))

    def _prepare_layouts(self, first_phase: int) -> None:
        """Build the operators of every plan shape still to come (with per-step timings: of every shape and
        durations), so that no replan pays for one (a fraction of a millisecond each, once per shape).

        Nothing to do when neither the first phase, the timeline (its length and timings: a new one whenever they
        change) nor the configuration changed since the last call: step adjustment calls this at every decision."""
        timeline, prepared = self.timeline, self._prepared
        if prepared is not None and prepared == (first_phase, timeline, self.config):
            return
        n = self.n_steps
        last_replan = first_phase + 2 if n is None else 2 * n
        self._layout_at = {q: self._layout(q, self._plan_span(q)) for q in range(first_phase, last_replan + 1, 2)}
        self._prepared = (first_phase, timeline, self.config)

    def _layout(self, first: int, last: int) -> PlanLayout:
        """Operator and anchor bookkeeping for the plan over phases ``first..last`` (cached by plan shape and, when
        steps have their own timing, by the phases' durations too). With step timing adaptation, a new layout
        also gets the operators of the candidate timings of the step that follows (one batch, built ahead)."""
        n = self.n_steps
        timeline = self.timeline
        # The phase kinds of a plan depend only on these three facts, so they key the cache cheaply; with one
        # timing for every step they also fix the durations.
        shape: tuple = (first == 0, last - first, n is not None and last == 2 * n + 1)
        adapts = self._adapts_timing()
        if not timeline.uniform or adapts:
            # With step timing adaptation the walk may turn per-step at any decision: key by the durations from
            # the start, so that the layouts built so far are found again then.
            shape = (*shape, timeline.durations(first, last))
        layout = self._layouts.get(shape)
        if layout is None:
            kinds = tuple(timeline.kind(q) for q in range(first, last + 1))
            key = PatternKey(
                kinds=kinds,
                durations=timeline.durations(first, last),
                w=self.w,
                first_degree=self.config.first_degree,
            )
            layout = self._layouts[shape] = PlanLayout(PlanOperator(key), kinds)
            if adapts and len(kinds) > 1 and kinds[1] == "single":
                adjust = self.config.step_adjustment
                durations = single_support_options(adjust, layout.durations[1])
                if durations is not None:
                    layout.variant_zmp_rows(1, durations, adjust.samples)
        return layout
