"""The settings and the outputs of the MuJoCo controller levels (:mod:`rtgait.control.controller`): what the robot is
to the controller, its gains and landing handling, and what one tick gives the IK."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import NamedTuple

from rtgait.control.foot_control import FootControlGains, FootOffsets
from rtgait.control.sole_level import SoleLevelSettings
from rtgait.core.geometry.terrain import Terrain
from rtgait.core.laws.feedback import DcmFeedbackGains
from rtgait.core.laws.stepping import StepAdjustment, SteppingLimits
from rtgait.core.planner.levels import DEFAULT_REPLAN_DCM_ERROR
from rtgait.core.planner.measured import AUTO_MIN_REMAINDER, AUTO_REPLAN_INTERVAL
from rtgait.interface.robot_info import RobotInfo
from rtgait.interface.task_targets import IKTargets

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
"""COM admittance ``A`` of the MuJoCo levels (1/s): the value used on HRP-2Kai with mc_rtc's ZMPCC (mc_rtc PR #16).
lipm_walking_controller runs HRP-4 with it off, the feet alone realising the ZMP (``docs/design/control.md``)."""

SIM_COP_ADMITTANCE = 0.002
"""Ankle damping gain ``K`` of the MuJoCo levels (rad/(N m s)), a fifth of lipm_walking_controller's 0.01 for HRP-4
(:class:`~rtgait.control.foot_control.FootControlGains`). The CoP loop's rate is ``K`` times the stiffness that turns an
ankle tilt into a sole moment: on HRP-2 and HRP-4 the rubber bushes of the foot set it, some 10^3 N m/rad; here the
stiff ankle servo in series with MuJoCo's sole contact, some 10^4 N m/rad, so the same ``K`` would make the loop
faster than the measurement filter and the tick (``docs/design/control.md``)."""

# The core's own thresholds for replans triggered by a DCM error (rtgait.core.planner.measured), under the names the
# MuJoCo controller uses: the least time between two, and the shortest phase remainder one is made over (s).
ERROR_REPLAN_INTERVAL = AUTO_REPLAN_INTERVAL
ERROR_REPLAN_MIN_REMAINDER = AUTO_MIN_REMAINDER


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


def controller_step_adjustment(
    options: ControllerOptions, info: RobotInfo, terrain: Terrain | None = None
) -> StepAdjustment:
    """The step adjustment of the ``"adaptive"`` level: ``options.step_adjustment``, else the robot's
    :func:`step_limits`; with ``options.adapt_timing``, its step timing adaptation on; with ``terrain`` (the one the
    walk's footholds were placed on), its moved landings kept on their treads or stones at the terrain's height
    and tilt (:func:`~rtgait.core.geometry.terrain_landing.land_on_terrain`)."""
    adjust = options.step_adjustment or step_limits(info)
    if options.adapt_timing and not adjust.adapt_timing:
        adjust = replace(adjust, adapt_timing=True)
    if terrain is not None and adjust.terrain is not terrain:
        adjust = replace(adjust, terrain=terrain)
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
            before they are fed back (s); 0: none. MuJoCo's contact forces answer the stiff servos within a tick,
            and fed back raw they make the ankle tilts chatter.
        replan_dcm_error: ``"adaptive"``: DCM error that triggers an immediate replan (m).
        step_adjustment: ``"adaptive"``: stride box and limits; default :func:`step_limits` of the robot.
        adapt_timing: ``"adaptive"``: step adjustment may also change the single support of the step it moves
            (:class:`~rtgait.core.laws.stepping.StepAdjustment` ``adapt_timing``, Morisawa et al. 2006): shorten it,
            down to the limits' ``min_single_support``, and, where the limits set ``max_single_support``,
            lengthen it (a push toward the stance foot's outside, which no landing catches).
        early_touchdown_fraction: a landing counts as an early touch-down from this fraction of the swing on; before,
            it is ignored (a scuff).
        late_descent_speed: how fast a late foot's target goes down (m/s).
        late_descent_acceleration: the peak acceleration (m/s^2) with which a late foot's target leaves rest for
            ``late_descent_speed`` and comes to rest at ``late_descent_limit``, along a quintic blend
            (:mod:`rtgait.control.late_descent`; 9.81, gravity's, is its argued value: 57 ms to 0.3 m/s); 0 (default):
            at full speed from the first tick, a step of the target's velocity (off by default: at G1's own gains
            the later landings it gives fall, ``docs/results.md``, "A late foot's descent from rest").
        late_descent_limit: how far below the plan it goes at most (m); also how far below where it touched an
            early-landed foot's target goes on down.
        ground_tolerance: a late foot's landing height relative to the other sole, beyond the plan's difference of
            their footholds, is taken for a change of the ground only when it is larger than this (m); within it the
            foot stands at the other foot's ground (:mod:`rtgait.control.landings`, "Heights"). The estimate of two
            soles' relative height is off by the legs' joint calibration: up to 4.4 mm for Talos's zero offsets of
            +-0.5 deg (worst case over the offsets at its landings), and taken at face value each landing's error
            adds to the last (``docs/robots.md``, "Ground under a late foot").
        on_time_window: a touch-down this little before the plan's (s) is on time, not early: the foot goes on down
            with the plan and support switches with it. The swing's height profile ends flat (2 mm at 70 ms before
            the touch-down, :mod:`rtgait.core.geometry.swing`), so a robot whose stance side gives 2 mm touches that
            early at every step.
        relanding_tolerance: a foot that lands again (after a bounce, or a standing foot unloaded and loaded
            again) is re-anchored only when it moved this far (m; its heading twice this in rad) from where it was
            anchored: a bounce in place would only replan for nothing.
        late_grace: a foot not on the ground when its swing ends counts as late only this long (s) after: the
            landing's detection lags the touch (MuJoCo's soft contact reaches the landing force a few milliseconds
            after the sole touches), and a foot lowered for that lag would stand its stance below the floor.
        measured_replanning: ``"adaptive"``: when a plan starts from the measured COM state. ``"on-error"``
            (default): only when the measured DCM is more than ``replan_dcm_error`` off the plan's (a disturbance);
            every other plan (the regular double-support replans, the re-anchoring at landings, the start) continues
            the plan under way. ``"always"``: every plan, the core's ``feedback="measured"`` (module docstring).
        com_reference: ``"adaptive"``, the plan of a DCM-error replan: ``"dcm"`` (default) starts it from the
            measured DCM ``xi`` with the COM where the plan has it, ``c = c_plan``, ``c' = w (xi - c_plan)``: the COM
            target's position goes on without a step, its velocity steps by ``w`` times the DCM error (0.1 m/s at
            the 25 mm threshold for Talos). ``"measured"`` starts it from the measured COM state: the COM target
            moves by the COM error in one tick (mm, ``error / dt`` on the IK's velocity references: 4-10 rad/s on
            Talos's legs, the stiff drives' damping at their torque limits for 3-10 ms). ``"planned"`` takes the
            footsteps the measured state's step adjustment gives and lets the COM go on from where the plan had it,
            so that the servos keep pulling the robot back.
        anchor_blend: how long (s) a foot's IK target takes to go from where it was to where a re-anchoring (or the
            start or end of an early landing's hold) puts it, from its pose and rate then, along the quintic of the
            planner's retargeted swing (:mod:`rtgait.control.target_blend`); 0 (default): at once. Moved in one tick,
            a loaded foot's target steps by ``jump`` and the commanded joint motion has an acceleration of
            ``jump / dt^2``; blended, its peak is ``5.77 jump / anchor_blend^2`` and continuous. A swing foot
            re-anchored on time goes to where it landed along the planner's retargeted swing over what is left of
            the swing; it is blended only when that is shorter than ``anchor_blend``. Only what the IK is asked is
            blended: the planner, the support polygon and the ZMP split have the foot where it was measured. Why it
            is off by default: ``docs/design/control.md``.
        hip_strategy: the closed levels lean the upper body when the DCM law asks the feet for a ZMP beyond the
            support polygon (:mod:`rtgait.core.laws.hip_strategy`: the rate of angular momentum moves the CMP beyond the
            sole), with the robot's lean limits (:attr:`RobotInfo.lean`).
        max_lean: the hip strategy's largest lean on each axis (rad); 0.25 (14 degrees) stays inside Talos's and
            G1's hip roll ranges (+-0.52 rad) with the walking's own roll on top.
        sole_level: the closed levels learn the tilt each sole shows in the estimate while it stands flat and loaded
            (the leg's joint calibration errors) and command the sole at it, so that the real one lands and stands
            level (:mod:`rtgait.control.sole_level`): the learning's time constant (s) of stance; 0 turns it off.
        dcm_bias: the closed levels estimate the bias of the estimated DCM from the measured ZMP
            (:mod:`rtgait.estimation.dcm_bias`: the model's COM is off the true one) and feed back and replan on
            the unbiased COM state. Off by default: it takes part of a push for a bias (G1 falls from a 6 N s push
            at mid single support with it on, ``tests/sim/test_sim_ci.py``).
        swing_feedback: the closed levels steer each swing foot's estimated position onto its target by an offset
            of its IK target (:mod:`rtgait.control.swing_feedback`): the time constant (s) of that integral action;
            0 (default) turns it off.
    """

    dcm: DcmFeedbackGains = field(default_factory=lambda: DcmFeedbackGains(com_admittance=SIM_COM_ADMITTANCE))
    foot: FootControlGains | None = field(default_factory=lambda: FootControlGains(cop_admittance=SIM_COP_ADMITTANCE))
    measurement_filter: float = 0.005
    replan_dcm_error: float = DEFAULT_REPLAN_DCM_ERROR
    step_adjustment: StepAdjustment | None = None
    early_touchdown_fraction: float = 0.5
    late_descent_speed: float = 0.3
    late_descent_limit: float = 0.02
    late_descent_acceleration: float = 0.0
    ground_tolerance: float = 0.005
    measured_replanning: str = "on-error"
    late_grace: float = 0.01
    on_time_window: float = 0.08
    relanding_tolerance: float = 0.01
    com_reference: str = "dcm"
    adapt_timing: bool = True
    anchor_blend: float = 0.0
    hip_strategy: bool = True
    max_lean: float = 0.25
    sole_level: float = SoleLevelSettings().time_constant
    dcm_bias: bool = False
    swing_feedback: float = 0.0

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
        for name in ("adapt_timing", "hip_strategy", "dcm_bias"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"ControllerOptions.{name} must be true or false, got {getattr(self, name)!r}")


# The numbers of ControllerOptions: (lowest, highest, unit); the lowest itself is allowed unless in _OPEN_BELOW.
_RANGES = {
    "measurement_filter": (0.0, 10.0, "s"),
    "replan_dcm_error": (1e-4, 1.0, "m"),
    "early_touchdown_fraction": (0.0, 1.0, "of the swing"),
    "late_descent_speed": (0.0, 10.0, "m/s"),
    "late_descent_limit": (0.0, 10.0, "m"),
    "late_descent_acceleration": (0.0, 1000.0, "m/s^2"),
    "ground_tolerance": (0.0, 10.0, "m"),
    "late_grace": (0.0, 10.0, "s"),
    "on_time_window": (0.0, 10.0, "s"),
    "relanding_tolerance": (0.0, 10.0, "m"),
    "anchor_blend": (0.0, 10.0, "s"),
    "max_lean": (0.0, 0.6, "rad"),
    "sole_level": (0.0, 1e4, "s"),
    "swing_feedback": (0.0, 1e4, "s"),
}
_OPEN_BELOW = ("max_lean",)
_CHOICES = {"measured_replanning": ("on-error", "always"), "com_reference": ("dcm", "measured", "planned")}


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
        offsets: the foot force control's output (its tilts go to the ankles,
            :func:`~rtgait.robot.ankles.add_ankle_offsets`; its heights are already in the feet's z).
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
