"""The closed loop: planner -> whole-body IK -> joint servos -> MuJoCo, once per control period, and what is measured.

Every control tick (``sim.control_dt``: 1 ms for Talos, 2 ms for G1):

1. footstep changes due at this time are handed to the planner (at their connection mode's deadline, as
   :func:`rtgait.core.rollout.rollout` does), and the planner is sampled: COG, ZMP, both feet;
2. the whole-body IK, warm-started from the previous tick, turns the COG and feet into joint angles (always one
   Gauss-Newton iteration, so the solution varies smoothly from tick to tick and its finite difference is a
   clean joint velocity);
3. those angles and their velocity become the joint references of the PD servos (:mod:`rtgait.sim.actuation`),
   interpolated linearly over the physics substeps of the period;
4. ``mj_step`` advances the physics by ``sim.substeps`` steps, the servo torques recomputed at each.

Measured each tick, at the tick's time (the first substep's contacts): the ZMP as the centre of pressure of the
sole-floor contact forces, the base pose, the COG, which feet touch the floor, on how many corners of their sole
boxes, how far each sole is tilted, whether the legs touch each other (:mod:`rtgait.sim.contact`), and the joint
torques (their mean over the period's substeps). The run ends early when the robot falls (:class:`FallLimits`).
A foot that carries most of the load and tilts beyond :attr:`FallLimits.tip_angle` has *tipped over*: it stands
on an edge with the opposite edge lifted, the robot has lost flat contact. That is recorded
(:attr:`SimResult.tipped`) but does not end the run, since a robot may recover from it.

The walk starts from half-sitting, whose COG is higher than the planner's constant COG height: a short
transition (:attr:`LoopOptions.start_ramp`, then :attr:`LoopOptions.start_hold` at rest) moves the IK's COG target
to the walk's start before the planner's clock begins.

The paper's cases assume the planner alone, so the stabiliser (:class:`Stabilizer`) is off unless asked for.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from rtgait.core.footsteps import Footstep
from rtgait.core.online import OnlinePlanner
from rtgait.core.rollout import ScheduledChange
from rtgait.robot.ik import IKTargets, WholeBodyIK
from rtgait.sim.actuation import ReferenceInterpolator
from rtgait.sim.contact import ContactMonitor, FallLimits, Landings, Push, Pushes, measure_contacts
from rtgait.sim.model import SimModel

__all__ = [
    "LANDING_WINDOW",
    "SUPPORT_CODES",
    "FallLimits",
    "LoopOptions",
    "Push",
    "SimResult",
    "Stabilizer",
    "measure_contacts",
    "run_closed_loop",
]

SUPPORT_CODES = {"double": 0, "left": 1, "right": 2}
"""Planned support per tick in :attr:`SimResult.support`: 0 double, 1 left foot only, 2 right foot only."""

LANDING_WINDOW = 0.5
"""Longest time after a step's planned touch-down (s) in which its foot must be found on the floor; the double
support that follows the landing, when shorter, is the window."""


@dataclass(frozen=True)
class Stabilizer:
    """ZMP and COG feedback through the IK's COG target (the COG-ZMP regulator of Choi et al., IEEE T-RO 2007).

    The IK's COG target is the planned COG plus a shift ``s`` (per horizontal axis) that obeys

        ds/dt = zmp_gain * (p_measured - p_planned) - cog_gain * (c_measured - c_planned)

    and is clipped to ``limit``. For the linear inverted pendulum ``p = c - c''/w^2`` this makes the COG error
    decay when ``0 < zmp_gain < w < cog_gain`` (about 3.4 1/s for a COG 0.84 m high); feedback from the ZMP alone
    would not be stable, since moving the COG toward a ZMP first pushes the ZMP the other way. With stiff joint
    servos the measured COG follows its target, so the COG term also pulls the shift back to zero. The measured
    ZMP and COG are low-pass filtered first: the contact forces react to the servos within a tick, and feeding
    that back unfiltered makes the feet chatter.

    Attributes:
        zmp_gain: COG velocity per metre of ZMP error (1/s).
        cog_gain: COG velocity per metre of COG error (1/s).
        limit: largest shift of the COG target on each axis (m).
        filter: time constant of the first-order low-pass filter on the measurements (s).
    """

    zmp_gain: float = 2.0
    cog_gain: float = 6.0
    limit: float = 0.05
    filter: float = 0.05

    def __post_init__(self) -> None:
        for name in ("zmp_gain", "cog_gain", "limit", "filter"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"stabilizer {name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class LoopOptions:
    """Settings of the closed loop.

    Attributes:
        start_ramp: time to move the COG from half-sitting to the walk's start (s), minimum-jerk profile.
        start_hold: rest at the walk's start posture before the planner's clock begins (s).
        after: extra time simulated after the planned walk has come to rest (s).
        stabilizer: optional ZMP feedback; ``None`` (default): the planner alone, as in the paper.
        pushes: external forces.
        falls: fall and tip-over criteria.
        contact_threshold: a foot touches the floor when its normal force exceeds this fraction of the weight.
        changes: footstep changes, each handed to the planner at its connection mode's deadline.
        stop_after_steps: for a walk by velocity command: ``planner.stop()`` once this many steps are committed,
            so that the walk has ``stop_after_steps + 1`` steps (the last one closes the feet).
        on_tick: called every tick from the walk's start on, as ``on_tick(t, data)`` with the simulation time
            ``t`` (s) and the MuJoCo state, before the footstep changes and the planner's sample: a hook for
            simulated sensors and operators (e.g. a hand pull through ``data.xfrc_applied`` that sets the
            planner's velocity command, :mod:`rtgait.sim.guided`). It may call ``planner.stop()``.
        duration: for a walk by command that ``on_tick`` ends: simulate this long (s, from the start of the run)
            instead of a length known in advance; ``stop_after_steps`` is then not needed.
        replay_period: the robot's whole configuration is recorded every this many seconds (rounded to whole
            control ticks) for the 3D replay (:attr:`SimResult.replay_q`); 0.04 s is the replay's 25 frames per
            second, and keeps a minute of walking to 1500 rows.
    """

    start_ramp: float = 1.0
    start_hold: float = 0.5
    after: float = 0.5
    stabilizer: Stabilizer | None = None
    pushes: tuple[Push, ...] = ()
    falls: FallLimits = field(default_factory=FallLimits)
    contact_threshold: float = 0.01
    changes: tuple[ScheduledChange, ...] = ()
    stop_after_steps: int | None = None
    replay_period: float = 0.04
    on_tick: Callable[[float, mujoco.MjData], None] | None = None
    duration: float | None = None

    def __post_init__(self) -> None:
        if self.duration is not None and not (math.isfinite(self.duration) and self.duration > 0.0):
            raise ValueError(f"duration must be > 0 s, got {self.duration}")
        if not (math.isfinite(self.replay_period) and self.replay_period > 0.0):
            raise ValueError(f"replay_period must be a duration > 0 s, got {self.replay_period}")
        for name in ("start_ramp", "start_hold", "after"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be a duration >= 0 s, got {value}")
        if not 0.0 < self.contact_threshold < 0.5:
            raise ValueError(
                f"contact_threshold must be a fraction of the weight in (0, 0.5), got {self.contact_threshold}"
            )
        if self.stop_after_steps is not None and self.stop_after_steps < 1:
            raise ValueError(f"stop_after_steps must be >= 1, got {self.stop_after_steps}")


@dataclass(frozen=True, eq=False)
class SimResult:
    """A walk in physics, control tick by control tick, and its outcome. Times are simulation times (s) from the
    start of the run; the planner's clock starts at :attr:`walk_start`. ``k`` ticks were simulated (fewer than
    planned after a fall); every array has ``k`` rows and describes the state at the tick's time.

    Attributes:
        times: tick times (s), shape ``(k,)``.
        zmp: measured ZMP, the centre of pressure of the sole-floor contact forces (m), shape ``(k, 2)``; NaN
            while no foot touches the floor.
        zmp_planned: the planner's ZMP (m), shape ``(k, 2)``; during the start transition, the COG target's
            ground projection.
        cog: the measured COG (m), shape ``(k, 3)``.
        cog_planned: the COG target given to the IK (m), shape ``(k, 3)`` (with the stabiliser's shift, if any).
        base_position: floating-base position (m), shape ``(k, 3)``.
        base_quaternion: floating-base orientation, unit quaternion ``(qx, qy, qz, qw)``, shape ``(k, 4)``.
        contact: whether each foot (left, right) touches the floor, shape ``(k, 2)``.
        normal_force: vertical contact force on each foot (N), shape ``(k, 2)``.
        corners: corners of each sole box touching the floor (0 to 4), shape ``(k, 2)``.
        sole_tilt: angle between each sole's normal and the vertical (rad), shape ``(k, 2)``.
        support: planned support per tick, codes :data:`SUPPORT_CODES` (the start transition is double).
        torque: the joint torques the servos applied (N m), mean over the tick's physics substeps, shape ``(k, n)``,
            columns in :attr:`joint_names` order; within each joint's torque limit.
        joint_names: the actuated joints, the columns of :attr:`torque`.
        legs_touch: whether the legs' collision boxes touched each other at the tick, shape ``(k,)``.
        control_dt: the control period, the interval between two ticks (s).
        physics_dt: the physics step (s).
        walk_start: simulation time at which the planner's walk begins (s).
        walk_end: simulation time at which the planned walk has come to rest (s).
        steps_planned: steps of the walk (the closing step included).
        steps_completed: touch-downs completed: after the step's planned landing, and before the next lift-off
            (at most :data:`LANDING_WINDOW` later), the landing foot was on the floor and the robot had not fallen.
        fell: whether the robot fell.
        fall_time: when (s), or ``None``.
        fall_cause: ``"base too low"``, ``"base tilted"`` or ``"no foot on the floor"``, or ``None``.
        tipped: whether a foot carrying most of the load tilted beyond :attr:`FallLimits.tip_angle`.
        tip_time: when that first happened (s), or ``None``.
        wall_time: wall-clock time of the loop (s).
        robot: the robot's name.
        mass: its mass (kg).
        replay_index: the ticks at which the configuration was recorded for the replay, every
            :attr:`LoopOptions.replay_period`, shape ``(m,)``; their times are :attr:`replay_times`.
        replay_q: the robot's configuration at those ticks in its FULL Pinocchio model (``robot.full_model``:
            free flyer ``x, y, z, qx, qy, qz, qw``, then every joint; locked joints at half-sitting), shape
            ``(m, full nq)`` (m, rad), converted from MuJoCo's ``qpos`` by joint name.
        replay_soles: MuJoCo's left and right sole site positions at those ticks (m), shape ``(m, 2, 3)``.
        footprints: the planner's footprints ``F[0..]`` as planned at the end of the run.
    """

    times: np.ndarray
    zmp: np.ndarray
    zmp_planned: np.ndarray
    cog: np.ndarray
    cog_planned: np.ndarray
    base_position: np.ndarray
    base_quaternion: np.ndarray
    contact: np.ndarray
    normal_force: np.ndarray
    corners: np.ndarray
    sole_tilt: np.ndarray
    support: np.ndarray
    walk_start: float
    walk_end: float
    steps_planned: int
    steps_completed: int
    fell: bool
    fall_time: float | None
    fall_cause: str | None
    tipped: bool
    tip_time: float | None
    wall_time: float
    robot: str
    mass: float
    replay_index: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    replay_q: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    replay_soles: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    footprints: tuple[Footstep, ...] = ()
    torque: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    joint_names: tuple[str, ...] = ()
    legs_touch: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    control_dt: float = 0.001
    physics_dt: float = 0.001

    @property
    def replay_times(self) -> np.ndarray:
        """Times of the replay's configurations (s), shape ``(m,)``."""
        return self.times[self.replay_index]

    @property
    def duration(self) -> float:
        """Simulated time (s)."""
        return float(self.times[-1] + self.control_dt) if len(self.times) else 0.0

    @property
    def legs_touched(self) -> bool:
        """Whether the legs touched each other at any tick (a step that crossed the feet, a swing foot that hit the
        stance leg)."""
        return bool(self.legs_touch.any())

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second of the loop."""
        return self.duration / self.wall_time if self.wall_time > 0.0 else math.inf

    @property
    def distance_walked(self) -> float:
        """Horizontal displacement of the base from the start to the last tick (m)."""
        return float(np.hypot(*(self.base_position[-1, :2] - self.base_position[0, :2])))

    @property
    def single_support_mask(self) -> np.ndarray:
        """Ticks in planned single support at which the ZMP was measured."""
        return (self.support != 0) & np.isfinite(self.zmp[:, 0])

    @property
    def zmp_tracking_error_rms(self) -> float:
        """RMS distance between the measured and the planned ZMP in single support (m); NaN without any."""
        mask = self.single_support_mask
        if not mask.any():
            return math.nan
        error = self.zmp[mask] - self.zmp_planned[mask]
        return float(np.sqrt(np.mean(np.sum(error * error, axis=1))))

    @property
    def zmp_tracking_error_max(self) -> float:
        """Largest distance between the measured and the planned ZMP in single support (m); NaN without any."""
        mask = self.single_support_mask
        if not mask.any():
            return math.nan
        return float(np.max(np.hypot(*(self.zmp[mask] - self.zmp_planned[mask]).T)))

    @property
    def all_steps_completed(self) -> bool:
        """Whether every step of the walk touched down and the robot did not fall."""
        return not self.fell and self.steps_completed == self.steps_planned

    def summary(self) -> dict[str, Any]:
        """The outcome as JSON-ready values (SI units)."""

        def number(value: float) -> float | None:
            return None if not math.isfinite(value) else value  # JSON has no NaN

        return {
            "robot": self.robot,
            "fell": self.fell,
            "fall_time": self.fall_time,
            "fall_cause": self.fall_cause,
            "tipped": self.tipped,
            "tip_time": self.tip_time,
            "steps_planned": self.steps_planned,
            "steps_completed": self.steps_completed,
            "distance_walked": self.distance_walked,
            "zmp_tracking_error_rms": number(self.zmp_tracking_error_rms),
            "zmp_tracking_error_max": number(self.zmp_tracking_error_max),
            "simulated_time": self.duration,
            "wall_time": self.wall_time,
            "real_time_factor": self.real_time_factor,
            "walk_start": self.walk_start,
            "walk_end": self.walk_end,
            "legs_touched": self.legs_touched,
            "control_dt": self.control_dt,
            "physics_dt": self.physics_dt,
        }


def _minimum_jerk(s: float) -> float:
    """0 -> 1 over ``s`` in [0, 1] with zero velocity and acceleration at both ends."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def _walk_length(planner: OnlinePlanner, n_steps: int) -> float:
    """Time from the start of a walk of ``n_steps`` steps until its COG is at rest (s)."""
    timing = planner.config.timing
    return (
        timing.start
        + n_steps * timing.single_support
        + (n_steps - 1) * timing.double_support
        + timing.end
        + timing.settle
    )


def _start_pose(planner: OnlinePlanner) -> tuple[list[float], list[float], list[float]]:
    """COG ``(x, y, z)`` and feet ``(x, y, z, yaw)`` at the start of the walk: standing, COG between the feet.

    Read from the first two footprints rather than by sampling, so the planner stays unsampled (an early footstep
    change is still accepted at its deadline).
    """
    first, second = planner.footprints(1)[:2]
    left, right = (first, second) if first.side == "left" else (second, first)
    cog = [0.5 * (left.x + right.x), 0.5 * (left.y + right.y), planner.config.cog_height]
    return cog, [left.x, left.y, 0.0, left.yaw], [right.x, right.y, 0.0, right.yaw]


def run_closed_loop(
    sim: SimModel,
    planner: OnlinePlanner,
    options: LoopOptions | None = None,
    *,
    ik: WholeBodyIK | None = None,
    data: mujoco.MjData | None = None,
    progress: Callable[[float], None] | None = None,
) -> SimResult:
    """Walk ``planner``'s walk with the simulated robot ``sim`` in closed loop (see the module docstring).

    Args:
        sim: the MuJoCo model of the robot.
        planner: an online planner, not started; its clock starts after the start transition.
        options: loop settings (start transition, pushes, stabiliser, fall limits, footstep changes).
        ik: the whole-body IK to use (default: one with default weights on ``sim.robot``).
        data: MuJoCo state to run in (reset to the start configuration first); a new one when ``None``.
        progress: called now and then with the fraction of the planned time simulated, for long runs.

    Returns:
        The per-tick record and the outcome.

    Raises:
        ValueError: the walk has no planned end and no ``stop_after_steps``, a push names an unknown body, or the
            IK was built for another robot.
    """
    options = options or LoopOptions()
    robot = sim.robot
    model = sim.model
    ik = ik or WholeBodyIK(robot)
    if ik.robot is not robot:
        raise ValueError(f"the IK solver was built for another model of {ik.robot.name!r}, not this simulation's")

    walk_start = options.start_ramp + options.start_hold
    stop_after = options.stop_after_steps
    if planner.n_steps is not None:
        stop_after = None  # a walk of footsteps ends by itself
    elif stop_after is None and options.duration is None:
        raise ValueError("a walk by velocity command needs LoopOptions.stop_after_steps or duration to end")
    cog_start, left_start, right_start = _start_pose(planner)
    # The start configuration: half-sitting's COG over the planner's standing feet, soles level. Half-sitting
    # itself may differ from it by a milliradian (a sole not quite level); starting from the IK's own solution
    # keeps the first ticks free of a step in the servo references, which the velocity reference would amplify.
    cog_half_sitting = robot.cog_half_sitting.tolist()
    q, _ = ik.solve(IKTargets(cog_half_sitting, left_start, right_start), robot.q_half_sitting, 200, 1e-9)
    if data is None:
        data = sim.new_data(q=q)
    else:
        sim.reset(data, q=q)
    dt = sim.control_dt
    n_sub = sim.substeps
    planner.start(walk_start)
    if options.duration is not None and planner.n_steps is None and stop_after is None:
        # Ended by on_tick: the number of steps and the walk's end are known only afterwards.
        n_steps = 0
        walk_end = options.duration
        n_ticks = math.floor(options.duration / dt + 1e-9) + 1
    else:
        # The walk's length is known in advance, also by command: stop() closes the feet after stop_after steps.
        n_steps = planner.n_steps if stop_after is None else stop_after + 1  # type: ignore[assignment]
        assert n_steps is not None
        walk_end = walk_start + _walk_length(planner, n_steps)
        n_ticks = math.floor((walk_end + options.after) / dt + 1e-9) + 1
    on_tick = options.on_tick

    # ----- the record, allocated once ----------------------------------------------------------------------------
    times = np.arange(n_ticks) * dt
    zmp_planned = np.empty((n_ticks, 2))
    cog = np.empty((n_ticks, 3))
    cog_planned = np.empty((n_ticks, 3))
    base = np.empty((n_ticks, 7))  # MuJoCo's order (x, y, z, qw, qx, qy, qz); reordered at the end
    support = np.zeros(n_ticks, dtype=np.int8)
    torque = np.empty((n_ticks, model.nu))
    # The replay's record: a whole qpos every few ticks only (a 1 kHz record of ~40 coordinates would be 30 times
    # more than a 25 fps replay shows).
    replay_every = max(1, round(options.replay_period / dt))
    n_replay = (n_ticks - 1) // replay_every + 1
    replay_qpos = np.empty((n_replay, model.nq))
    replay_soles = np.empty((n_replay, 2, 3))
    if model.opt.cone != mujoco.mjtCone.mjCONE_PYRAMIDAL:  # pragma: no cover - the model builder keeps the default
        raise ValueError("the closed loop measures contact forces of pyramidal friction cones only")
    threshold = options.contact_threshold * robot.mass * float(-model.opt.gravity[2])
    contacts = ContactMonitor(
        data, sim.left_sole_geom, sim.right_sole_geom, sim.left_sole_site, sim.right_sole_site, n_ticks, threshold,
        options.falls, dt,
    )  # fmt: skip
    pushes = Pushes(sim, data, options.pushes)

    # ----- loop state --------------------------------------------------------------------------------------------
    # MuJoCo's arrays of fixed size are views that stay valid.
    ctrl, qpos, subtree_com, site_xpos, actuator_force = (
        data.ctrl, data.qpos, data.subtree_com, data.site_xpos, data.actuator_force
    )  # fmt: skip
    left_site, right_site, base_body = sim.left_sole_site, sim.right_sole_site, sim.base_body
    servo = ReferenceInterpolator(sim.actuation, q[7:])
    joints_previous = q[7:].copy()
    pending = sorted(options.changes, key=lambda c: planner.change_deadline(c.step))
    stabilizer = options.stabilizer
    zmp_gain = stabilizer.zmp_gain if stabilizer else 0.0
    cog_gain = stabilizer.cog_gain if stabilizer else 0.0
    smoothing = dt / (stabilizer.filter + dt) if stabilizer else 0.0
    error_px = error_py = error_cx = error_cy = 0.0  # filtered ZMP and COG errors (m)
    cog_x = cog_y = 0.0  # the COG measured at the previous tick (m)
    shift_x = shift_y = 0.0
    measured_x = measured_y = math.nan
    ramp = options.start_ramp

    landings = Landings(max(min(planner.config.timing.double_support, LANDING_WINDOW), dt), threshold)
    fell, fall_time, fall_cause = False, None, None
    stopped = stop_after is None
    report_every = max(n_ticks // 50, 1)
    ticks = n_ticks
    step = mujoco.mj_step

    began = time.perf_counter()
    for k in range(n_ticks):
        t = k * dt
        pushes.update(t)

        # ----- references -----------------------------------------------------------------------------------
        if t < walk_start:
            s = _minimum_jerk(t / ramp) if ramp > 0.0 else 1.0
            target_cog = [a + s * (b - a) for a, b in zip(cog_half_sitting, cog_start, strict=True)]
            left_foot, right_foot = left_start, right_start
            planned_x, planned_y = target_cog[0], target_cog[1]
            code, phase = 0, -1
        else:
            if on_tick is not None:
                on_tick(t, data)
            while pending and t >= planner.change_deadline(pending[0].step):
                change = pending.pop(0)
                planner.change_step(
                    change.step, length=change.length, width=change.width, turn=change.turn, through=change.through
                )
            if not stopped and planner.first_open_step() > stop_after:  # type: ignore[operator]
                planner.stop()
                stopped = True
            values, label, phase = planner.sample_values(t)
            target_cog = values[0:3]
            left_foot, right_foot = values[13:17], values[17:21]
            planned_x, planned_y = values[9], values[10]
            code = SUPPORT_CODES[label]
        if stabilizer is not None and measured_x == measured_x:  # NaN-safe: no correction without a measurement
            # Filtered errors of the previous tick's measurements (first-order low-pass, time constant `filter`).
            error_px += smoothing * (measured_x - planned_x - error_px)
            error_py += smoothing * (measured_y - planned_y - error_py)
            error_cx += smoothing * (cog_x - target_cog[0] - error_cx)
            error_cy += smoothing * (cog_y - target_cog[1] - error_cy)
            shift_x += dt * (zmp_gain * error_px - cog_gain * error_cx)
            shift_y += dt * (zmp_gain * error_py - cog_gain * error_cy)
            shift_x = min(max(shift_x, -stabilizer.limit), stabilizer.limit)
            shift_y = min(max(shift_y, -stabilizer.limit), stabilizer.limit)
            target_cog = [target_cog[0] + shift_x, target_cog[1] + shift_y, target_cog[2]]

        q, _ = ik.solve(IKTargets(target_cog, left_foot, right_foot), q, max_iterations=1, tolerance=0.0)
        joints = q[7:]
        servo.command(joints, (joints - joints_previous) / dt)
        joints_previous = joints

        # ----- physics: the control period's substeps ---------------------------------------------------------
        row = base[k]
        row[:] = qpos[0:7]  # the state at t, before the steps integrate it to t + dt
        replay_row = k // replay_every if k % replay_every == 0 else -1
        if replay_row >= 0:
            replay_qpos[replay_row] = qpos
        tau = torque[k]
        servo.apply(0, ctrl)
        step(model, data)
        # mj_step computed the kinematics, contacts and forces of the state it started from: the state at t.
        tau[:] = actuator_force
        if replay_row >= 0:
            replay_soles[replay_row, 0] = site_xpos[left_site]
            replay_soles[replay_row, 1] = site_xpos[right_site]
        com = subtree_com[base_body]
        cog[k] = com
        cog_x, cog_y = float(com[0]), float(com[1])
        measured_x, measured_y, fl, fr = contacts.measure(k, t)
        for i in range(1, n_sub):
            servo.apply(i, ctrl)
            step(model, data)
            tau += actuator_force
        if n_sub > 1:
            tau *= 1.0 / n_sub
        zmp_planned[k, 0] = planned_x
        zmp_planned[k, 1] = planned_y
        cog_planned[k] = target_cog
        support[k] = code

        landings.update(t, phase, code, fl, fr)

        # ----- falls ----------------------------------------------------------------------------------------
        fall_cause = contacts.fall(row)
        if fall_cause is not None:
            fell, fall_time, ticks = True, t, k + 1
            break
        if progress is not None and k % report_every == 0:
            progress(k / n_ticks)
    wall = time.perf_counter() - began
    pushes.clear()
    if progress is not None:
        progress(1.0)

    if n_steps == 0:  # ended by on_tick: the steps the planner ended up with, and when it came to rest
        n_steps = planner.n_steps if planner.n_steps is not None else landings.count
        walk_end = min(planner.end_time, walk_end)
    n_recorded = (ticks - 1) // replay_every + 1
    return SimResult(
        times=times[:ticks],
        zmp=contacts.zmp(ticks),
        zmp_planned=zmp_planned[:ticks],
        cog=cog[:ticks],
        cog_planned=cog_planned[:ticks],
        base_position=base[:ticks, 0:3].copy(),
        base_quaternion=base[:ticks][:, [4, 5, 6, 3]],
        contact=contacts.normal_force(ticks) > threshold,
        normal_force=contacts.normal_force(ticks),
        corners=contacts.corners(ticks),
        sole_tilt=contacts.sole_tilt(ticks),
        support=support[:ticks],
        walk_start=walk_start,
        walk_end=walk_end,
        steps_planned=n_steps,
        steps_completed=landings.count,
        fell=fell,
        fall_time=fall_time,
        fall_cause=fall_cause,
        tipped=contacts.tip_time is not None,
        tip_time=contacts.tip_time,
        wall_time=wall,
        robot=robot.name,
        mass=robot.mass,
        replay_index=np.arange(n_recorded) * replay_every,
        replay_q=sim.full_configurations(replay_qpos[:n_recorded]),
        replay_soles=replay_soles[:n_recorded],
        footprints=tuple(planner.footprints()),
        torque=torque[:ticks],
        joint_names=sim.joint_names,
        legs_touch=contacts.legs_touch(ticks),
        control_dt=dt,
        physics_dt=sim.timestep,
    )
