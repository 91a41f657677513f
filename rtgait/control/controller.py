"""The controller levels of the MuJoCo loop: planner sample -> feedback -> IK targets, once per control tick.

Names and planner settings are those of :mod:`rtgait.core.planner.levels` (:func:`~rtgait.core.planner.levels.
level_config`), as in the pendulum-level loop:

* ``"open-loop"``: the plan alone (the paper's assumption): COM and feet targets are the planner's sample.
* ``"stabilized"``: the DCM law (:class:`~rtgait.core.laws.feedback.DcmFeedback`) on the measured DCM gives a
  commanded ZMP ``p_cmd`` and a COM correction ``d`` (m, added to the planned COM; COM admittance
  ``d' = -A (p_cmd - p_measured) - d / T_c``), and foot force control (:mod:`rtgait.control.foot_control`) makes the
  feet produce ``p_cmd``: split between the feet in contact, each sole's CoP servoed by its ankle, the force
  difference by the feet's heights. When the polygon limits the law's ZMP, the shortfall is asked of the upper
  body's lean (the hip strategy, :mod:`rtgait.core.laws.hip_strategy`, ``ControllerOptions.hip_strategy``), which
  returns upright once nothing is asked, also after a switch to ``"open-loop"``.
* ``"adaptive"``: ``"stabilized"`` with the planner in the loop: every landing is classified and re-anchors the plan
  on its measured pose (:mod:`rtgait.control.landings`), and a DCM error beyond ``replan_dcm_error`` (25 mm) remakes
  the plan from the measured state with step adjustment in a stride box sized for the robot
  (:func:`~rtgait.control.settings.step_limits`). The other levels only log landings.

When the measured state enters the plan (``ControllerOptions.measured_replanning``): ``"on-error"`` (default) only on
such a DCM error; every other plan (the start, the double-support replans, the re-anchoring at landings) continues
the plan under way, whose COM the stiff servos track with the law's correction. ``"always"`` makes every plan from the
measured state (the core's ``feedback="measured"``); on a stiff position-controlled robot the IK's COM target then
follows each tick's servo lag instead of holding the robot (``docs/design/control.md``).

When no step catches the error, the plan is kept (:mod:`rtgait.control.error_replan`).

On the closed levels, two corrections for a robot that is not its model (``docs/robots.md``, "Model error"): the
DCM bias estimator (:mod:`rtgait.estimation.dcm_bias`, ``ControllerOptions.dcm_bias``) takes the offset of the
estimated COM from the one the measured ZMP agrees with out of the measurement the levels act on (the log keeps the
estimator's), and sole levelling (:mod:`rtgait.control.sole_level`, ``ControllerOptions.sole_level``) adds the tilt
each sole shows while it stands flat to its commanded roll and pitch.

All on Python floats; the support polygon (numpy) is rebuilt only when the feet in contact move.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from rtgait.control.error_replan import dcm_error_replan
from rtgait.control.external_force import ExternalForce, shifted_measurement
from rtgait.control.foot_control import FootForceControl, FootOffsets, split_zmp
from rtgait.control.foot_frame import feet_offset, translated
from rtgait.control.landings import FootLandings
from rtgait.control.level_switch import switch_level
from rtgait.control.pendulum_zmp import pendulum_zmp
from rtgait.control.settings import (
    ERROR_REPLAN_INTERVAL,
    ERROR_REPLAN_MIN_REMAINDER,
    SIM_COM_ADMITTANCE,
    SIM_COP_ADMITTANCE,
    ControlEvent,
    ControllerOptions,
    ControlTargets,
    RobotInfo,
    controller_step_adjustment,
    step_limits,
)
from rtgait.control.sole_level import SoleLevel, SoleLevelSettings
from rtgait.control.swing_feedback import SwingFeedback, SwingFeedbackSettings
from rtgait.core.geometry.footsteps import Footstep, Side, SoleRect, Stride, mean_heading
from rtgait.core.geometry.support import support_polygon
from rtgait.core.geometry.terrain import Terrain
from rtgait.core.laws.feedback import DcmFeedback
from rtgait.core.laws.hip_strategy import HipStrategy
from rtgait.core.lipm.closed_form import GRAVITY
from rtgait.core.planner.config import PlannerConfig
from rtgait.core.planner.levels import ControllerLevel, check_level, level_config
from rtgait.core.planner.online import OnlinePlanner
from rtgait.estimation.dcm_bias import DcmBiasEstimator

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy as np

    from rtgait.estimation.state import FootState, Measurement

__all__ = [
    "ERROR_REPLAN_INTERVAL",
    "ERROR_REPLAN_MIN_REMAINDER",
    "SIM_COM_ADMITTANCE",
    "SIM_COP_ADMITTANCE",
    "ControlEvent",
    "ControlTargets",
    "ControllerOptions",
    "RobotInfo",
    "WalkingController",
    "make_controller",
    "step_limits",
]

_NO_EVENTS: tuple[ControlEvent, ...] = ()
_NO_OFFSETS = FootOffsets()
_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing
_SIDES: tuple[Side, Side] = ("left", "right")


class WalkingController:
    """One controller level around an online planner (module docstring). Build with :func:`make_controller`."""

    def __init__(
        self,
        level: ControllerLevel,
        planner: OnlinePlanner,
        info: RobotInfo,
        dt: float,
        options: ControllerOptions,
        terrain: Terrain | None = None,
    ) -> None:
        check_level(level, "level")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a control period > 0 s, got {dt}")
        self.level, self.planner, self.info, self.dt, self.options = level, planner, info, float(dt), options
        self.terrain = terrain
        """The terrain the walk's footholds were placed on, for step adjustment's landings; ``None``: none known."""
        self.sole = info.sole
        self._weight = info.mass * GRAVITY  # N
        closed = level != "open-loop"
        self.feedback = DcmFeedback(planner.w, options.dcm, dt) if closed else None
        self.foot = FootForceControl(options.foot, dt) if closed and options.foot is not None else None
        # The soles' tilts seen while they stand flat (joint calibration errors), given back to the ankles, and the
        # offset of the estimated COM from the true one (the model's masses), from the measured ZMP: made for every
        # level (a switch may close the loop), acting in the closed ones.
        settings = SoleLevelSettings(time_constant=options.sole_level) if options.sole_level > 0.0 else None
        self.sole_level = SoleLevel(info.sole, info.mass * GRAVITY, dt, settings) if settings is not None else None
        self.dcm_bias = DcmBiasEstimator(planner.w, dt) if options.dcm_bias else None
        # The swing foot's measured position steered onto its target (the stance leg's deflection on soft drives).
        tau_swing = options.swing_feedback
        swing = SwingFeedbackSettings(time_constant=tau_swing) if tau_swing > 0.0 else None
        self.swing = SwingFeedback(dt, swing) if swing is not None and closed else None
        self._on_error = level == "adaptive" and options.measured_replanning == "on-error"
        self._last_error_replan = -math.inf
        tau = options.measurement_filter
        self._smoothing = 1.0 if tau == 0.0 else -math.expm1(-dt / tau)
        # A known external force (a person's pull on the hand): the robot leans against it (set_external_force).
        self.external = ExternalForce(info.mass, planner.w, dt)
        # The hip strategy: the upper body leans when the DCM law asks the feet for more than the sole gives.
        lean = info.lean if options.hip_strategy else None
        if lean is not None and options.max_lean != lean.max_lean:
            lean = dataclasses.replace(lean, max_lean=options.max_lean)
        self.hip = HipStrategy(lean, info.mass, dt) if lean is not None else None
        self._polygon_key: tuple[float, ...] | None = None
        self._polygon: np.ndarray | None = None
        # The feet's landings: classification, re-anchoring, holds, heights and the IK targets' blends.
        self.foot_landings = FootLandings(planner, options, self.dt, adaptive=level == "adaptive")
        self._landings_update, self._landings_ik = self.foot_landings.update, self.foot_landings.ik_targets  # per tick
        self._feet_frame = False  # whether the measurement is taken into the feet's frame: set by start()
        self.reset()

    def off_level_ground(self) -> None:
        """Turn sole levelling off for this walk: it takes every tilt a sole standing flat shows for a calibration
        error of its leg, which a sloped foothold or a heel rolled onto its toe before a step up is not."""
        self.sole_level = None

    def reset(self) -> None:
        """Zero the feedback states and forget the feet's landing states (called by :meth:`start`)."""
        if self.feedback is not None:
            self.feedback.reset()
        if self.foot is not None:
            self.foot.reset()
        if self.hip is not None:
            self.hip.reset()
        if self.sole_level is not None:
            self.sole_level.reset()
        if self.dcm_bias is not None:
            self.dcm_bias.reset()
        if self.swing is not None:
            self.swing.reset()
        self._filtered: list[float] | None = None  # zmp x, y; per foot: normal force, cop x, cop y
        self._replans = self._adjustments = 0
        self.foot_landings.reset()

    def start(self, t0: float, measurement: Measurement | None = None) -> None:
        """Start the walk at ``t0`` (s). ``"adaptive"`` with a measurement starts the planner from the measured feet
        and COM state; the other levels start from the plan's own standing feet (the paper's)."""
        self.reset()
        planner = self.planner
        if self.level == "adaptive" and measurement is not None:
            m = measurement
            feet = (m.left.footstep("left"), m.right.footstep("right"))
            if self._on_error:  # standing: the COM where the plan has it, between the measured feet, at rest
                planner.start(t0, feet=feet)
            else:
                planner.start(t0, feet=feet, cog=m.com[:2], cog_vel=m.com_vel[:2])
        else:
            planner.start(t0)
        self._last_error_replan = -math.inf
        self._replans, self._adjustments = planner.replan_count, planner.step_adjustment_count
        # Off the flat floor the measurement is taken into the feet's frame (foot_frame.py); flat walks as measured.
        self._feet_frame = self.level == "adaptive" and not all(foot.level for foot in planner.footprints())

    # ----- the tick ------------------------------------------------------------------------------------------------
    def tick(self, t: float, measurement: Measurement) -> ControlTargets:
        """The IK targets at ``t`` (s) for this tick's measurement (:class:`~rtgait.estimation.state.Measurement`)."""
        if self._feet_frame and (last := self.foot_landings.last_ik_targets) is not None:
            measurement = translated(measurement, *feet_offset(measurement, *last))
        external = self.external
        leaning = external.active
        if leaning:  # plan and feed back in the frame of the unpulled pendulum (external_force.py)
            rate = external.rate
            measurement = shifted_measurement(
                measurement, (-external.offset[0], -external.offset[1]), (-rate[0], -rate[1]), self.planner.w
            )
        closed = self.level != "open-loop"
        if self.dcm_bias is not None and closed:
            # Feed back and replan on the COM state the measured ZMP agrees with; after the lean's shift, whose
            # pendulum the measured ZMP drives, so that a known pull is no bias.
            raw = measurement
            heading = mean_heading(raw.left.pose[3], raw.right.pose[3])
            bx, by = self.dcm_bias.update(raw.dcm, raw.zmp, heading)
            measurement = shifted_measurement(raw, (-bx, -by), (0.0, 0.0), self.planner.w)
        planner, m = self.planner, measurement
        adaptive = self.level == "adaptive"
        events: list[ControlEvent] = []
        if adaptive:
            planner.observe(t, m.com[:2], m.com_vel[:2])  # with "always", may replan at once (DCM error)
        values, support, q = planner.sample_values(t)
        if self._on_error:
            replanned, self._last_error_replan = dcm_error_replan(
                planner, self.options, t, m, values, support, q, events, self._last_error_replan,
                self.foot_landings.skimming,
            )  # fmt: skip
            if replanned:
                values, support, q = planner.sample_values(t)
        # The landings (may replan: a touch-down), the feet's targets and the support acted on (foot_landings.py).
        values, planned_support, q, left, right, support = self._landings_update(t, m, values, support, q, events)
        self._planner_events(t, events)

        planned_zmp = (values.zmp_x, values.zmp_y)
        com = (values.cog_x, values.cog_y, values.cog_z)
        offsets = _NO_OFFSETS
        zmp, com_offset = planned_zmp, (0.0, 0.0)
        shortfall = (0.0, 0.0)
        if self.feedback is not None:
            zmp_measured, left_state, right_state = self._filter(m)
            polygon = self._support_polygon(support, left, right)
            # The measurement's DCM, made once by the estimator with the planner's w (checked at the stack's
            # making), is the one acted on and the one logged.
            out = self.feedback.update(planned_zmp, (values.dcm_x, values.dcm_y), m.dcm, polygon, None, zmp_measured)
            zmp, com_offset = out.zmp, out.com_offset
            if out.saturated and self.hip is not None:
                # The law asks more than the sole gives: the rest is asked of the upper body's lean.
                shortfall = (out.zmp_unsaturated[0] - zmp[0], out.zmp_unsaturated[1] - zmp[1])
            com = (com[0] + com_offset[0], com[1] + com_offset[1], com[2])
            if self.foot is not None:
                split = split_zmp(zmp, left, right, self.sole, support)
                offsets = self.foot.update(split, left_state, right_state, support)
                left = (left[0], left[1], left[2] + offsets.left_height, left[3])
                right = (right[0], right[1], right[2] + offsets.right_height, right[3])
            if self.sole_level is not None and closed:
                lr, lp, rr, rp = self.sole_level.update(m.left, m.right, support)
                o = offsets
                offsets = _new_tuple(FootOffsets, (o.left_roll + lr, o.left_pitch + lp, o.left_height,
                                                   o.right_roll + rr, o.right_pitch + rp, o.right_height))  # fmt: skip
        if leaning:
            com = (com[0] + external.offset[0], com[1] + external.offset[1], com[2])
        lean = None
        if self.hip is not None:  # also without feedback (open-loop after a switch): a lean under way returns
            leaned = self.hip.update(shortfall, mean_heading(left[3], right[3]))
            if leaned.lean != (0.0, 0.0, 0.0):
                lean = leaned.lean
        # The blends act on the IK's targets only: the polygon and split have the feet where they are.
        left, right = self._landings_ik(t, left, right)
        if self.swing is not None:
            left, right = self.swing.update(left, right, (m.left, m.right), support)
        return _new_tuple(ControlTargets, (
            t, com, left, right, offsets, zmp, planned_zmp, com_offset, support, q, tuple(events) or _NO_EVENTS,
            planned_support, (values.dcm_x, values.dcm_y), lean,
        ))  # fmt: skip

    # ----- the support polygon -------------------------------------------------------------------------------------
    def _support_polygon(self, support: str, left: tuple[float, ...], right: tuple[float, ...]) -> np.ndarray:
        """The support polygon of the feet in contact (cached until they move)."""
        # The key without building lists (every tick): the ground poses of the feet in contact.
        if support == "double":
            key: tuple[float, ...] = (left[0], left[1], left[3], right[0], right[1], right[3])
        elif support == "left":
            key = (left[0], left[1], left[3])
        elif support == "right":
            key = (right[0], right[1], right[3])
        else:
            key = ()
        if key != self._polygon_key or self._polygon is None:
            chosen = [(pose, side) for pose, side in ((left, "left"), (right, "right")) if support in ("double", side)]
            feet = [Footstep(pose[0], pose[1], pose[3], side) for pose, side in chosen]  # type: ignore[arg-type]
            self._polygon, self._polygon_key = support_polygon(feet, self.sole), key
        return self._polygon

    # ----- measurements and the planner's log ----------------------------------------------------------------------
    def _filter(self, m: Measurement) -> tuple[tuple[float, float] | None, FootState, FootState]:
        """The measured ZMP (as the pendulum's, :mod:`rtgait.control.pendulum_zmp`) and feet with their loads and CoPs
        low-passed (NaN restarts a filter)."""
        (zx, zy), fl, fr = m.zmp, m.left, m.right
        # The ZMP of a pendulum carried by its weight (pendulum_zmp.py), before the filter: the measured moment, not
        # M / F, on a total normal force near zero.
        zx, zy = pendulum_zmp((zx, zy), m.com, fl.normal_force + fr.normal_force, self._weight)
        (lx, ly), (rx, ry) = fl.cop_local, fr.cop_local
        lz, rz = fl.normal_force, fr.normal_force
        state = self._filtered
        if state is not None and self._smoothing != 1.0:
            # Each of the eight filters written out (a comprehension over them costs twice as much):
            # s + a (r - s), or the raw value r where either is NaN.
            a = self._smoothing
            s0, s1, s2, s3, s4, s5, s6, s7 = state
            zx = zx if (s0 != s0 or zx != zx) else s0 + a * (zx - s0)
            zy = zy if (s1 != s1 or zy != zy) else s1 + a * (zy - s1)
            lz = lz if (s2 != s2 or lz != lz) else s2 + a * (lz - s2)
            lx = lx if (s3 != s3 or lx != lx) else s3 + a * (lx - s3)
            ly = ly if (s4 != s4 or ly != ly) else s4 + a * (ly - s4)
            rz = rz if (s5 != s5 or rz != rz) else s5 + a * (rz - s5)
            rx = rx if (s6 != s6 or rx != rx) else s6 + a * (rx - s6)
            ry = ry if (s7 != s7 or ry != ry) else s7 + a * (ry - s7)
        self._filtered = [zx, zy, lz, lx, ly, rz, rx, ry]
        # By name, so that a new field of the feet's state cannot shift the others (a microsecond a foot).
        left = fl._replace(normal_force=lz, cop_local=(lx, ly))
        right = fr._replace(normal_force=rz, cop_local=(rx, ry))
        return (None if zx != zx else (zx, zy)), left, right

    def _planner_events(self, t: float, events: list[ControlEvent]) -> None:
        """Step adjustments and the replans other than the regular ones, since the last tick."""
        planner = self.planner
        new = planner.step_adjustment_count - self._adjustments
        if new:
            self._adjustments = planner.step_adjustment_count
            for decision in list(planner.step_adjustments)[-new:]:
                x, y = decision.landing
                kind = "step-refused" if decision.kept else "step-adjustment"
                events.append(ControlEvent(t, kind, "", decision.reason, x, y))
        new = planner.replan_count - self._replans
        if new:
            self._replans = planner.replan_count
            for record in list(planner.plans)[-new:]:
                if record.reason not in ("start", "double-support"):
                    events.append(ControlEvent(t, "replan", "", record.reason))

    # ----- switching level mid-walk --------------------------------------------------------------------------------
    def set_external_force(self, force: tuple[float, float], height: float) -> None:
        """A horizontal force (N, world frame) measured on the robot at ``height`` (m above the ground), e.g. a
        wrist sensor's reading: the closed-loop levels lean against it so the ZMP stays planned
        (:mod:`rtgait.control.external_force`); ``"open-loop"`` ignores it (the paper's robot knows nothing)."""
        if self.level != "open-loop":
            self.external.set(force, height)

    def set_level(self, level: ControllerLevel) -> None:
        """Switch to controller level ``level`` (``"open-loop"``, ``"stabilized"``, ``"adaptive"``) mid-walk or
        before the start, without a jump in the IK's targets (:func:`rtgait.control.level_switch.switch_level` says
        what each switch starts, stops or resets).

        Raises:
            ValueError: an unknown level.
        """
        switch_level(self, level)


def make_controller(
    level: ControllerLevel,
    planner_config: PlannerConfig,
    strides: Sequence[Stride] | None,
    sole: SoleRect,
    robot: RobotInfo,
    *,
    dt: float = 0.001,
    options: ControllerOptions | None = None,
    terrain: Terrain | None = None,
) -> WalkingController:
    """A controller of level ``level`` (``"open-loop"``, ``"stabilized"``, ``"adaptive"``) with its own planner.

    Args:
        level: the controller level (module docstring).
        planner_config: the planner's base configuration; the level's is made from it by
            :func:`~rtgait.core.planner.levels.level_config` (the levels differ only by what the loop adds).
        strides: the walk; ``None`` to walk by velocity command.
        sole: the sole rectangle (m), for support polygons, the ZMP split and step adjustment.
        robot: what the controller knows of the robot (:func:`rtgait.robot.controller_info.robot_info` makes it
            from a loaded robot model).
        dt: control period (s).
        options: feedback gains and landing handling (:class:`ControllerOptions`).
        terrain: the terrain the walk's footholds were placed on (a scenario's ``[terrain]`` with
            ``place_footsteps``): step adjustment keeps the landings it moves on their own treads or stones, at the
            terrain's height and tilt there (:mod:`rtgait.core.geometry.terrain_landing`). ``None`` (default): the
            moved landings keep their height and tilt, as on the flat floor.
    """
    options = options or ControllerOptions()
    if not isinstance(robot, RobotInfo):
        raise TypeError(f"robot must be a RobotInfo (rtgait.robot.controller_info.robot_info), not {type(robot)}")
    info = robot
    if info.sole != sole:
        info = dataclasses.replace(info, sole=sole)
    if terrain is not None and getattr(terrain, "kind", None) == "flat":
        terrain = None  # nothing to keep a landing on: a flat walk stays as it is
    adjust = controller_step_adjustment(options, info, terrain) if level == "adaptive" else None
    config = level_config(
        planner_config, level, sole, replan_dcm_error=options.replan_dcm_error, step_adjustment=adjust
    )
    if level == "adaptive" and options.measured_replanning == "on-error":
        # The controller takes the measured state in, and steps elsewhere, only on a DCM error (error_replan).
        options = dataclasses.replace(options, step_adjustment=adjust)
        config = dataclasses.replace(config, feedback="planned", step_adjustment=None)
    return WalkingController(level, OnlinePlanner(config, strides), info, dt, options, terrain)
