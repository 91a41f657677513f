"""The settings and the outputs of the MuJoCo controller levels (:mod:`rtgait.control.controller`): what the robot is
to the controller, its gains and landing handling, and what one tick gives the IK."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, NamedTuple

from rtgait.control.foot_control import FootControlGains, FootOffsets
from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.laws.feedback import DcmFeedbackGains
from rtgait.core.laws.hip_strategy import HipStrategyLimits
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.planner.levels import DEFAULT_REPLAN_DCM_ERROR
from rtgait.core.planner.measured import AUTO_MIN_REMAINDER, AUTO_REPLAN_INTERVAL
from rtgait.robot.ik import IKTargets

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = [
    "ERROR_REPLAN_INTERVAL",
    "ERROR_REPLAN_MIN_REMAINDER",
    "SIM_COM_ADMITTANCE",
    "SIM_COP_ADMITTANCE",
    "ControlEvent",
    "ControlTargets",
    "ControllerOptions",
    "RobotInfo",
    "controller_step_adjustment",
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
(:class:`~rtgait.control.foot_control.FootControlGains`). The CoP loop's rate is ``K`` times the stiffness that turns an
ankle tilt into a sole moment: on HRP-2 and HRP-4 the rubber bushes of the foot set it, some 10^3 N m/rad; here it is
the stiff ankle servo (Talos 2.7e5 N m/rad, G1 6e4) in series with MuJoCo's sole contact, some 10^4 N m/rad, so
0.01 made the loop faster than the 5 ms filter and the tick: the tilts chattered at their rate limit and fig8 fell,
on Talos and on G1. Measured (``stabilized``, fig6/7/8): 0.001-0.003 walk on both robots, the measured ZMP 2-5 mm
closer to the plan than without ankle damping."""

# The core's own thresholds for replans triggered by a DCM error (rtgait.core.planner.measured), under the names the
# MuJoCo
# controller uses: the least time between two, and the shortest phase remainder one is made over (s).
ERROR_REPLAN_INTERVAL = AUTO_REPLAN_INTERVAL
ERROR_REPLAN_MIN_REMAINDER = AUTO_MIN_REMAINDER


@dataclass(frozen=True)
class RobotInfo:
    """What the controllers need to know about the robot (SI units).

    Attributes:
        mass: (kg).
        sole: the sole rectangle around the sole frame (m).
        leg_length: scale of the stride box (m) when ``stepping`` is ``None``: the walking COM height serves
            (:meth:`from_robot`).
        stepping: the robot description's ``[stepping]`` limits (:class:`~rtgait.core.laws.stepping.SteppingLimits`),
            the stride box of step adjustment (:func:`step_limits`); ``None``: none described.
        lean: the upper body's lean inertia and acceleration limits for the hip strategy
            (:func:`rtgait.robot.lean.hip_strategy_limits`); ``None``: no hip strategy.
    """

    mass: float
    sole: SoleRect
    leg_length: float
    stepping: SteppingLimits | None = None
    lean: HipStrategyLimits | None = None

    @classmethod
    def from_robot(cls, robot: RobotModel, sole: SoleRect | None = None) -> RobotInfo:
        """From a loaded robot: its mass, its described sole (or ``sole``), its walking COM height, its
        ``[stepping]`` limits and its upper body's lean (none when its hips cannot make one)."""
        from rtgait.robot.lean import hip_strategy_limits

        description = robot.description
        try:
            lean = hip_strategy_limits(robot)
        except ValueError:
            lean = None
        return cls(robot.mass, sole or description.sole, description.cog_height, description.stepping, lean)


def step_limits(info: RobotInfo, stepping: SteppingLimits | None = None) -> StepAdjustment:
    """Step adjustment's stride box for a robot: ``stepping`` when given, else the robot description's
    ``[stepping]`` table (``info.stepping``, from ``robot.description.stepping``), else
    :class:`~rtgait.core.laws.stepping.StepAdjustment`'s defaults (set for an HRP-2-like walk, COM 0.8 m high: 0.35 m
    forward or back, 0.12-0.45 m sideways) scaled by ``leg_length / 0.8``, with the soles kept 2 cm apart at the
    least; its swing speed and last-moment limits as they are (no change in the last 0.2 s before touch-down:
    auto_stabilizer's ``overwritableRemainTime``)."""
    stepping = stepping if stepping is not None else info.stepping
    if stepping is not None:
        return stepping.adjustment(info.sole)
    scale = info.leg_length / 0.8
    min_width = max(0.12 * scale, 2.0 * info.sole.inner + 0.02)
    max_width = max(0.45 * scale, min_width + 0.1)
    return StepAdjustment(info.sole, SteppingLimits(max_length=0.35 * scale, min_width=min_width, max_width=max_width))


def controller_step_adjustment(options: ControllerOptions, info: RobotInfo) -> StepAdjustment:
    """The step adjustment of the ``"adaptive"`` level: ``options.step_adjustment``, else the robot's
    :func:`step_limits`; with ``options.adapt_timing``, its step timing adaptation on."""
    adjust = options.step_adjustment or step_limits(info)
    if options.adapt_timing and not adjust.adapt_timing:
        adjust = replace(adjust, adapt_timing=True)
    return adjust


@dataclass(frozen=True)
class ControllerOptions:
    """Settings of the ``"stabilized"`` and ``"adaptive"`` levels: the one home of the controller's gains and options.
    Files set them through ``[control]`` tables (:mod:`rtgait.control.control_table`; every key with its default,
    unit, range and source: ``docs/cli_and_scenarios.md``, "Controller settings").

    Attributes:
        dcm: the DCM law's gains and the COM admittance; default the core law's gains with ``com_admittance`` =
            :data:`SIM_COM_ADMITTANCE`.
        foot: foot force control gains, default its defaults with ``cop_admittance`` = :data:`SIM_COP_ADMITTANCE`;
            ``None`` turns foot force control off.
        measurement_filter: time constant of the first-order low-pass on the measured ZMP and feet loads and CoPs
            before they are fed back (s); 0: none. MuJoCo's contact forces answer the stiff servos within a tick:
            fed back raw, they made Talos's ankle tilts chatter to their clamp (ZMP 101 mm RMS from the plan, against
            22 mm with 5 ms).
        replan_dcm_error: ``"adaptive"``: DCM error that triggers an immediate replan (m).
        step_adjustment: ``"adaptive"``: stride box and limits; default :func:`step_limits` of the robot.
        adapt_timing: ``"adaptive"``: step adjustment may also change the single support of the step it moves
            (:class:`~rtgait.core.laws.stepping.StepAdjustment` ``adapt_timing``, Morisawa et al. 2006): shorten it,
            down to the limits' ``min_single_support``, and, where the limits set ``max_single_support``,
            lengthen it (a push toward the stance foot's outside, which no landing catches). On by default: on
            Talos and G1 it raised the pushes survived in 30 of 32 direction and phase pairs (README, "Pushes").
        early_touchdown_fraction: a landing counts as an early touch-down from this fraction of the swing on; before,
            it is ignored (a scuff).
        late_descent_speed: how fast a late foot's target goes down (m/s).
        late_descent_limit: how far below the plan it goes at most (m); also how far below where it touched an
            early-landed foot's target goes on down.
        on_time_window: a touch-down this little before the plan's (s) is on time, not early: the foot goes on down
            with the plan and support switches with it. The swing's height profile ends flat (2 mm at 70 ms before
            the touch-down, :mod:`rtgait.core.geometry.swing`), so a robot whose stance side gives 2 mm touches that
            early at
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
        anchor_blend: how long (s) a foot's IK target takes to go from where it was to where a re-anchoring (or the
            start or end of an early landing's hold) puts it, from its pose and rate then, along the quintic of the
            planner's retargeted swing (:func:`rtgait.core.geometry.swing.retargeted_swing`; the minimum-jerk ``10 s^3
            - 15 s^4 +
            6 s^5`` of ``s = (t - t_jump) / anchor_blend`` for a target at rest); 0: at once. A landed foot is
            re-anchored on its measured pose, a few millimetres (and milliradians) from its target; moved in one tick, a
            loaded foot's target steps and the commanded joint motion has the second difference of that step, an
            acceleration of ``jump / dt^2`` (3.7 mm in 1 ms: 3700 m/s^2 of the leg). Blended, its peak is ``5.77 jump /
            anchor_blend^2`` (13 m/s^2 for 3.7 mm in 40 ms) and it is continuous, so the commanded motion's ZMP is too.
            A swing foot re-anchored on time goes to where it landed along the planner's retargeted swing, smooth, over
            what is left of the swing; it is blended only when that is shorter than ``anchor_blend`` (on fig6-8 Talos
            lands 10-40 ms before the plan's touch-down, G1 30-70 ms; the retargeted swing of a landing 1 ms before it
            moved a loaded foot's target 2 mm in one tick). 40 ms: less than half of Talos's and G1's 0.1 s double
            support, so the blend of a late landing (10-15 ms into it) is over before that foot carries the robot alone.
            Only what the IK is asked is blended: the planner, the support polygon and the ZMP split have the foot where
            it was measured. Off by default (0): it takes the one-tick spikes out of the commanded motion's ZMP (Talos
            fig8 250 -> 21 mm RMS) without changing Talos's outcomes, but with 40 ms G1's 60 s forward walk at 0.3 m/s
            walked 0.26 m/s and fell at its end (60.4 s at a 0.5 ms physics step, 61.5 s at 0.25 ms), where without
            it G1 walks it at 0.30 m/s; why is not known yet.
        hip_strategy: the closed levels lean the upper body when the DCM law asks the feet for a ZMP beyond the
            support polygon (:mod:`rtgait.core.laws.hip_strategy`: the rate of angular momentum moves the CMP beyond the
            sole), with the robot's lean limits (:attr:`RobotInfo.lean`). On by default: it raised Talos's pushes
            survived in 12 of 16 direction and phase pairs (lowered them in 4), forward and backward in single
            support past 60 N s (docs/robots.md, "The hip strategy"); on G1, whose light upper body recovers at most
            about 1.6 N s, it changes them mostly within the bisection's scatter.
        max_lean: the hip strategy's largest lean on each axis (rad); 0.25 (14 degrees) stays inside Talos's and
            G1's hip roll ranges (+-0.52 rad) with the walking's own roll on top.
    """

    dcm: DcmFeedbackGains = field(default_factory=lambda: DcmFeedbackGains(com_admittance=SIM_COM_ADMITTANCE))
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
    adapt_timing: bool = True
    anchor_blend: float = 0.0
    hip_strategy: bool = True
    max_lean: float = 0.25

    def __post_init__(self) -> None:
        if not isinstance(self.dcm, DcmFeedbackGains):
            raise ValueError(f"ControllerOptions.dcm must be a DcmFeedbackGains, got {type(self.dcm).__name__}")
        if self.foot is not None and not isinstance(self.foot, FootControlGains):
            raise ValueError(f"ControllerOptions.foot must be a FootControlGains or None, got {self.foot!r}")
        if self.step_adjustment is not None and not isinstance(self.step_adjustment, StepAdjustment):
            raise ValueError(f"ControllerOptions.step_adjustment must be a StepAdjustment or None, got "
                             f"{type(self.step_adjustment).__name__}")  # fmt: skip
        for name, (low, high, unit) in _RANGES.items():
            value = getattr(self, name)
            number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            low_ok = number and (value > low if name in _OPEN_BELOW else value >= low)
            if not (low_ok and value <= high):
                interval = f"{'(' if name in _OPEN_BELOW else '['}{low:g}, {high:g}]"
                raise ValueError(f"ControllerOptions.{name} must be a number within {interval} {unit}, got {value!r}")
            object.__setattr__(self, name, float(value))  # a TOML integer as the float it stands for
        for name, choices in _CHOICES.items():
            if getattr(self, name) not in choices:
                allowed = " or ".join(repr(choice) for choice in choices)
                raise ValueError(f"ControllerOptions.{name} must be {allowed}, got {getattr(self, name)!r}")
        for name in ("adapt_timing", "hip_strategy"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"ControllerOptions.{name} must be true or false, got {getattr(self, name)!r}")


# The numbers of ControllerOptions: (lowest, highest, unit); the lowest itself is allowed unless in _OPEN_BELOW.
_RANGES = {
    "measurement_filter": (0.0, 10.0, "s"),
    "replan_dcm_error": (1e-4, 1.0, "m"),
    "early_touchdown_fraction": (0.0, 1.0, "of the swing"),
    "late_descent_speed": (0.0, 10.0, "m/s"),
    "late_descent_limit": (0.0, 10.0, "m"),
    "late_grace": (0.0, 10.0, "s"),
    "on_time_window": (0.0, 10.0, "s"),
    "relanding_tolerance": (0.0, 10.0, "m"),
    "anchor_blend": (0.0, 10.0, "s"),
    "max_lean": (0.0, 0.6, "rad"),
}
_OPEN_BELOW = ("max_lean",)
_CHOICES = {"measured_replanning": ("on-error", "always"), "com_reference": ("measured", "planned")}


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
        left_foot, right_foot: sole targets ``(x, y, z, yaw)`` (m, rad), the foot-control heights and the blend of
            a re-anchored foot (``ControllerOptions.anchor_blend``) included.
        offsets: the foot force control's output (its tilts go to the ankles, :func:`~rtgait.control.foot_control.
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
        lean: the upper body's lean (rotation vector, rad) of the hip strategy (:mod:`rtgait.core.laws.hip_strategy`);
            ``None``: upright.
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
    lean: tuple[float, float, float] | None = None

    @property
    def ik(self) -> IKTargets:
        """The whole-body IK's targets."""
        return IKTargets(self.com, self.left_foot, self.right_foot, self.lean)
