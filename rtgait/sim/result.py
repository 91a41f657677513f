"""A walk in physics, tick by tick, and the measures of its outcome (:class:`SimResult`).

Times are on the walk's clock: ``t = 0`` when the planner starts, negative during the start transition from
half-sitting (:attr:`SimResult.run_start` is the first tick), the same clock as ``rtgait simulate --model lipm``.

The error measures are honest about what is compared with what (all in m, over the planned single supports from
the walk's start to its planned end, where the measured ZMP must be on the stance sole):

* ``vs_plan``: the measured ZMP (centre of pressure of the sole contacts) against the planner's ZMP, the one the
  linear inverted pendulum of the plan needs. This is what the paper's method promises.
* ``vs_command``: against the ZMP the controller asked the feet for (the DCM law's ``p_cmd``; the plan's ZMP in
  ``open-loop``).
* ``vs_commanded_motion``: against the multibody ZMP of the commanded motion, i.e. of the joint references the servos
  were given (the IK's configuration with the ankle offsets of foot force control), from Pinocchio's centroidal
  dynamics with finite differences (:mod:`rtgait.sim.commanded_motion`). The pendulum plan ignores the legs' angular
  momentum, so even a perfect servo would miss ``vs_plan`` by that much (20-30 mm on Talos, ``docs/robots.md``);
  what is left of ``vs_commanded_motion`` is the servos' and the contacts' doing. Where the controller moves its
  targets at once (its events: landings, re-anchoring, replans, step adjustments) the motion is differentiated on
  either side, not across the jump, and the ticks of a swing re-anchored before the plan's double support are left
  out (``reanchored_ticks``). On a run that fell it stops earlier than the other two
  (:attr:`SimResult.commanded_motion_mask`): at the first tip-over, which is where such a fall began.

The slip of the stance feet is measured by :mod:`rtgait.sim.stance`; the JSON summary is made by
:mod:`rtgait.sim.result_summary`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.support import SUPPORT_CODES
from rtgait.core.push import Push
from rtgait.sim.result_summary import _error_stats, result_summary
from rtgait.sim.stance import STANCE_FRACTION, Stance, stances

if TYPE_CHECKING:
    import pinocchio as pin

    from rtgait.control.controller import ControlEvent
    from rtgait.core.laws.stepping import StepDecision
    from rtgait.sim.config import SensorSettings
    from rtgait.sim.estimation_errors import EstimationErrors
    from rtgait.sim.model_error import ModelError
    from rtgait.sim.tick_log import CompleteLog
    from rtgait.stack.safety import SafetyEvent

__all__ = ["FALL_MARGIN", "REST_SPEED", "SimResult"]

FALL_MARGIN = 0.5
"""The ZMP errors leave out the last this many seconds before a fall (s): the robot is falling, not walking, and
the commanded motion of an IK chasing a falling robot has no meaningful ZMP."""

REST_SPEED = 0.02
"""Largest COM speed (m/s, averaged over the run's last 0.1 s) of a walk that ended at rest."""


@dataclass(frozen=True, eq=False)
class SimResult:
    """A walk in physics, control tick by control tick, and its outcome. ``k`` ticks were simulated (fewer than
    planned after a fall); every array has ``k`` rows and describes the state at the tick's time.

    Attributes:
        times: tick times (s, walk clock; module docstring), shape ``(k,)``.
        zmp: measured ZMP, the centre of pressure of the sole-floor contact forces (m), shape ``(k, 2)``; NaN
            while no foot touches the floor.
        zmp_planned: the planner's ZMP (m), shape ``(k, 2)``; during the start transition, the COG target's
            ground projection.
        zmp_command: the ZMP the controller asked the feet for (m), shape ``(k, 2)``: the DCM law's, or the plan's
            in ``open-loop`` and during the start transition.
        dcm: the measured DCM ``c + c'/w`` the controller acted on (m), shape ``(k, 2)``: the estimator's, made once
            (the controller takes it as it is, or moved by its lean against a known pull,
            :mod:`rtgait.control.external_force`), of the state one physics step before the tick
            (:mod:`rtgait.sim.loop`); NaN during the start transition.
        dcm_planned: the plan's DCM at the tick (m), shape ``(k, 2)``; NaN during the start transition.
        cog: the measured COG (m), shape ``(k, 3)``.
        cog_planned: the COG target given to the IK (m), shape ``(k, 3)`` (the plan's with the controller's COM
            offset).
        base_position: floating-base position (m), shape ``(k, 3)``.
        base_quaternion: floating-base orientation, unit quaternion ``(qx, qy, qz, qw)``, shape ``(k, 4)``.
        contact: whether each foot (left, right) touches the floor, shape ``(k, 2)``.
        normal_force: vertical contact force on each foot (N), shape ``(k, 2)``.
        corners: corners of each sole box touching the floor (0 to 4), shape ``(k, 2)``.
        sole_tilt: angle between each sole's normal and the vertical (rad), shape ``(k, 2)``.
        sole_pose: each sole's ground pose ``(x, y, yaw)`` (m, rad), shape ``(k, 2, 3)``.
        support: planned support per tick, codes :data:`~rtgait.core.geometry.support.SUPPORT_CODES` (the start
            transition is double).
        torque: the joint torques the servos applied (N m), mean over the tick's physics substeps, shape ``(k, n)``,
            columns in :attr:`joint_names` order; within each joint's torque limit.
        joint_names: the actuated joints, the columns of :attr:`torque`.
        legs_touch: whether the legs' collision shapes touched each other at the tick, shape ``(k,)``.
        commanded_q: the commanded configuration of the robot's reduced Pinocchio model at each tick (the IK's
            floating base, the servos' joint references), shape ``(k, nq)`` (m, unit quaternion, rad).
        control_dt: the control period, the interval between two ticks (s).
        physics_dt: the physics step (s).
        run_start: time of the first tick (s, walk clock): minus the start transition's length.
        walk_end: when the planned walk (as it ended up: step adjustment may shorten it) has come to rest (s).
        steps_planned: steps of the walk (the closing step included).
        steps_completed: touch-downs completed: after the step's planned landing, and before the next lift-off,
            the landing foot was on the floor and the robot had not fallen.
        missed_landings: single supports whose swing foot was not on the floor by the end of its window.
        fell: whether the robot fell.
        fall_time: when (s), or ``None``.
        fall_cause: ``"base too low"``, ``"base tilted"`` or ``"no foot on the floor"``, or ``None``.
        tipped: whether a foot carrying most of the load tilted beyond the fall limits' ``tip_angle`` from the tilt it
            was commanded (a planned toe-off is no tip).
        tip_time: when that first happened (s), or ``None``.
        wall_time: wall-clock time of the loop (s), the planner, controller, IK and physics.
        robot: the robot's name.
        mass: its mass (kg).
        controller: the controller level (:data:`rtgait.core.planner.levels.CONTROLLER_LEVELS`).
        pushes: the external pushes of the run.
        events: what the controller logged (landings, re-anchoring, step adjustments, replans).
        step_adjustments: the planner's step adjustments, in order.
        replans: replannings of the planner since the walk's start.
        replay_index: the ticks at which the configuration was recorded for the replay; their times are
            :attr:`replay_times`.
        replay_q: the robot's configuration at those ticks in its FULL Pinocchio model, shape ``(m, full nq)``.
        replay_soles: MuJoCo's left and right sole site positions at those ticks (m), shape ``(m, 2, 3)``.
        footprints: the planner's footprints ``F[0..]`` as planned at the end of the run.
        model: the reduced Pinocchio model of :attr:`commanded_q` (for the multibody ZMP), or ``None``.
        log: the rest of the per-tick record (joint and base velocities, per-foot wrench, feet targets, ...:
            :class:`~rtgait.sim.tick_log.CompleteLog`), or ``None`` for a result made without it.
        model_error: how the simulated robot differed from its model (:mod:`rtgait.sim.model_error`), or ``None``.
        safety_events: the faults that tripped the stack's safety layer into damping
            (:class:`~rtgait.stack.safety.SafetyEvent`).
        safety: the safety layer's record (:meth:`~rtgait.stack.safety.SafetyLayer.summary`: damping, events per
            kind, the first event, clipped ticks per joint), or ``None`` for a result made without it.
        state: what the controller acted on: ``"estimated"``, the kinematic-inertial estimator on the simulated
            sensors; ``"truth"``, the simulator's truth (:attr:`rtgait.sim.loop_options.LoopOptions.state`).
        sensors: the simulated sensors' noise factor, latency (control periods, the description's when not set)
            and seed, or ``None`` when not known.
        at_rest_speed: mean horizontal COM speed over the run's last 0.1 s (m/s).
    """

    times: np.ndarray
    zmp: np.ndarray
    zmp_planned: np.ndarray
    zmp_command: np.ndarray
    dcm: np.ndarray
    dcm_planned: np.ndarray
    cog: np.ndarray
    cog_planned: np.ndarray
    base_position: np.ndarray
    base_quaternion: np.ndarray
    contact: np.ndarray
    normal_force: np.ndarray
    corners: np.ndarray
    sole_tilt: np.ndarray
    sole_pose: np.ndarray
    support: np.ndarray
    torque: np.ndarray
    joint_names: tuple[str, ...]
    legs_touch: np.ndarray
    commanded_q: np.ndarray
    control_dt: float
    physics_dt: float
    run_start: float
    walk_end: float
    steps_planned: int
    steps_completed: int
    missed_landings: int
    fell: bool
    fall_time: float | None
    fall_cause: str | None
    tipped: bool
    tip_time: float | None
    wall_time: float
    robot: str
    mass: float
    controller: str
    replay_index: np.ndarray
    replay_q: np.ndarray
    replay_soles: np.ndarray
    footprints: tuple[Footstep, ...]
    pushes: tuple[Push, ...] = ()
    events: tuple[ControlEvent, ...] = ()
    step_adjustments: tuple[StepDecision, ...] = ()
    replans: int = 0
    model: pin.Model | None = field(default=None, repr=False)
    gravity: float = 9.81
    log: CompleteLog | None = field(default=None, repr=False)
    model_error: ModelError | None = field(default=None, repr=False)
    safety_events: tuple[SafetyEvent, ...] = ()
    safety: dict[str, Any] | None = None
    drive: dict[str, Any] | None = None
    state: str = "estimated"
    sensors: SensorSettings | None = None

    # ----- time ------------------------------------------------------------------------------------------------------
    @property
    def walk_start(self) -> float:
        """When the walk starts on the result's clock (s): 0, the walk's clock."""
        return 0.0

    @property
    def replay_times(self) -> np.ndarray:
        """Times (s) of the replay's configurations, shape ``(m,)``."""
        return self.times[self.replay_index]

    @property
    def duration(self) -> float:
        """Simulated time (s), the start transition included."""
        return float(self.times[-1] - self.run_start + self.control_dt) if len(self.times) else 0.0

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second of the loop."""
        return self.duration / self.wall_time if self.wall_time > 0.0 else math.inf

    # ----- outcome ---------------------------------------------------------------------------------------------------
    @property
    def legs_touched(self) -> bool:
        """Whether the legs touched each other at any tick (a step that crossed the feet, a swing foot that hit the
        stance leg)."""
        return bool(self.legs_touch.any())

    @property
    def distance_walked(self) -> float:
        """Horizontal displacement of the base from the start to the last tick (m)."""
        return float(np.hypot(*(self.base_position[-1, :2] - self.base_position[0, :2])))

    @property
    def all_steps_completed(self) -> bool:
        """Whether every step of the walk touched down and the robot did not fall."""
        return not self.fell and self.steps_completed == self.steps_planned

    @property
    def at_rest_speed(self) -> float:
        """Mean horizontal COM speed over the run's last 0.1 s (m/s); inf for a run shorter than that."""
        n = max(1, round(0.1 / self.control_dt))
        if len(self.times) <= n:
            return math.inf
        return float(np.hypot(*(self.cog[-1, :2] - self.cog[-1 - n, :2])) / (n * self.control_dt))

    @property
    def ended_at_rest(self) -> bool:
        """Not fallen, the run went past the walk's planned end, and at its end the COM is still (below
        :data:`REST_SPEED`) with both feet on the floor, flat on their footholds (no foot tipped onto an edge: each
        sole's tilt within 0.02 rad of its last foothold's surface tilt, 0 on level ground)."""
        if self.fell or not len(self.times) or self.times[-1] < self.walk_end:
            return False
        surface = {foot.side: math.acos(math.cos(foot.pitch) * math.cos(foot.roll)) for foot in self.footprints}
        expected = np.array([surface.get("left", 0.0), surface.get("right", 0.0)])
        flat = bool((np.abs(self.sole_tilt[-1] - expected) < 0.02).all())
        return self.at_rest_speed < REST_SPEED and bool(self.contact[-1].all()) and flat

    @property
    def step_adjustment_count(self) -> int:
        """Step adjustments of the run."""
        return len(self.step_adjustments)

    # ----- slip ------------------------------------------------------------------------------------------------------
    @functools.cached_property
    def stances(self) -> list[Stance]:
        """Every stance of both feet and its slip (module docstring)."""
        threshold = STANCE_FRACTION * self.mass * self.gravity
        return stances(self.times, self.normal_force, self.sole_pose, threshold)

    @property
    def foot_slip_max(self) -> float:
        """Largest horizontal slip of a stance foot during one stance (m); 0 without any stance."""
        return max((s.slip for s in self.stances), default=0.0)

    @property
    def foot_yaw_slip_max(self) -> float:
        """Largest change of heading of a stance foot during one stance (rad)."""
        return max((s.yaw_slip for s in self.stances), default=0.0)

    # ----- ZMP errors ------------------------------------------------------------------------------------------------
    @property
    def single_support_mask(self) -> np.ndarray:
        """Ticks of the walk (from its start to its planned end, and up to :data:`FALL_MARGIN` before a fall) in
        planned single support at which the ZMP was measured."""
        end = self.walk_end if self.fall_time is None else min(self.walk_end, self.fall_time - FALL_MARGIN)
        return (self.support != 0) & np.isfinite(self.zmp[:, 0]) & (self.times >= 0.0) & (self.times <= end)

    @property
    def commanded_motion_mask(self) -> np.ndarray:
        """The ticks of ``vs_commanded_motion``: :attr:`single_support_mask`, and on a run that fell and had tipped
        over before, only the ticks before the first tip-over (:attr:`tip_time`).

        A fall that starts with a tip-over starts there: a loaded foot rolls onto a sole edge, which the commanded
        motion (feet flat where the IK has them) does not have, and the IK's targets then chase a robot that turns
        about that edge (an example in ``docs/design/simulation.md``). A fall without a tip-over keeps the
        :data:`FALL_MARGIN` cut; a run that tipped over and did not fall keeps every tick (it stood
        again); one that tipped, walked on and fell much later loses the walk after the tip, an under-count. What
        happened before the tip stays in.
        """
        mask = self.single_support_mask
        if self.fell and self.tip_time is not None:
            mask = mask & (self.times < self.tip_time)
        return mask

    @property
    def zmp_tracking_error_rms(self) -> float:
        """RMS distance between the measured and the planned ZMP in single support (m); NaN without any."""
        value = _error_stats(self.zmp, self.zmp_planned, self.single_support_mask)["rms"]
        return math.nan if value is None else value

    @property
    def zmp_tracking_error_max(self) -> float:
        """Largest distance between the measured and the planned ZMP in single support (m); NaN without any."""
        value = _error_stats(self.zmp, self.zmp_planned, self.single_support_mask)["max"]
        return math.nan if value is None else value

    @property
    def swinging(self) -> np.ndarray:
        """Whether the plan has each foot (left, right) swinging at the tick, shape ``(k, 2)``."""
        return np.column_stack([self.support == SUPPORT_CODES["right"], self.support == SUPPORT_CODES["left"]])

    @functools.cached_property
    def reanchored_swings(self) -> np.ndarray:
        """The ticks from each touch-down that re-anchored a swinging foot to the plan's next double support, where
        the commanded motion is the reference catching up with the foot (:mod:`rtgait.sim.commanded_motion`), shape
        ``(k,)``."""
        from rtgait.sim.commanded_motion import reanchoring_mask

        return reanchoring_mask(self.times, self.swinging, self.events, self.control_dt)

    @functools.cached_property
    def zmp_commanded_motion(self) -> np.ndarray:
        """The multibody ZMP of the commanded motion (m), shape ``(k, 2)``, differentiated between the controller's
        retargeting ticks, NaN over :attr:`reanchored_swings` and off the ground (:mod:`rtgait.sim.commanded_motion`);
        NaN without a model or with fewer than 3 ticks."""
        if self.model is None or len(self.times) < 3:
            return np.full((len(self.times), 2), math.nan)
        from rtgait.sim.commanded_motion import commanded_motion_zmp

        return commanded_motion_zmp(
            self.model, self.commanded_q, self.times, self.control_dt, self.swinging, self.events,
            self.mass * self.gravity,
        )  # fmt: skip

    def zmp_errors(self) -> dict[str, dict[str, float | int | None]]:
        """The three ZMP error measures of the module docstring: ``vs_plan``, ``vs_command`` and
        ``vs_commanded_motion``, each ``rms``, ``median``, ``p95``, ``max``, ``rms_x``, ``rms_y`` (m) and the number of
        ``ticks`` compared over the planned single supports (:attr:`single_support_mask`; ``vs_commanded_motion``
        over :attr:`commanded_motion_mask`, which also gives ``reanchored_ticks``, those of its ticks left out as
        :attr:`reanchored_swings`)."""
        mask = self.single_support_mask
        motion = self.commanded_motion_mask
        return {
            "vs_plan": _error_stats(self.zmp, self.zmp_planned, mask),
            "vs_command": _error_stats(self.zmp, self.zmp_command, mask),
            "vs_commanded_motion": {
                **_error_stats(self.zmp, self.zmp_commanded_motion, motion),
                "reanchored_ticks": int((motion & self.reanchored_swings).sum()),
            },
        }

    # ----- the estimate --------------------------------------------------------------------------------------------
    @functools.cached_property
    def estimation_errors(self) -> EstimationErrors | None:
        """How far the estimate the controller acted on was from the simulator's truth
        (:mod:`rtgait.sim.estimation_errors`), over the walk's ticks (from its start, and up to
        :data:`FALL_MARGIN` before a fall, as the ZMP errors); ``None`` on the truth or without the tick log."""
        if self.state != "estimated" or self.log is None:
            return None
        from rtgait.sim.estimation_errors import estimation_errors

        end = math.inf if self.fall_time is None else self.fall_time - FALL_MARGIN
        rows = (self.times >= 0.0) & (self.times <= end) & np.isfinite(self.log.estimate.com[:, 0])
        rows &= np.isfinite(self.log.truth.com[:, 0])
        return estimation_errors(self.times, self.log.estimate, self.log.truth, self.mass * self.gravity, rows)

    def summary(self) -> dict[str, Any]:
        """The outcome as JSON-ready values (SI units; times on the walk's clock); with a model error, its compact
        record (:meth:`~rtgait.sim.model_error.ModelError.summary`) as ``model_error``; the state the controller
        acted on, the sensors' settings and, on the estimate, its errors (:attr:`estimation_errors`)."""
        return result_summary(self)
