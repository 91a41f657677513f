"""Switching a walking controller between its levels mid-walk, without a jump in the IK's targets: the laws a
switch up starts from zero state, the offsets a switch down fades out (:mod:`rtgait.control.level_fade`), and the
planner's settings made for the new level (:func:`rtgait.core.planner.levels.level_config`)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from rtgait.control.foot_control import FootForceControl, FootOffsets
from rtgait.control.level_fade import LEVEL_FADE, FeedbackFade, FootFade
from rtgait.control.settings import controller_step_adjustment
from rtgait.core.laws.feedback import DcmFeedback
from rtgait.core.planner.levels import ControllerLevel, check_level, level_config

__all__ = ["switch_level"]


def switch_level(controller: Any, level: ControllerLevel) -> None:  # a WalkingController, which imports this
    """Switch ``controller`` to level ``level`` (``"open-loop"``, ``"stabilized"``, ``"adaptive"``) mid-walk or
    before the start, without a jump in the IK's targets.

    The planner and its plan go on as they are (no replan at the switch); its settings become the new level's, made
    from its current ones as :func:`~rtgait.control.controller.make_controller` makes them
    (:func:`~rtgait.core.planner.levels.level_config`: measured-state replanning, the DCM-error threshold and step
    adjustment for ``"adaptive"`` only). What each switch starts, stops or resets:

    * to a closed level from ``"open-loop"``: a new DCM feedback law and foot force control, from zero state
      (no COM or foot offset, an empty integral), so the targets start from the plan's; the commanded ZMP steps
      to the law's (it is no IK target: the foot force control it drives integrates from zero);
    * to ``"open-loop"``: the COM and foot offsets held at the switch fade out over
      :data:`rtgait.control.level_fade.LEVEL_FADE` (0.2 s, smooth) instead of vanishing
      (:mod:`rtgait.control.level_fade`), then the feedback and foot force control are dropped;
    * between ``"stabilized"`` and ``"adaptive"``: the feedback and foot force control go on unchanged;
    * into ``"adaptive"``: the planner is observed from the next tick on (a DCM error beyond
      ``replan_dcm_error`` replans at once from the measured state, the next landings re-anchor the plan) and
      the DCM-error replan's rate limit is cleared; out of it, a late foot's descent stops (the height it reached
      is shed over its next swing, as after any landing) and landings are only logged again.

    The feet's landing states (early and late touch-downs under way, their heights) are kept, and so is the
    stride box of step adjustment in the options (it acts in ``"adaptive"`` only; a return to it reuses it).

    Raises:
        ValueError: an unknown level.
    """
    check_level(level, "level")
    if level == controller.level:
        return
    options, planner = controller.options, controller.planner
    adjust = controller_step_adjustment(options, controller.info, controller.terrain) if level == "adaptive" else None
    config = level_config(
        planner.config, level, controller.sole, replan_dcm_error=options.replan_dcm_error, step_adjustment=adjust
    )
    if level == "adaptive" and options.measured_replanning == "on-error":
        controller.options = options = dataclasses.replace(options, step_adjustment=adjust)
        config = dataclasses.replace(config, feedback="planned", step_adjustment=None)
        controller.foot_landings.options = options
    planner.config = config
    if controller.level == "open-loop":  # up: new laws from zero state (a fade under way goes on around them)
        feedback = DcmFeedback(planner.w, options.dcm, controller.dt)
        foot = FootForceControl(options.foot, controller.dt) if options.foot is not None else None
        if isinstance(controller.feedback, FeedbackFade):
            controller.feedback.inner = feedback
        else:
            controller.feedback = feedback
        if isinstance(controller.foot, FootFade):
            controller.foot.inner = foot
        else:
            controller.foot = foot
        if controller.sole_level is not None:  # the learnt tilts kept, the soles' command from the plan's again
            controller.sole_level.restart_command()
        if controller.dcm_bias is not None:  # not updated in open-loop: it starts again from the measured DCM
            controller.dcm_bias.reset()
    elif level == "open-loop":  # down: fade the offsets out (nothing to fade before the start)
        ticks = max(1, round(LEVEL_FADE / controller.dt))
        offset = controller.feedback.com_offset if controller.feedback is not None else (0.0, 0.0)
        offsets = controller.foot.offsets if controller.foot is not None else FootOffsets()
        if controller.sole_level is not None:  # the soles' levelling fades with the foot force control's tilts
            lr, lp, rr, rp = controller.sole_level.command
            o = offsets
            offsets = FootOffsets(o.left_roll + lr, o.left_pitch + lp, o.left_height,
                                  o.right_roll + rr, o.right_pitch + rp, o.right_height)  # fmt: skip
        moved = any(offset) or any(offsets)
        controller.feedback = FeedbackFade(controller, None, offset, ticks) if moved else None
        controller.foot = FootFade(controller, None, offsets, ticks) if moved else None
    controller._on_error = level == "adaptive" and options.measured_replanning == "on-error"
    if level == "adaptive":
        controller._last_error_replan = -math.inf
    controller.foot_landings.set_adaptive(level == "adaptive")
    controller.level = level
