"""The controller levels of the MuJoCo loop: planner sample -> feedback -> IK targets, once per control tick.

Names and planner settings are those of :mod:`rtgait.core.closed_loop` (:func:`~rtgait.core.closed_loop.
controller_config`), the pendulum-level loop:

* ``"open-loop"``: the plan alone (the paper's assumption): COM and feet targets are the planner's sample.
* ``"stabilized"``: the DCM law (:class:`~rtgait.core.feedback.DcmFeedback`) on the measured DCM gives a commanded ZMP
  ``p_cmd`` and a COM correction ``d`` (COM admittance ``d' = -A (p_cmd - p_measured) - d / T_c``, added to the planned
  COM), and foot force control (:mod:`rtgait.sim.foot_control`) makes the feet produce ``p_cmd``: split between the
  feet in contact, each sole's CoP servoed by its ankle, the force difference by the feet's heights.
* ``"adaptive"``: ``"stabilized"`` with a planner that closes the loop: :meth:`~rtgait.core.online.OnlinePlanner.
  observe` every tick, replanning from the measured state, step adjustment in a stride box sized for the robot
  (:func:`step_limits`), re-anchoring on the landed feet, and landing detection.

  *When the measured state enters the plan* (``ControllerOptions.measured_replanning``). ``"on-error"`` (default):
  when the measured DCM is more than ``replan_dcm_error`` (25 mm) off the plan's, the plan under way is remade from the
  measured state and the step adjustment may move the next landing; every other plan (the start, the regular
  double-support replans, the re-anchoring at landings) continues the plan under way, whose COM the stiff servos
  track with the feedback law's correction. ``"always"``: the core's ``feedback="measured"``, every plan from the
  measured state. On a stiff position-controlled robot ``"always"`` turns each tick's servo lag into a new plan: the
  IK's COM target follows the robot instead of holding it, and G1 fell on fig6 (Talos walked either way).

  *Landings.* Every landing is reported with its measured pose (:meth:`~rtgait.core.online.OnlinePlanner.touchdown`:
  re-anchoring and an immediate replan). One within ``on_time_window`` (80 ms) of the plan's touch-down is on time:
  the foot follows the plan down (the swing's height profile ends flat, so a robot whose stance side gives 2 mm lands
  that early at every step). An *early* one (before that, in the swing's second half, ``early_touchdown_fraction``)
  switches support at once: polygon and ZMP split take both feet until the plan's double support, and the foot stays
  where it landed while its target goes on down with the plan, at most ``late_descent_limit`` below where it touched
  (on a higher ground the foot must not push the robot up). A *late* one (the swing is over, the foot carries
  nothing ``late_grace`` after it, the landing's detection lag): the other foot carries the robot and the foot's
  target descends at ``late_descent_speed`` to ``late_descent_limit`` below the plan (auto_stabilizer
  ``FootStepGenerator.h``: ``touchVel`` 0.3 m/s, ``goalOffset`` -0.02 m); unlike auto_stabilizer the plan is not
  delayed. A late foot stands at the ground's measured height (its target brought there over the single support it
  carries next: kept as deep as the target went, it would lift the body and make the next landing later still);
  any other keeps the height it landed at; either is shed linearly over its next swing. A foot that lands again in
  the same stance (a bounce) is re-anchored only if it moved ``relanding_tolerance`` (10 mm).

  *No step in a loaded foot's target.* A re-anchoring moves the landed foot's target onto its measured pose, a few
  millimetres from where the servos had it, and an early landing's hold starts and ends with a jump of its own; the IK
  gets the foot's target moved from its old pose and rate to the new target over ``anchor_blend`` (40 ms) along the
  planner's own retargeted-swing quintic (:mod:`rtgait.sim.target_blend`), and so do swing feet re-anchored less
  than that before the plan's touch-down. The planner, the support polygon and the ZMP split have the foot where it was
  measured at once.

  *When no step catches the error, the plan is kept* (:meth:`WalkingController._dcm_error_replan`): no replan for
  an outward DCM error in single support, and a later step's landing and timing are kept when no candidate for it
  catches the error (the core's ``on_failure="keep"``).

All on Python floats; the support polygon (numpy) is rebuilt only when the feet in contact move.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from rtgait.core.closed_loop import CONTROLLERS, Controller, controller_config
from rtgait.core.config import PlannerConfig
from rtgait.core.feedback import DcmFeedback
from rtgait.core.footsteps import Footstep, Side, SoleRect, Stride
from rtgait.core.online import OnlinePlanner
from rtgait.core.support import support_polygon
from rtgait.sim.control_settings import (
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
from rtgait.sim.external_force import ExternalForce, shifted_measurement
from rtgait.sim.foot_control import FootForceControl, FootOffsets, split_zmp
from rtgait.sim.target_blend import FootBlend, Pose

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy as np

    from rtgait.core.stepping import StepAdjustment
    from rtgait.robot.model import RobotModel
    from rtgait.sim.measure import FootState, Landing, Measurement

__all__ = [
    "CONTROLLERS",
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
_SIDES: tuple[Side, Side] = ("left", "right")


class WalkingController:
    """One controller level around an online planner (module docstring). Build with :func:`make_controller`."""

    def __init__(
        self, level: Controller, planner: OnlinePlanner, info: RobotInfo, dt: float, options: ControllerOptions
    ) -> None:
        if level not in CONTROLLERS:
            raise ValueError(f"level must be one of {', '.join(CONTROLLERS)}, got {level!r}")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a control period > 0 s, got {dt}")
        self.level, self.planner, self.info, self.dt, self.options = level, planner, info, float(dt), options
        self.sole = info.sole
        closed = level != "open-loop"
        self.feedback = DcmFeedback(planner.w, options.gains, dt) if closed else None
        self.foot = FootForceControl(options.foot, dt) if closed and options.foot is not None else None
        self._on_error = level == "adaptive" and options.measured_replanning == "on-error"
        self._last_error_replan = -math.inf
        tau = options.measurement_filter
        self._smoothing = 1.0 if tau == 0.0 else -math.expm1(-dt / tau)
        # A known external force (a person's pull on the hand): the robot leans against it (set_external_force).
        self.external = ExternalForce(info.mass, planner.w, dt)
        self._polygon_key: tuple[float, ...] | None = None
        self._polygon: np.ndarray | None = None
        self.reset()

    def reset(self) -> None:
        """Zero the feedback states and forget the feet's landing states (called by :meth:`start`)."""
        if self.feedback is not None:
            self.feedback.reset()
        if self.foot is not None:
            self.foot.reset()
        self._filtered: list[float] | None = None  # zmp x, y; per foot: normal force, cop x, cop y
        self._phase = -1
        self._replans = self._adjustments = 0
        # Early touch-down: (x, y, yaw) where it landed, and the least height of its target (m).
        self._hold: list[tuple[float, float, float, float] | None] = [None, None]
        self._late = [False, False]  # the swing ended in the air ...
        self._late_from = [math.inf, math.inf]  # ... and from when (s) it counts as late
        self._landed = [True, True]  # whether the foot's last swing ended on the ground
        self._anchor: list[tuple[float, float, float] | None] = [None, None]  # the last re-anchored pose per foot
        self._swing_phase = [-2, -2]  # phase of each foot's last swing
        self._z = [0.0, 0.0]  # height of each foot's target above the plan (m): landing heights, late descent
        self._blend: list[tuple[float, float, float] | None] = [None, None]  # (height, swing start, duration)
        # A late foot that landed: its target's height returns from where it landed to the measured ground's, over
        # its stance's single support: (height at the landing, ground height, from, until) (m, m, s, s).
        self._ground: list[tuple[float, float, float, float] | None] = [None, None]
        # A re-anchored or held foot's IK target is blended to where the foot is to stand (rtgait.sim.target_blend).
        self._blends = (FootBlend("left"), FootBlend("right"))
        # The pose (x, y, yaw) a landing of this tick sends the foot to, when its target is to be blended there.
        self._moved: list[tuple[float, float, float] | None] = [None, None]
        self._last_ik: tuple[Pose, Pose] | None = None  # the IK's feet targets of the last tick

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

    # ----- the tick ------------------------------------------------------------------------------------------------
    def tick(self, t: float, measurement: Measurement) -> ControlTargets:
        """The IK targets at ``t`` (s) for this tick's measurement (:class:`~rtgait.sim.measure.Measurement`)."""
        external = self.external
        leaning = external.active
        if leaning:  # plan and feed back in the frame of the unpulled pendulum (external_force.py)
            rate = external.rate
            measurement = shifted_measurement(
                measurement, (-external.offset[0], -external.offset[1]), (-rate[0], -rate[1]), self.planner.w
            )
        planner, m = self.planner, measurement
        adaptive = self.level == "adaptive"
        events: list[ControlEvent] = []
        if adaptive:
            planner.observe(t, m.com[:2], m.com_vel[:2])  # with "always", may replan at once (DCM error)
        values, support, q = planner.sample_values(t)
        if self._on_error and self._dcm_error_replan(t, m, values, support, q, events):
            values, support, q = planner.sample_values(t)
        if q != self._phase:
            held = (self._hold[0] is not None, self._hold[1] is not None)
            before = self._targets(values) if held[0] or held[1] else None
            self._enter_phase(q, support, m)  # ends the holds of early landings
            if before is not None:
                after = self._targets(values)
                goals = [(a[0], a[1], a[3]) if h else None for a, h in zip(after, held, strict=True)]
                self._start_blends(t, before, after, goals)
        self._update_heights(t)
        if m.landings:
            before = self._targets(values)
            for landing in m.landings:
                if self._landing(t, landing, values, support, q, events) and adaptive:
                    values, support, q = planner.sample_values(t)  # the touch-down replanned
            moved, self._moved = self._moved, [None, None]
            if moved[0] is not None or moved[1] is not None:
                self._start_blends(t, before, self._targets(values), moved)
        self._planner_events(t, events)

        left = self._foot_target(0, values[13:17])
        right = self._foot_target(1, values[17:21])
        planned_support = support
        support = self._support(t, support)
        planned_zmp = (values[9], values[10])
        com = (values[0], values[1], values[2])
        offsets = FootOffsets()
        zmp, com_offset = planned_zmp, (0.0, 0.0)
        if self.feedback is not None:
            zmp_measured, left_state, right_state = self._filter(m)
            polygon = self._support_polygon(support, left, right)
            # The DCM with the planner's w (the measurer's may differ), so that it compares with the plan's.
            w = planner.w
            dcm = (m.com[0] + m.com_vel[0] / w, m.com[1] + m.com_vel[1] / w)
            out = self.feedback.update(planned_zmp, (values[21], values[22]), dcm, polygon, None, zmp_measured)
            zmp, com_offset = out.zmp, out.com_offset
            com = (com[0] + com_offset[0], com[1] + com_offset[1], com[2])
            if self.foot is not None:
                split = split_zmp(zmp, left, right, self.sole, support)
                offsets = self.foot.update(split, left_state, right_state, support)
                left = (left[0], left[1], left[2] + offsets.left_height, left[3])
                right = (right[0], right[1], right[2] + offsets.right_height, right[3])
        if leaning:
            com = (com[0] + external.offset[0], com[1] + external.offset[1], com[2])
        if self._blends[0].active:  # the IK's targets only: the polygon and split have the feet where they are
            left = self._blends[0].apply(t, left)
        if self._blends[1].active:
            right = self._blends[1].apply(t, right)
        self._last_ik = (left, right)
        return ControlTargets(
            t, com, left, right, offsets, zmp, planned_zmp, com_offset, support, q, tuple(events) or _NO_EVENTS,
            planned_support, (values[21], values[22]),
        )  # fmt: skip

    def _dcm_error_replan(
        self, t: float, m: Measurement, values: list[float], support: str, q: int, events: list[ControlEvent]
    ) -> bool:
        """``"on-error"``: replan from the measured state when the measured DCM is more than ``replan_dcm_error`` off
        the plan's, as the core's ``observe`` does with ``feedback="measured"`` (at most every
        :data:`ERROR_REPLAN_INTERVAL`, not within :data:`ERROR_REPLAN_MIN_REMAINDER` of a phase's end); returns
        whether it replanned.

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
        threshold = self.options.replan_dcm_error
        w = self.planner.w
        ex = m.com[0] + m.com_vel[0] / w - values[21]
        ey = m.com[1] + m.com_vel[1] / w - values[22]
        if ex * ex + ey * ey <= threshold * threshold or t - self._last_error_replan < ERROR_REPLAN_INTERVAL:
            return False
        planner = self.planner
        remainder = planner.phase_start(q) + planner.timeline.duration(q) - t
        if remainder < ERROR_REPLAN_MIN_REMAINDER:
            return False
        self._last_error_replan = t
        adjust = self.options.step_adjustment
        if self._only_crossing_catches(values, support, ex, ey) and not _lengthens(adjust):
            events.append(ControlEvent(t, "replan-skipped", support, "outward DCM error in single support"))
            return False
        if adjust is not None and support in _SIDES and remainder < adjust.min_time_to_touchdown:
            adjust = dataclasses.replace(adjust, on_failure="keep")  # the core moves the next step's landing
        replanned = planner.replan_now(t, "dcm-error", feedback="measured", step_adjustment=adjust or False)
        if replanned is not None and self.options.com_reference == "planned":
            # The footsteps are the measured state's; the COM goes on from where the plan had it, so that the
            # servos keep pulling the robot back: the plan under way remade from the state sampled before.
            planner.observe(t, (values[0], values[1]), (values[3], values[4]))
            planner.replan_now(t, "dcm-error-plan", feedback="measured", step_adjustment=False)
            planner.observe(t, m.com[:2], m.com_vel[:2])
        return replanned is not None

    @staticmethod
    def _only_crossing_catches(values: list[float], support: str, ex: float, ey: float) -> bool:
        """Whether, in a single support, the DCM error ``(ex, ey)`` (m) points outward from the stance foot more
        than along it: the capture point then moves away from where the swing foot may land (the stride box keeps
        it on its own side, the leg collision model would refuse a crossing step), so no landing catches it and
        the plan under way is kept: unless step timing adaptation may lengthen the single support
        (``max_single_support``), when the replan's decision may hold the stance longer (:func:`_lengthens`)."""
        if support not in _SIDES:
            return False
        i = 13 if support == "left" else 17  # the stance foot's (x, y, z, yaw) in the sample
        yaw = values[i + 3]
        c, s = math.cos(yaw), math.sin(yaw)
        along, lateral = c * ex + s * ey, -s * ex + c * ey
        outward = lateral if support == "left" else -lateral
        return outward > abs(along)

    # ----- landings and the feet's targets ---------------------------------------------------------------------------
    def _enter_phase(self, q: int, support: str, m: Measurement) -> None:
        """Bookkeeping when the plan enters phase ``q``: a swing that ended in the air is late; a new swing blends
        its foot's landing height out and forgets the last landing."""
        previous = self._phase
        self._phase = q
        for i in (0, 1):
            hold = self._hold[i]
            if hold is not None:  # an early touch-down holds until the swing's end (the plan's z = 0 there)
                self._z[i], self._hold[i] = max(self._z[i], hold[3]), None
            if self._swing_phase[i] != previous or previous < 0:
                continue
            if self._blend[i] is not None:  # the swing is over: so is the blend of its foot's height
                self._blend[i], self._z[i] = None, 0.0
            if not self._landed[i]:
                loaded = (m.left, m.right)[i].loaded
                self._late[i] = self.level == "adaptive" and not loaded
                self._late_from[i] = self.planner.phase_start(q) + self.options.late_grace
                self._landed[i] = loaded
        if support in _SIDES:  # a single support: the other foot lifts off
            i = 1 if support == "left" else 0
            self._swing_phase[i] = q
            self._landed[i] = self._late[i] = False
            self._ground[i] = None
            planner = self.planner
            self._blend[i] = (self._z[i], planner.phase_start(q), planner.timeline.duration(q))

    def _landing(
        self, t: float, landing: Landing, values: list[float], support: str, q: int, events: list[ControlEvent]
    ) -> bool:
        """Classify a landing and, in ``"adaptive"``, act on it; returns whether the planner replanned."""
        i = 0 if landing.side == "left" else 1
        planner = self.planner
        swinging = support in _SIDES and _SIDES[i] != support  # the plan has this foot swinging
        if self._landed[i] or not (swinging or q == self._swing_phase[i] + 1):
            kind = "re-landing"  # it bounced, or a standing foot was unloaded and loaded again
        elif swinging:
            start, duration = planner.phase_start(q), planner.timeline.duration(q)
            if start + duration - t <= self.options.on_time_window:
                kind = "on time"  # the foot follows the plan down: nothing to switch
            elif t - start >= self.options.early_touchdown_fraction * duration:
                kind = "early"
            else:
                kind = "ignored"
        else:
            kind = "late" if self._late[i] and t >= self._late_from[i] else "on time"
        events.append(ControlEvent(t, "landing", landing.side, kind, landing.x, landing.y))
        if kind == "ignored" or self.level != "adaptive":
            return False
        anchor = self._anchor[i]
        if kind == "re-landing" and anchor is not None:
            tolerance = self.options.relanding_tolerance
            moved = math.hypot(landing.x - anchor[0], landing.y - anchor[1])
            if moved < tolerance and abs(math.remainder(landing.yaw - anchor[2], math.tau)) < 2.0 * tolerance:
                return False  # where it was anchored: nothing to re-anchor
        self._landed[i] = True
        if self._late[i] and t >= self._late_from[i]:
            # Lowered to find the ground: stand where the sole met it. The target went below the plan because the
            # foot was higher than planned when the swing ended (a body that rose or rolled, or a lower ground);
            # the measured sole height is the ground's, and keeping the target's own depth instead would extend
            # the stance leg, lift the body and make the next landing later still. The target returns to it over
            # the single support this foot carries next (a loaded foot's target moved at the descent's speed made
            # the ankle damping chatter).
            limit = self.options.late_descent_limit
            ground = min(0.0, max(-limit, landing.z))
            stance = q + 1 if support == "double" else q
            until = planner.phase_start(stance) + planner.timeline.duration(stance)
            self._ground[i] = (self._z[i], ground, t, max(until, t + self.dt))
        self._late[i] = False
        if kind == "early":
            # Stand on it from now on where it landed; it goes on down with the plan (a stiff robot sags: most early
            # landings are that), but no further than late_descent_limit below where it touched (a higher ground).
            self._blend[i] = None
            floor = values[15 + 4 * i] + self._z[i] - self.options.late_descent_limit
            self._hold[i] = (landing.x, landing.y, landing.yaw, floor)
            self._moved[i] = (landing.x, landing.y, landing.yaw)
        # A swinging foot's target goes on from where it is to where it landed over what is left of the swing (the
        # planner's retargeted swing, smooth): blended only when that is shorter than anchor_blend.
        remainder = planner.phase_start(q) + planner.timeline.duration(q) - t if swinging else 0.0
        try:
            index = planner.touchdown(t, landing.side, landing.x, landing.y, landing.yaw)
        except (ValueError, RuntimeError) as error:
            events.append(ControlEvent(t, "touchdown-refused", landing.side, str(error), landing.x, landing.y))
            return False
        self._anchor[i] = (landing.x, landing.y, landing.yaw)
        if remainder < self.options.anchor_blend:
            self._moved[i] = (landing.x, landing.y, landing.yaw)
        events.append(ControlEvent(t, "touchdown", landing.side, f"footprint {index}", landing.x, landing.y))
        return True

    def _update_heights(self, t: float) -> None:
        """This tick's height offsets of the feet's targets (m): a landing height blended out over the swing that
        follows it, or the descent of a late foot."""
        for i in (0, 1):
            blend = self._blend[i]
            if blend is not None:
                height, start, duration = blend
                s = (t - start) / duration
                if s >= 1.0:
                    self._blend[i] = None
                    self._z[i] = 0.0
                else:
                    self._z[i] = height * (1.0 - max(s, 0.0))
            elif self._late[i] and t >= self._late_from[i]:
                limit = self.options.late_descent_limit
                self._z[i] = max(self._z[i] - self.options.late_descent_speed * self.dt, -limit)
            elif (ground := self._ground[i]) is not None:  # landed late: back to the ground's height
                landed, level, start, until = ground
                s = (t - start) / (until - start)
                if s >= 1.0:
                    self._z[i], self._ground[i] = level, None
                else:
                    self._z[i] = landed + (level - landed) * max(s, 0.0)

    def _foot_target(self, i: int, planned: list[float]) -> tuple[float, float, float, float]:
        """Foot ``i``'s target ``(x, y, z, yaw)`` before foot force control."""
        hold = self._hold[i]
        if hold is not None:  # early touch-down: where it landed, down with the plan to a floor
            return (hold[0], hold[1], max(planned[2] + self._z[i], hold[3]), hold[2])
        return (planned[0], planned[1], planned[2] + self._z[i], planned[3])

    def _targets(self, values: list[float]) -> tuple[Pose, Pose]:
        """Both feet's targets ``(x, y, z, yaw)`` before foot force control, for the sample ``values``."""
        return self._foot_target(0, values[13:17]), self._foot_target(1, values[17:21])

    def _start_blends(
        self,
        t: float,
        before: tuple[Pose, Pose],
        after: tuple[Pose, Pose],
        goals: Sequence[tuple[float, float, float] | None],
    ) -> None:
        """Blend the IK's targets of the feet re-anchored or held at ``t`` (s) over ``anchor_blend`` to the poses
        ``goals`` (x, y, yaw; ``None``: not this foot) they are to stand at (:mod:`rtgait.sim.target_blend`), from
        where the IK had them: ``before`` and ``after`` are the tick's targets without and with the change."""
        duration = self.options.anchor_blend
        if duration <= 0.0:
            return
        last, rate = self._last_ik, 1.0 / self.dt
        for i in (0, 1):
            goal = goals[i]
            if goal is None:
                continue
            old = self._blends[i].apply(t, before[i])  # a blend under way goes on from where it has the target
            previous = old if last is None else last[i]
            vx, vy = (old[0] - previous[0]) * rate, (old[1] - previous[1]) * rate
            vyaw = math.remainder(old[3] - previous[3], math.tau) * rate
            self._blends[i].start(t, old, (vx, vy, vyaw), goal, old[2] - after[i][2], duration)

    def _support(self, t: float, planned: str) -> str:
        """The feet the controller acts on: the plan's, both after an early touch-down, the other while late."""
        if planned in _SIDES:
            swing = 1 if planned == "left" else 0
            return "double" if self._hold[swing] is not None else planned
        late_left = self._late[0] and t >= self._late_from[0]
        late_right = self._late[1] and t >= self._late_from[1]
        if late_left != late_right:
            return "right" if late_left else "left"
        return planned

    def _support_polygon(self, support: str, left: tuple[float, ...], right: tuple[float, ...]) -> np.ndarray:
        """The support polygon of the feet in contact (cached until they move)."""
        chosen = [(pose, side) for pose, side in ((left, "left"), (right, "right")) if support in ("double", side)]
        key = tuple(v for pose, _ in chosen for v in (pose[0], pose[1], pose[3]))
        if key != self._polygon_key or self._polygon is None:
            feet = [Footstep(pose[0], pose[1], pose[3], side) for pose, side in chosen]  # type: ignore[arg-type]
            self._polygon, self._polygon_key = support_polygon(feet, self.sole), key
        return self._polygon

    # ----- measurements and the planner's log ----------------------------------------------------------------------
    def _filter(self, m: Measurement) -> tuple[tuple[float, float] | None, FootState, FootState]:
        """The measured ZMP and feet with their loads and CoPs low-passed (NaN restarts a filter)."""
        raw = [*m.zmp, m.left.normal_force, *m.left.cop_local, m.right.normal_force, *m.right.cop_local]
        state = self._filtered
        if state is None or self._smoothing == 1.0:
            state = raw
        else:
            a = self._smoothing
            state = [r if (s != s or r != r) else s + a * (r - s) for s, r in zip(state, raw, strict=True)]
        self._filtered = state
        zx, zy, fl, lx, ly, fr, rx, ry = state
        left = m.left._replace(normal_force=fl, cop_local=(lx, ly))
        right = m.right._replace(normal_force=fr, cop_local=(rx, ry))
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
        (:mod:`rtgait.sim.external_force`); ``"open-loop"`` ignores it (the paper's robot knows nothing)."""
        if self.level != "open-loop":
            self.external.set(force, height)

    def set_level(self, level: Controller) -> None:
        """Switch to controller level ``level`` (``"open-loop"``, ``"stabilized"``, ``"adaptive"``) mid-walk or
        before the start, without a jump in the IK's targets.

        The planner and its plan go on as they are (no replan at the switch); its settings become the new level's,
        made from its current ones as :func:`make_controller` makes them (:func:`~rtgait.core.closed_loop.
        controller_config`: measured-state replanning, the DCM-error threshold and step adjustment for
        ``"adaptive"`` only). What each switch starts, stops or resets:

        * to a closed level from ``"open-loop"``: a new DCM feedback law and foot force control, from zero state
          (no COM or foot offset, an empty integral), so the targets start from the plan's; the commanded ZMP steps
          to the law's (it is no IK target: the foot force control it drives integrates from zero);
        * to ``"open-loop"``: the COM and foot offsets held at the switch fade out over
          :data:`rtgait.sim.level_fade.LEVEL_FADE` (0.2 s, smooth) instead of vanishing
          (:mod:`rtgait.sim.level_fade`), then the feedback and foot force control are dropped;
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
        if level not in CONTROLLERS:
            raise ValueError(f"level must be one of {', '.join(CONTROLLERS)}, got {level!r}")
        if level == self.level:
            return
        from rtgait.sim.level_fade import LEVEL_FADE, FeedbackFade, FootFade

        options, planner = self.options, self.planner
        adjust = controller_step_adjustment(options, self.info) if level == "adaptive" else None
        config = controller_config(
            planner.config, level, self.sole, replan_dcm_error=options.replan_dcm_error, step_adjustment=adjust
        )
        if level == "adaptive" and options.measured_replanning == "on-error":
            self.options = options = dataclasses.replace(options, step_adjustment=adjust)
            config = dataclasses.replace(config, feedback="planned", step_adjustment=None)
        planner.config = config
        if self.level == "open-loop":  # up: new laws from zero state (a fade under way goes on around them)
            feedback = DcmFeedback(planner.w, options.gains, self.dt)
            foot = FootForceControl(options.foot, self.dt) if options.foot is not None else None
            if isinstance(self.feedback, FeedbackFade):
                self.feedback.inner = feedback
            else:
                self.feedback = feedback
            if isinstance(self.foot, FootFade):
                self.foot.inner = foot
            else:
                self.foot = foot
        elif level == "open-loop":  # down: fade the offsets out (nothing to fade before the start)
            ticks = max(1, round(LEVEL_FADE / self.dt))
            offset = self.feedback.com_offset if self.feedback is not None else (0.0, 0.0)
            offsets = self.foot.offsets if self.foot is not None else FootOffsets()
            moved = any(offset) or any(offsets)
            self.feedback = FeedbackFade(self, None, offset, ticks) if moved else None
            self.foot = FootFade(self, None, offsets, ticks) if moved and self.foot is not None else None
        self._on_error = level == "adaptive" and options.measured_replanning == "on-error"
        if level == "adaptive":
            self._last_error_replan = -math.inf
        else:
            self._late = [False, False]
        self.level = level


def _lengthens(adjust: StepAdjustment | None) -> bool:
    """Whether step adjustment ``adjust`` may give a step a longer single support: then a DCM error toward the
    stance foot's outside has an answer, the stance held longer while the sole's centre of pressure at its outer
    edge brings the DCM back, and the controller replans for it."""
    return adjust is not None and adjust.adapt_timing and adjust.max_single_support is not None


def make_controller(
    level: Controller,
    planner_config: PlannerConfig,
    strides: Sequence[Stride] | None,
    sole: SoleRect,
    robot: RobotInfo | RobotModel,
    *,
    dt: float = 0.001,
    options: ControllerOptions | None = None,
) -> WalkingController:
    """A controller of level ``level`` (``"open-loop"``, ``"stabilized"``, ``"adaptive"``) with its own planner.

    Args:
        level: the controller level (module docstring).
        planner_config: the planner's base configuration; the level's is made from it by
            :func:`~rtgait.core.closed_loop.controller_config` (the levels differ only by what the loop adds).
        strides: the walk; ``None`` to walk by velocity command.
        sole: the sole rectangle (m), for support polygons, the ZMP split and step adjustment.
        robot: a :class:`RobotInfo` or a loaded :class:`~rtgait.robot.model.RobotModel`.
        dt: control period (s).
        options: feedback gains and landing handling (:class:`ControllerOptions`).
    """
    options = options or ControllerOptions()
    info = robot if isinstance(robot, RobotInfo) else RobotInfo.from_robot(robot, sole)
    if info.sole != sole:
        info = dataclasses.replace(info, sole=sole)
    adjust = controller_step_adjustment(options, info) if level == "adaptive" else None
    config = controller_config(
        planner_config, level, sole, replan_dcm_error=options.replan_dcm_error, step_adjustment=adjust
    )
    if level == "adaptive" and options.measured_replanning == "on-error":
        # The controller takes the measured state in, and steps elsewhere, only on a DCM error (_dcm_error_replan).
        options = dataclasses.replace(options, step_adjustment=adjust)
        config = dataclasses.replace(config, feedback="planned", step_adjustment=None)
    return WalkingController(level, OnlinePlanner(config, strides), info, dt, options)
