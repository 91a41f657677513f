"""The controller levels of the MuJoCo loop: planner sample -> feedback -> IK targets, once per control tick.

Names and planner settings are those of :mod:`rtgait.core.closed_loop` (:func:`~rtgait.core.closed_loop.
controller_config`), the pendulum-level loop:

* ``"open-loop"``: the plan alone (the paper's assumption): COM and feet targets are the planner's sample.
* ``"stabilized"``: the DCM law (:class:`~rtgait.core.feedback.DcmFeedback`) on the measured DCM gives a commanded ZMP
  ``p_cmd`` and a COM correction ``d`` (COM admittance ``d' = -A (p_cmd - p_measured) - d / T_c``, added to the planned
  COM), and foot force control (:mod:`rtgait.sim.foot_control`) makes the feet produce ``p_cmd``: split between the
  feet in contact, each sole's CoP servoed by its ankle, the force difference by the feet's heights.
* ``"adaptive"``: ``"stabilized"`` with a planner that closes the loop: ``feedback="measured"`` and
  :meth:`~rtgait.core.online.OnlinePlanner.observe` every tick, ``replan_dcm_error``, step adjustment in a stride box
  sized for the robot (:func:`step_limits`), and landings. Every landing is reported with its measured pose
  (:meth:`~rtgait.core.online.OnlinePlanner.touchdown`: re-anchoring and an immediate replan). An *early* one (in the
  swing's second half, ``early_touchdown_fraction``) switches support at once: polygon and ZMP split take both feet
  until the plan's double support, and the foot stays where it landed while its target goes on down with the plan,
  at most ``late_descent_limit`` below where it touched (a stiff robot sags, so on flat ground it lands early; on a
  higher ground the foot must not push the robot up). A *late* one (the swing is over, the foot carries nothing):
  the other foot carries the robot and the foot's target descends at ``late_descent_speed`` to ``late_descent_limit``
  below the plan (auto_stabilizer ``FootStepGenerator.h``: ``touchVel`` 0.3 m/s, ``goalOffset`` -0.02 m); unlike
  auto_stabilizer the plan is not delayed. A foot keeps the height it landed at while it stands, and sheds it
  linearly over its next swing.

All on Python floats; the support polygon (numpy) is rebuilt only when the feet in contact move.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

from rtgait.core.closed_loop import CONTROLLERS, DEFAULT_REPLAN_DCM_ERROR, Controller, controller_config
from rtgait.core.config import PlannerConfig
from rtgait.core.feedback import DcmFeedback, DcmFeedbackGains
from rtgait.core.footsteps import Footstep, Side, SoleRect, Stride
from rtgait.core.online import OnlinePlanner
from rtgait.core.stepping import StepAdjustment
from rtgait.core.support import support_polygon
from rtgait.robot.ik import IKTargets
from rtgait.sim.foot_control import FootControlGains, FootForceControl, FootOffsets, split_zmp

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy as np

    from rtgait.robot.model import RobotModel
    from rtgait.sim.measure import FootState, Landing, Measurement

__all__ = [
    "CONTROLLERS",
    "SIM_COM_ADMITTANCE",
    "ControlEvent",
    "ControlTargets",
    "ControllerOptions",
    "RobotInfo",
    "WalkingController",
    "make_controller",
    "step_limits",
]

SIM_COM_ADMITTANCE = 0.5
"""COM admittance ``A`` of the MuJoCo levels (1/s): the value used on HRP-2Kai with mc_rtc's ZMPCC (mc_rtc PR #16,
``closed_loop_anchors.md`` 1.2). lipm_walking_controller runs HRP-4 with it off, the feet alone realising the ZMP.
Talos in MuJoCo, stiff position servos, 6 steps of 0.1 m at 0.7/0.1 s with a 0.1 s push on the pelvis mid single
support: with ``A = 0`` the measured ZMP strayed 52 mm RMS from the plan and a 25 N s outward push felled it; with
0.5, 22 mm, and it stood that push and a 40 N s inward one; with 2, 10 mm, but the inward push saturated the COM
offset (5 cm) and felled it."""

_NO_EVENTS: tuple[ControlEvent, ...] = ()
_SIDES: tuple[Side, Side] = ("left", "right")


@dataclass(frozen=True)
class RobotInfo:
    """What the controllers need to know about the robot (SI units).

    Attributes:
        mass: (kg).
        sole: the sole rectangle around the sole frame (m).
        leg_length: scale of the stride box (m): the walking COM height serves (:meth:`from_robot`).
    """

    mass: float
    sole: SoleRect
    leg_length: float

    @classmethod
    def from_robot(cls, robot: RobotModel, sole: SoleRect | None = None) -> RobotInfo:
        """From a loaded robot: its mass, its described sole (or ``sole``) and its walking COM height."""
        return cls(robot.mass, sole or robot.description.sole, robot.description.cog_height)


def step_limits(info: RobotInfo) -> StepAdjustment:
    """Step adjustment's stride box for a robot: :class:`~rtgait.core.stepping.StepAdjustment`'s defaults (set for an
    HRP-2-like walk, COM 0.8 m high: 0.35 m forward or back, 0.12-0.45 m sideways) scaled by ``leg_length / 0.8``, with
    the soles kept 2 cm apart at the least; its swing speed and last-moment limits as they are (no change in the
    last 0.2 s before touch-down: auto_stabilizer's ``overwritableRemainTime``)."""
    scale = info.leg_length / 0.8
    min_width = max(0.12 * scale, 2.0 * info.sole.inner + 0.02)
    max_width = max(0.45 * scale, min_width + 0.1)
    return StepAdjustment(info.sole, max_length=0.35 * scale, min_width=min_width, max_width=max_width)


@dataclass(frozen=True)
class ControllerOptions:
    """Settings of the ``"stabilized"`` and ``"adaptive"`` levels.

    Attributes:
        gains: DCM law and COM admittance; default the core law's gains with ``com_admittance`` =
            :data:`SIM_COM_ADMITTANCE`.
        foot: foot force control gains; ``None`` turns foot force control off.
        measurement_filter: time constant of the first-order low-pass on the measured ZMP and feet loads and CoPs
            before they are fed back (s); 0: none. MuJoCo's contact forces answer the stiff servos within a tick:
            fed back raw, they made Talos's ankle tilts chatter to their clamp (ZMP 101 mm RMS from the plan, against
            22 mm with 5 ms).
        replan_dcm_error: ``"adaptive"``: DCM error that triggers an immediate replan (m).
        step_adjustment: ``"adaptive"``: stride box and limits; default :func:`step_limits` of the robot.
        early_touchdown_fraction: a landing counts as an early touch-down from this fraction of the swing on; before,
            it is ignored (a scuff).
        late_descent_speed: how fast a late foot's target goes down (m/s).
        late_descent_limit: how far below the plan it goes at most (m); also how far below where it touched an
            early-landed foot's target goes on down.
    """

    gains: DcmFeedbackGains = field(default_factory=lambda: DcmFeedbackGains(com_admittance=SIM_COM_ADMITTANCE))
    foot: FootControlGains | None = field(default_factory=FootControlGains)
    measurement_filter: float = 0.005
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR
    step_adjustment: StepAdjustment | None = None
    early_touchdown_fraction: float = 0.5
    late_descent_speed: float = 0.3
    late_descent_limit: float = 0.02

    def __post_init__(self) -> None:
        for name in ("measurement_filter", "late_descent_speed", "late_descent_limit"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 10.0):
                raise ValueError(f"ControllerOptions.{name} must be within [0, 10], got {value}")
        if not 0.0 <= self.early_touchdown_fraction <= 1.0:
            raise ValueError(f"early_touchdown_fraction must be within [0, 1], got {self.early_touchdown_fraction}")


class ControlEvent(NamedTuple):
    """Something for the log: ``kind`` is ``"landing"`` (``detail`` early, on time, late, re-landing or ignored),
    ``"touchdown"`` (the planner re-anchored ``side`` at ``(x, y)``), ``"touchdown-refused"``, ``"step-adjustment"``
    (``x, y``: the new landing) or ``"replan"`` (``detail``: the planner's reason)."""

    t: float
    kind: str
    side: str
    detail: str
    x: float = math.nan
    y: float = math.nan


class ControlTargets(NamedTuple):
    """One tick's output (world frame, SI units).

    Attributes:
        t: time (s).
        com: COM target ``(x, y, z)`` for the IK (m): the plan's plus the COM correction.
        left_foot, right_foot: sole targets ``(x, y, z, yaw)`` (m, rad), the foot-control heights included.
        offsets: the foot force control's output (its tilts go to the ankles, :func:`~rtgait.sim.foot_control.
            add_ankle_offsets`; its heights are already in the feet's z).
        zmp_command: the commanded ZMP (m); the planned one in ``"open-loop"``.
        zmp_planned: the planner's ZMP (m).
        com_offset: the COM correction ``d`` (m).
        support: the support the controller acts on (``"double"``, ``"left"``, ``"right"``): the plan's, or after an
            early or late touch-down the feet really on the ground.
        phase: the planner's phase index.
        events: what happened at this tick (:class:`ControlEvent`).
    """

    t: float
    com: tuple[float, float, float]
    left_foot: tuple[float, float, float, float]
    right_foot: tuple[float, float, float, float]
    offsets: FootOffsets
    zmp_command: tuple[float, float]
    zmp_planned: tuple[float, float]
    com_offset: tuple[float, float]
    support: str
    phase: int
    events: tuple[ControlEvent, ...]

    @property
    def ik(self) -> IKTargets:
        """The whole-body IK's targets."""
        return IKTargets(self.com, self.left_foot, self.right_foot)


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
        tau = options.measurement_filter
        self._smoothing = 1.0 if tau == 0.0 else -math.expm1(-dt / tau)
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
        self._late = [False, False]
        self._landed = [True, True]  # whether the foot's last swing ended on the ground
        self._swing_phase = [-2, -2]  # phase of each foot's last swing
        self._z = [0.0, 0.0]  # height of each foot's target above the plan (m): landing heights, late descent
        self._blend: list[tuple[float, float, float] | None] = [None, None]  # (height, swing start, duration)

    def start(self, t0: float, measurement: Measurement | None = None) -> None:
        """Start the walk at ``t0`` (s). ``"adaptive"`` with a measurement starts the planner from the measured feet
        and COM state; the other levels start from the plan's own standing feet (the paper's)."""
        self.reset()
        planner = self.planner
        if self.level == "adaptive" and measurement is not None:
            m = measurement
            feet = (m.left.footstep("left"), m.right.footstep("right"))
            planner.start(t0, feet=feet, cog=m.com[:2], cog_vel=m.com_vel[:2])
        else:
            planner.start(t0)
        self._replans, self._adjustments = planner.replan_count, planner.step_adjustment_count

    # ----- the tick ------------------------------------------------------------------------------------------------
    def tick(self, t: float, measurement: Measurement) -> ControlTargets:
        """The IK targets at ``t`` (s) for this tick's measurement (:class:`~rtgait.sim.measure.Measurement`)."""
        planner, m = self.planner, measurement
        adaptive = self.level == "adaptive"
        events: list[ControlEvent] = []
        if adaptive:
            planner.observe(t, m.com[:2], m.com_vel[:2])  # may replan at once (DCM error)
        values, support, q = planner.sample_values(t)
        if q != self._phase:
            self._enter_phase(q, support, m)
        self._update_heights(t)
        for landing in m.landings:
            if self._landing(t, landing, values, support, q, events) and adaptive:
                values, support, q = planner.sample_values(t)  # the touch-down replanned
        self._planner_events(t, events)

        left = self._foot_target(0, values[13:17])
        right = self._foot_target(1, values[17:21])
        support = self._support(support)
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
        return ControlTargets(
            t, com, left, right, offsets, zmp, planned_zmp, com_offset, support, q, tuple(events) or _NO_EVENTS
        )

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
                self._landed[i] = loaded
        if support in _SIDES:  # a single support: the other foot lifts off
            i = 1 if support == "left" else 0
            self._swing_phase[i] = q
            self._landed[i] = self._late[i] = False
            planner = self.planner
            self._blend[i] = (self._z[i], planner.phase_start(q), planner.timeline.duration(q))

    def _landing(
        self, t: float, landing: Landing, values: list[float], support: str, q: int, events: list[ControlEvent]
    ) -> bool:
        """Classify a landing and, in ``"adaptive"``, act on it; returns whether the planner replanned."""
        i = 0 if landing.side == "left" else 1
        planner = self.planner
        if support in _SIDES and _SIDES[i] != support:  # the plan has this foot swinging
            start, duration = planner.phase_start(q), planner.timeline.duration(q)
            kind = "early" if t - start >= self.options.early_touchdown_fraction * duration else "ignored"
        elif self._late[i]:
            kind = "late"
        else:
            kind = "on time" if q == self._swing_phase[i] + 1 else "re-landing"
        events.append(ControlEvent(t, "landing", landing.side, kind, landing.x, landing.y))
        if kind == "ignored" or self.level != "adaptive":
            return False
        self._landed[i] = True
        self._late[i] = False
        if kind == "early":
            # Stand on it from now on where it landed; it goes on down with the plan (a stiff robot sags: most early
            # landings are that), but no further than late_descent_limit below where it touched (a higher ground).
            self._blend[i] = None
            floor = values[15 + 4 * i] + self._z[i] - self.options.late_descent_limit
            self._hold[i] = (landing.x, landing.y, landing.yaw, floor)
        try:
            index = planner.touchdown(t, landing.side, landing.x, landing.y, landing.yaw)
        except (ValueError, RuntimeError) as error:
            events.append(ControlEvent(t, "touchdown-refused", landing.side, str(error), landing.x, landing.y))
            return False
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
            elif self._late[i]:
                limit = self.options.late_descent_limit
                self._z[i] = max(self._z[i] - self.options.late_descent_speed * self.dt, -limit)

    def _foot_target(self, i: int, planned: list[float]) -> tuple[float, float, float, float]:
        """Foot ``i``'s target ``(x, y, z, yaw)`` before foot force control."""
        hold = self._hold[i]
        if hold is not None:  # early touch-down: where it landed, down with the plan to a floor
            return (hold[0], hold[1], max(planned[2] + self._z[i], hold[3]), hold[2])
        return (planned[0], planned[1], planned[2] + self._z[i], planned[3])

    def _support(self, planned: str) -> str:
        """The feet the controller acts on: the plan's, both after an early touch-down, the other while late."""
        if planned in _SIDES:
            swing = 1 if planned == "left" else 0
            return "double" if self._hold[swing] is not None else planned
        late_left, late_right = self._late
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
                events.append(ControlEvent(t, "step-adjustment", "", decision.reason, x, y))
        new = planner.replan_count - self._replans
        if new:
            self._replans = planner.replan_count
            for record in list(planner.plans)[-new:]:
                if record.reason not in ("start", "double-support"):
                    events.append(ControlEvent(t, "replan", "", record.reason))


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
        info = RobotInfo(info.mass, sole, info.leg_length)
    adjust = (options.step_adjustment or step_limits(info)) if level == "adaptive" else None
    config = controller_config(
        planner_config, level, sole, replan_dcm_error=options.replan_dcm_error, step_adjustment=adjust
    )
    return WalkingController(level, OnlinePlanner(config, strides), info, dt, options)
