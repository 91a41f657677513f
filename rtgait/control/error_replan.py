"""The adaptive level's replan on a DCM error: the plan remade from the measured state, with step adjustment, when
the measured DCM is more than ``replan_dcm_error`` off the plan's (:mod:`rtgait.control.controller`,
``ControllerOptions.measured_replanning = "on-error"``).

When no step catches the error, the plan is kept: no replan for an outward DCM error in single support unless step
timing adaptation may hold the stance longer, and a later step's landing and timing are kept when no candidate for it
catches the error (the core's ``on_failure="keep"``).

Where the new plan's COM starts (``ControllerOptions.com_reference``). The pendulum's state splits into the DCM
``xi = c + c'/w``, which diverges and which alone the plan's ZMP and step adjustment must answer, and a convergent part
that decays by itself at the rate ``w``. ``"dcm"`` (default) starts the plan from the measured DCM with the COM where
the plan has it,

    c(t) = c_plan(t),        c'(t) = w (xi_measured - c_plan(t)),

so the IK's COM target keeps its position and only its velocity steps, by ``w`` times the DCM error (about 0.1 m/s at
the 25 mm threshold). ``"measured"`` starts it from the measured COM state: the target then moves by the COM error
(the servo lag and the estimate's error, millimetres) in one tick, ``error / dt`` on the IK's velocity references,
which can drive the legs to their torque limits (``docs/results.md``, "A DCM-error replan's step of the COM target").
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from rtgait.control.settings import ERROR_REPLAN_INTERVAL, ERROR_REPLAN_MIN_REMAINDER, ControlEvent

if TYPE_CHECKING:
    from rtgait.control.settings import ControllerOptions
    from rtgait.core.laws.stepping import StepAdjustment
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.core.planner.sample import SampleValues
    from rtgait.estimation.state import Measurement

__all__ = ["dcm_error_replan", "lengthens", "only_crossing_catches"]

_SIDES = ("left", "right")


def dcm_error_replan(
    planner: OnlinePlanner, options: ControllerOptions, t: float, m: Measurement, values: SampleValues, support: str,
    q: int, events: list[ControlEvent], last_replan: float, skimming: bool,
) -> tuple[bool, float]:  # fmt: skip
    """``"on-error"``: replan ``planner`` from the measured state ``m`` at ``t`` (s) when the measured DCM is more
    than ``options.replan_dcm_error`` off the plan's ``values``, as the core's ``observe`` does with
    ``feedback="measured"`` (at most every :data:`ERROR_REPLAN_INTERVAL` after ``last_replan``, not within
    :data:`ERROR_REPLAN_MIN_REMAINDER` of phase ``q``'s end; without step adjustment while a foot is ``skimming``
    ground it met early); returns whether it replanned and the time of the last such replan (s).

    *A step that does not catch the push is not taken when it is a later step's.* The replan's step adjustment
    moves the landing of the step swinging now or, within the limits' ``min_time_to_touchdown`` of its
    touch-down, the next one's. For that later step, when no candidate keeps the plan's ZMP inside the support
    (the core's emergency decision: the best margin, still outside), the core's ``on_failure="keep"`` keeps its
    landing and timing, and the plan goes on from the planned state: the measured state stays out of the plan,
    the stiff servos keep pulling the COM back to the plan and the DCM law with the foot force control recover
    what the sole can (the ``"stabilized"`` level's recovery). Such a step would be a later landing moved far
    to reshape the plan's connection while the robot must first stand a single support on the foot away from
    the push. The step swinging now, or lifting off next, still takes its best landing (``"continue"``): that
    foot can still go toward the capture point."""
    threshold = options.replan_dcm_error
    ex = m.dcm[0] - values.dcm_x
    ey = m.dcm[1] - values.dcm_y
    if ex * ex + ey * ey <= threshold * threshold or t - last_replan < ERROR_REPLAN_INTERVAL:
        return False, last_replan
    remainder = planner.phase_start(q) + planner.timeline.duration(q) - t
    if remainder < ERROR_REPLAN_MIN_REMAINDER:
        return False, last_replan
    adjust = options.step_adjustment
    if skimming:  # a foot on its way over ground it met early: its landing stays
        adjust = None
    if only_crossing_catches(values, support, ex, ey) and not lengthens(adjust):
        events.append(ControlEvent(t, "replan-skipped", support, "outward DCM error in single support"))
        return False, t
    if adjust is not None and support in _SIDES and remainder < adjust.limits.min_time_to_touchdown:
        adjust = dataclasses.replace(adjust, on_failure="keep")  # the core moves the next step's landing
    reference = options.com_reference
    if reference == "dcm":
        # The measured DCM from the COM where the plan has it: the plan's COM position goes on without a step.
        w = planner.w
        cog = (values.cog_x, values.cog_y)
        planner.observe(t, cog, (w * (m.dcm[0] - cog[0]), w * (m.dcm[1] - cog[1])))
    replanned = planner.replan_now(t, "dcm-error", feedback="measured", step_adjustment=adjust or False)
    if reference == "dcm":
        planner.observe(t, m.com[:2], m.com_vel[:2])
    if replanned is not None and reference == "planned":
        # The footsteps are the measured state's; the COM goes on from where the plan had it, so that the
        # servos keep pulling the robot back: the plan under way remade from the state sampled before.
        planner.observe(t, (values.cog_x, values.cog_y), (values.cog_vx, values.cog_vy))
        planner.replan_now(t, "dcm-error-plan", feedback="measured", step_adjustment=False)
        planner.observe(t, m.com[:2], m.com_vel[:2])
    return replanned is not None, t


def only_crossing_catches(values: SampleValues, support: str, ex: float, ey: float) -> bool:
    """Whether, in a single support, the DCM error ``(ex, ey)`` (m) points outward from the stance foot more
    than along it: the capture point then moves away from where the swing foot may land (the stride box keeps
    it on its own side, the leg collision model would refuse a crossing step), so no landing catches it and
    the plan under way is kept: unless step timing adaptation may lengthen the single support
    (``max_single_support``), when the replan's decision may hold the stance longer (:func:`lengthens`)."""
    if support not in _SIDES:
        return False
    yaw = values.lfoot_yaw if support == "left" else values.rfoot_yaw  # the stance foot's
    c, s = math.cos(yaw), math.sin(yaw)
    along, lateral = c * ex + s * ey, -s * ex + c * ey
    outward = lateral if support == "left" else -lateral
    return outward > abs(along)


def lengthens(adjust: StepAdjustment | None) -> bool:
    """Whether step adjustment ``adjust`` may give a step a longer single support: then a DCM error toward the
    stance foot's outside has an answer, the stance held longer while the sole's centre of pressure at its outer
    edge brings the DCM back, and the controller replans for it."""
    return adjust is not None and adjust.adapt_timing and adjust.limits.max_single_support is not None
