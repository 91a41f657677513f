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

import dataclasses
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
    "SIM_COP_ADMITTANCE",
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

SIM_COP_ADMITTANCE = 0.002
"""Ankle damping gain ``K`` of the MuJoCo levels (rad/(N m s)), a fifth of lipm_walking_controller's 0.01 for HRP-4
(:class:`~rtgait.sim.foot_control.FootControlGains`). The CoP loop's rate is ``K`` times the stiffness that turns an
ankle tilt into a sole moment: on HRP-2 and HRP-4 the rubber bushes of the foot set it, some 10^3 N m/rad; here it is
the stiff ankle servo (Talos 2.7e5 N m/rad, G1 6e4) in series with MuJoCo's sole contact, some 10^4 N m/rad, so
0.01 made the loop faster than the 5 ms filter and the tick: the tilts chattered at their rate limit and fig8 fell,
on Talos and on G1. Measured (``stabilized``, fig6/7/8): 0.001-0.003 walk on both robots, the measured ZMP 2-5 mm
closer to the plan than without ankle damping."""

ERROR_REPLAN_INTERVAL = 0.05
"""Least time (s) between two replans of ``"adaptive"`` triggered by a DCM error: a replan from the measured state
zeroes the error, so a new one means a new disturbance (the core's own interval for ``feedback="measured"``)."""

ERROR_REPLAN_MIN_REMAINDER = 0.1
"""Shortest remainder of a phase (s) over which a DCM error triggers a replan; closer to the phase's end the free ZMP
polynomial would need wild swings, and the error is taken in at the next phase's first tick (as the core does)."""

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
        foot: foot force control gains, default its defaults with ``cop_admittance`` = :data:`SIM_COP_ADMITTANCE`;
            ``None`` turns foot force control off.
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
        on_time_window: a touch-down this little before the plan's (s) is on time, not early: the foot goes on down
            with the plan and support switches with it. The swing's height profile ends flat (2 mm at 70 ms before
            the touch-down, :mod:`rtgait.core.swing`), so a robot whose stance side gives 2 mm touches that early at
            every step (G1 does: its body rolls 5-8 mrad toward the swing foot); switching support at each of those
            touches made G1 fall on fig6 and fig8, while with this window it walks them.
        relanding_tolerance: a foot that lands again (after a bounce, or a standing foot unloaded and loaded
            again) is re-anchored only when it moved this far (m; its heading twice this in rad) from where it was
            anchored: a bounce in place would only replan for nothing.
        late_grace: a foot not on the ground when its swing ends counts as late only this long (s) after: the
            landing's detection lags the touch (MuJoCo's soft contact reaches the landing force a few milliseconds
            after the sole touches; Talos's landings were detected 2-9 ms after the planned touch-down), and a foot
            lowered for that lag stood its whole stance 1-2 mm below the floor, pressing against the other.
        measured_replanning: ``"adaptive"``: when a plan starts from the measured COM state. ``"on-error"``
            (default): only when the measured DCM is more than ``replan_dcm_error`` off the plan's (a disturbance);
            every other plan (the regular double-support replans, the re-anchoring at landings, the start) continues
            the plan under way. ``"always"``: every plan, the core's ``feedback="measured"`` (module docstring).
    """

    gains: DcmFeedbackGains = field(default_factory=lambda: DcmFeedbackGains(com_admittance=SIM_COM_ADMITTANCE))
    foot: FootControlGains | None = field(default_factory=lambda: FootControlGains(cop_admittance=SIM_COP_ADMITTANCE))
    measurement_filter: float = 0.005
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR
    step_adjustment: StepAdjustment | None = None
    early_touchdown_fraction: float = 0.5
    late_descent_speed: float = 0.3
    late_descent_limit: float = 0.02
    measured_replanning: str = "on-error"
    late_grace: float = 0.01
    on_time_window: float = 0.08
    relanding_tolerance: float = 0.01
    com_reference: str = "measured"

    def __post_init__(self) -> None:
        names = ("measurement_filter", "late_descent_speed", "late_descent_limit", "late_grace", "on_time_window",
                 "relanding_tolerance")  # fmt: skip
        for name in names:
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 10.0):
                raise ValueError(f"ControllerOptions.{name} must be within [0, 10], got {value}")
        if self.com_reference not in ("measured", "planned"):
            raise ValueError(f"com_reference must be 'measured' or 'planned', got {self.com_reference!r}")
        if self.measured_replanning not in ("on-error", "always"):
            raise ValueError(f"measured_replanning must be 'on-error' or 'always', got {self.measured_replanning!r}")
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
        planned_support: the plan's support at this tick (``"double"``, ``"left"``, ``"right"``).
        dcm_planned: the plan's DCM (m).
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
    planned_support: str = "double"
    dcm_planned: tuple[float, float] = (math.nan, math.nan)

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
        self._on_error = level == "adaptive" and options.measured_replanning == "on-error"
        self._last_error_replan = -math.inf
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
        self._late = [False, False]  # the swing ended in the air ...
        self._late_from = [math.inf, math.inf]  # ... and from when (s) it counts as late
        self._landed = [True, True]  # whether the foot's last swing ended on the ground
        self._anchor: list[tuple[float, float, float] | None] = [None, None]  # the last re-anchored pose per foot
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
        planner, m = self.planner, measurement
        adaptive = self.level == "adaptive"
        events: list[ControlEvent] = []
        if adaptive:
            planner.observe(t, m.com[:2], m.com_vel[:2])  # with "always", may replan at once (DCM error)
        values, support, q = planner.sample_values(t)
        if self._on_error and self._dcm_error_replan(t, m, values, q):
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
        return ControlTargets(
            t, com, left, right, offsets, zmp, planned_zmp, com_offset, support, q, tuple(events) or _NO_EVENTS,
            planned_support, (values[21], values[22]),
        )  # fmt: skip

    def _dcm_error_replan(self, t: float, m: Measurement, values: list[float], q: int) -> bool:
        """``"on-error"``: replan from the measured state when the measured DCM is more than ``replan_dcm_error`` off
        the plan's, as the core's ``observe`` does with ``feedback="measured"`` (at most every
        :data:`ERROR_REPLAN_INTERVAL`, not within :data:`ERROR_REPLAN_MIN_REMAINDER` of a phase's end); returns
        whether it replanned."""
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
        # The core takes the measured state into a plan, and adjusts steps, when its configuration says so: for this
        # one replan.
        config = planner.config
        planner.config = dataclasses.replace(config, feedback="measured", step_adjustment=self.options.step_adjustment)
        try:
            replanned = planner.replan_now(t, "dcm-error") is not None
            if replanned and self.options.com_reference == "planned":
                # The footsteps are the measured state's; the COM goes on from where the plan had it, so that the
                # servos keep pulling the robot back: the plan under way remade from the state sampled before.
                planner.observe(t, (values[0], values[1]), (values[3], values[4]))
                planner.config = dataclasses.replace(config, feedback="measured")
                planner.replan_now(t, "dcm-error-plan")
                planner.observe(t, m.com[:2], m.com_vel[:2])
            return replanned
        finally:
            planner.config = config

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
        self._anchor[i] = (landing.x, landing.y, landing.yaw)
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

    def _foot_target(self, i: int, planned: list[float]) -> tuple[float, float, float, float]:
        """Foot ``i``'s target ``(x, y, z, yaw)`` before foot force control."""
        hold = self._hold[i]
        if hold is not None:  # early touch-down: where it landed, down with the plan to a floor
            return (hold[0], hold[1], max(planned[2] + self._z[i], hold[3]), hold[2])
        return (planned[0], planned[1], planned[2] + self._z[i], planned[3])

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
    if level == "adaptive" and options.measured_replanning == "on-error":
        # The controller takes the measured state in, and steps elsewhere, only on a DCM error (_dcm_error_replan).
        options = dataclasses.replace(options, step_adjustment=adjust)
        config = dataclasses.replace(config, feedback="planned", step_adjustment=None)
    return WalkingController(level, OnlinePlanner(config, strides), info, dt, options)
