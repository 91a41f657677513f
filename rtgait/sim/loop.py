"""The closed loop: measure -> controller -> whole-body IK -> joint servos -> MuJoCo, once per control period.

Every control tick (``sim.control_dt``: 1 ms for Talos, 2 ms for G1) of the walk, at time ``t`` on the walk's clock:

1. **measure** (:class:`~rtgait.sim.measure.SimMeasurer`): per-foot contact wrench, centre of pressure and pose, the
   ZMP, the COM and its velocity, the DCM, and the landings since the last tick. They are read from the kinematics
   and contact forces the last physics step computed, i.e. of the state one physics step before ``t``: a real
   robot's sensors lag by a sample too, and reading them costs no extra ``mj_forward``;
2. footstep changes due at ``t`` go to the planner (at their connection mode's deadline, as
   :func:`rtgait.core.rollout.rollout` does); a walk by command is stopped after its steps;
3. **control** (:class:`~rtgait.sim.controllers.WalkingController`, the level asked for): the planner's sample, with
   the level's feedback, re-anchoring, step adjustment and landing handling, gives the IK's COM and feet targets and
   the foot force control's ankle tilts;
4. **IK**: the whole-body IK, warm-started from the previous tick, turns them into joint angles (always one
   Gauss-Newton iteration, so the solution varies smoothly and its finite difference is a clean joint velocity);
   the ankle tilts are added to the ankle joints (:func:`~rtgait.sim.foot_control.add_ankle_offsets`);
5. those angles and their velocity become the joint references of the PD servos (:mod:`rtgait.sim.actuation`),
   interpolated linearly over the physics substeps of the period, and ``mj_step`` advances the physics by
   ``sim.substeps`` steps, the servo torques recomputed at each.

Recorded each tick, at the tick's time (the first substep's contacts): the measured ZMP (centre of pressure of the
sole-floor contact forces), the base pose, the COG, which feet touch the floor, on how many corners of their sole
boxes, how far each sole is tilted, where each sole is, whether the legs touch each other
(:mod:`rtgait.sim.contact`), the joint torques (their mean over the period's substeps), and the commanded
configuration. The run ends early when the robot falls (:class:`FallLimits`). A foot that carries most of the load
and tilts beyond :attr:`FallLimits.tip_angle` has *tipped over*: recorded (:attr:`SimResult.tipped`), not an end,
since a robot may recover from it.

The walk starts from half-sitting, whose COG is higher than the planner's constant COG height: a short transition
(:attr:`LoopOptions.start_ramp`, then :attr:`LoopOptions.start_hold` at rest) moves the IK's COG target to the walk's
start before the planner's clock begins; it runs at negative times on the walk's clock, with no feedback.

``open-loop`` gives the IK the planner's sample unchanged, which is the loop before the controller levels existed
(the paper's assumption); the levels are described in :mod:`rtgait.sim.controllers`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from rtgait.core.online import OnlinePlanner
from rtgait.core.rollout import ScheduledChange
from rtgait.robot.ik import IKTargets, WholeBodyIK
from rtgait.sim.actuation import ReferenceInterpolator
from rtgait.sim.contact import ContactMonitor, FallLimits, Landings, Push, Pushes, measure_contacts
from rtgait.sim.controllers import ControllerOptions, RobotInfo, WalkingController
from rtgait.sim.foot_control import FootOffsets, add_ankle_offsets, find_ankle_joints
from rtgait.sim.measure import SimMeasurer
from rtgait.sim.model import SimModel
from rtgait.sim.result import SUPPORT_CODES, SimResult
from rtgait.sim.tick_log import TickLog

__all__ = [
    "LANDING_WINDOW",
    "SUPPORT_CODES",
    "FallLimits",
    "LoopOptions",
    "Push",
    "SimResult",
    "measure_contacts",
    "open_loop_controller",
    "run_closed_loop",
]

LANDING_WINDOW = 0.5
"""Longest time after a step's planned touch-down (s) in which its foot must be found on the floor; the double
support that follows the landing, when shorter, is the window."""

_NO_OFFSETS = FootOffsets()


@dataclass(frozen=True)
class LoopOptions:
    """Settings of the closed loop.

    Attributes:
        start_ramp: time to move the COG from half-sitting to the walk's start (s), minimum-jerk profile.
        start_hold: rest at the walk's start posture before the planner's clock begins (s).
        after: extra time simulated after the planned walk has come to rest (s).
        pushes: external forces (their times on the walk's clock).
        falls: fall and tip-over criteria.
        contact_threshold: a foot touches the floor when its normal force exceeds this fraction of the weight.
        changes: footstep changes, each handed to the planner at its connection mode's deadline.
        stop_after_steps: for a walk by velocity command: ``planner.stop()`` once this many steps are committed,
            so that the walk has ``stop_after_steps + 1`` steps (the last one closes the feet).
        velocity_changes: for a walk by velocity command: ``(t, vx, vy, wz)`` (s on the walk's clock, m/s, m/s,
            rad/s), each handed to the planner (``set_velocity``) at its time, in time order; the command before the
            first is the planner's own.
        on_tick: called every tick from the walk's start on, as ``on_tick(t, data)`` with the walk's time ``t``
            (s) and the MuJoCo state, before the footstep changes and the controller: a hook for simulated sensors
            and operators (e.g. a hand pull through ``data.xfrc_applied`` that sets the planner's velocity command,
            :mod:`rtgait.sim.guided`). It may call ``planner.stop()``.
        duration: for a walk by command that ``on_tick`` ends: simulate this long after the walk's start (s)
            instead of a length known in advance; ``stop_after_steps`` is then not needed.
        replay_period: the robot's whole configuration is recorded every this many seconds (rounded to whole
            control ticks) for the 3D replay (:attr:`SimResult.replay_q`); 0.04 s is the replay's 25 frames per
            second, and keeps a minute of walking to 1500 rows.
    """

    start_ramp: float = 1.0
    start_hold: float = 0.5
    after: float = 0.5
    pushes: tuple[Push, ...] = ()
    falls: FallLimits = field(default_factory=FallLimits)
    contact_threshold: float = 0.01
    changes: tuple[ScheduledChange, ...] = ()
    stop_after_steps: int | None = None
    velocity_changes: tuple[tuple[float, float, float, float], ...] = ()
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
        for change in self.velocity_changes:
            if len(change) != 4 or not all(math.isfinite(v) for v in change):
                raise ValueError(f"a velocity change is four finite numbers (t, vx, vy, wz), got {change!r}")
        times = [change[0] for change in self.velocity_changes]
        if times != sorted(times):
            raise ValueError(f"velocity changes must be in time order, got times {times}")

    @property
    def lead(self) -> float:
        """Length of the start transition (s): the walk starts this long after the run."""
        return self.start_ramp + self.start_hold


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


def open_loop_controller(sim: SimModel, planner: OnlinePlanner) -> WalkingController:
    """The ``open-loop`` level around ``planner`` (not started): the plan alone, as the paper assumes."""
    info = RobotInfo.from_robot(sim.robot)
    return WalkingController("open-loop", planner, info, sim.control_dt, ControllerOptions())


def run_closed_loop(
    sim: SimModel,
    controller: WalkingController | OnlinePlanner,
    options: LoopOptions | None = None,
    *,
    ik: WholeBodyIK | None = None,
    data: mujoco.MjData | None = None,
    progress: Callable[[float], None] | None = None,
) -> SimResult:
    """Walk the controller's walk with the simulated robot ``sim`` in closed loop (see the module docstring).

    Args:
        sim: the MuJoCo model of the robot.
        controller: a controller level (:func:`rtgait.sim.controllers.make_controller`, its period ``sim``'s
            control period), or an online planner, walked ``open-loop``; its planner must not be started (its clock
            starts at 0 after the start transition).
        options: loop settings (start transition, pushes, fall limits, footstep changes).
        ik: the whole-body IK to use (default: one with default weights on ``sim.robot``).
        data: MuJoCo state to run in (reset to the start configuration first); a new one when ``None``.
        progress: called now and then with the fraction of the planned time simulated, for long runs.

    Returns:
        The per-tick record and the outcome.

    Raises:
        ValueError: the walk has no planned end and no ``stop_after_steps``, a push names an unknown body, the IK
            was built for another robot, or the controller for another control period.
    """
    options = options or LoopOptions()
    robot = sim.robot
    model = sim.model
    ik = ik or WholeBodyIK(robot)
    if ik.robot is not robot:
        raise ValueError(f"the IK solver was built for another model of {ik.robot.name!r}, not this simulation's")
    if isinstance(controller, OnlinePlanner):
        controller = open_loop_controller(sim, controller)
    dt = sim.control_dt
    if abs(controller.dt - dt) > 1e-12 * dt:
        raise ValueError(f"the controller runs every {controller.dt:g} s, the simulation's control period is {dt:g} s")
    planner = controller.planner

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
    n_sub = sim.substeps
    k0 = math.ceil(options.lead / dt - 1e-9)  # the walk's first tick: the transition's ticks come before it
    if options.duration is not None and planner.n_steps is None and stop_after is None:
        # Ended by on_tick: the number of steps and the walk's end are known only afterwards.
        n_steps = 0
        walk_end = options.duration
        n_ticks = k0 + math.floor(options.duration / dt + 1e-9) + 1
    else:
        # The walk's length is known in advance, also by command: stop() closes the feet after stop_after steps.
        n_steps = planner.n_steps if stop_after is None else stop_after + 1  # type: ignore[assignment]
        assert n_steps is not None
        walk_end = _walk_length(planner, n_steps)
        n_ticks = k0 + math.floor((walk_end + options.after) / dt + 1e-9) + 1
    on_tick = options.on_tick

    # ----- the record, allocated once ----------------------------------------------------------------------------
    times = (np.arange(n_ticks) - k0) * dt
    planned = np.full((n_ticks, 8), math.nan)  # planned ZMP x, y, commanded ZMP x, y, DCM x, y, its plan's x, y
    cog = np.empty((n_ticks, 3))
    cog_planned = np.empty((n_ticks, 3))
    base = np.empty((n_ticks, 7))  # MuJoCo's order (x, y, z, qw, qx, qy, qz); reordered at the end
    support = np.zeros(n_ticks, dtype=np.int8)
    torque = np.empty((n_ticks, model.nu))
    commanded = np.empty((n_ticks, robot.model.nq))
    # The replay's record: a whole qpos every few ticks only (a 1 kHz record of ~40 coordinates would be 30 times
    # more than a 25 fps replay shows).
    replay_every = max(1, round(options.replay_period / dt))
    n_replay = (n_ticks - 1) // replay_every + 1
    replay_qpos = np.empty((n_replay, model.nq))
    replay_soles = np.empty((n_replay, 2, 3))
    if model.opt.cone != mujoco.mjtCone.mjCONE_PYRAMIDAL:  # pragma: no cover - the model builder keeps the default
        raise ValueError("the closed loop measures contact forces of pyramidal friction cones only")
    gravity = float(-model.opt.gravity[2])
    threshold = options.contact_threshold * robot.mass * gravity
    contacts = ContactMonitor(
        data, sim.left_sole_geom, sim.right_sole_geom, sim.left_sole_site, sim.right_sole_site, n_ticks, threshold,
        options.falls, dt,
    )  # fmt: skip
    pushes = Pushes(sim, data, options.pushes)
    measurer = SimMeasurer.for_sim(sim, omega=planner.w)
    ankles = find_ankle_joints(robot)

    # ----- loop state --------------------------------------------------------------------------------------------
    # MuJoCo's arrays of fixed size are views that stay valid.
    ctrl, qpos, subtree_com, site_xpos, actuator_force = (
        data.ctrl, data.qpos, data.subtree_com, data.site_xpos, data.actuator_force
    )  # fmt: skip
    left_site, right_site, base_body = sim.left_sole_site, sim.right_sole_site, sim.base_body
    servo = ReferenceInterpolator(sim.actuation, q[7:])
    joints_previous = q[7:].copy()
    log = TickLog(sim, data, servo, n_ticks, planner.w)  # the complete per-tick record (sim.parquet)
    pending: list[ScheduledChange] = []
    ramp = options.start_ramp
    events: list = []
    tick = controller.tick
    measure = measurer.measure

    landings = Landings(max(min(planner.config.timing.double_support, LANDING_WINDOW), dt), threshold)
    fell, fall_time, fall_cause = False, None, None
    stopped = stop_after is None
    commands = list(options.velocity_changes)
    report_every = max(n_ticks // 50, 1)
    ticks = n_ticks
    step = mujoco.mj_step

    began = time.perf_counter()
    for k in range(n_ticks):
        t = times[k].item()
        pushes.update(t)

        # ----- references -----------------------------------------------------------------------------------
        if k < k0:
            s = _minimum_jerk(k * dt / ramp) if ramp > 0.0 else 1.0
            target_cog = [a + s * (b - a) for a, b in zip(cog_half_sitting, cog_start, strict=True)]
            left_foot, right_foot = left_start, right_start
            planned_x = command_x = target_cog[0]
            planned_y = command_y = target_cog[1]
            code, phase, offsets = 0, -1, _NO_OFFSETS
            dcm = dcm_planned = (math.nan, math.nan)
        else:
            measurement = measure(data, t)
            if k == k0:
                controller.start(0.0, measurement)
                pending = sorted(options.changes, key=lambda c: planner.change_deadline(c.step))
            if on_tick is not None:
                on_tick(t, data)
            while pending and t >= planner.change_deadline(pending[0].step):
                change = pending.pop(0)
                planner.change_step(
                    change.step, length=change.length, width=change.width, turn=change.turn, through=change.through
                )
            while commands and t >= commands[0][0] - 1e-9 and not stopped:
                _, vx, vy, wz = commands.pop(0)
                planner.set_velocity(vx, vy, wz)
            if not stopped and planner.first_open_step() > stop_after:  # type: ignore[operator]
                planner.stop()
                stopped = True
            out = tick(t, measurement)
            target_cog = out.com
            left_foot, right_foot = out.left_foot, out.right_foot
            planned_x, planned_y = out.zmp_planned
            command_x, command_y = out.zmp_command
            code, phase, offsets = SUPPORT_CODES[out.planned_support], out.phase, out.offsets
            dcm, dcm_planned = measurement.dcm, out.dcm_planned
            if out.events:
                events.extend(out.events)

        q, _ = ik.solve(IKTargets(target_cog, left_foot, right_foot), q, max_iterations=1, tolerance=0.0)
        joints = q[7:]
        if offsets != _NO_OFFSETS:
            joints = joints.copy()
            add_ankle_offsets(joints, ankles, offsets)
        servo.command(joints, (joints - joints_previous) / dt)
        joints_previous = joints
        row = commanded[k]
        row[0:7] = q[0:7]
        row[7:] = joints

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
        cog[k] = subtree_com[base_body]
        _, _, fl, fr = contacts.measure(k, t)
        log.record(k, left_foot, right_foot, *((out, measurement) if k >= k0 else (None, None)), controller.level)
        for i in range(1, n_sub):
            servo.apply(i, ctrl)
            step(model, data)
            tau += actuator_force
        if n_sub > 1:
            tau *= 1.0 / n_sub
        planned[k] = planned_x, planned_y, command_x, command_y, dcm[0], dcm[1], dcm_planned[0], dcm_planned[1]
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

    if planner.started and planner.n_steps is not None:  # as the walk ended up (step adjustment may shorten it)
        n_steps = planner.n_steps
        walk_end = min(planner.end_time, walk_end) if options.duration is not None else planner.end_time
    elif n_steps == 0:  # ended by on_tick, never stopped: the steps that landed
        n_steps = landings.count
    n_recorded = (ticks - 1) // replay_every + 1
    return SimResult(
        times=times[:ticks],
        zmp=contacts.zmp(ticks),
        zmp_planned=planned[:ticks, 0:2].copy(),
        zmp_command=planned[:ticks, 2:4].copy(),
        dcm=planned[:ticks, 4:6].copy(),
        dcm_planned=planned[:ticks, 6:8].copy(),
        cog=cog[:ticks],
        cog_planned=cog_planned[:ticks],
        base_position=base[:ticks, 0:3].copy(),
        base_quaternion=base[:ticks][:, [4, 5, 6, 3]],
        contact=contacts.normal_force(ticks) > threshold,
        normal_force=contacts.normal_force(ticks),
        corners=contacts.corners(ticks),
        sole_tilt=contacts.sole_tilt(ticks),
        sole_pose=contacts.sole_poses(ticks),
        support=support[:ticks],
        torque=torque[:ticks],
        joint_names=sim.joint_names,
        legs_touch=contacts.legs_touch(ticks),
        commanded_q=commanded[:ticks],
        control_dt=dt,
        physics_dt=sim.timestep,
        run_start=float(times[0]),
        walk_end=float(walk_end),
        steps_planned=n_steps,
        steps_completed=landings.count,
        missed_landings=landings.missed,
        fell=fell,
        fall_time=fall_time,
        fall_cause=fall_cause,
        tipped=contacts.tip_time is not None,
        tip_time=contacts.tip_time,
        wall_time=wall,
        robot=robot.name,
        mass=robot.mass,
        controller=controller.level,
        replay_index=np.arange(n_recorded) * replay_every,
        replay_q=sim.full_configurations(replay_qpos[:n_recorded]),
        replay_soles=replay_soles[:n_recorded],
        footprints=tuple(planner.footprints()) if planner.started else (),
        pushes=tuple(options.pushes),
        events=tuple(events),
        step_adjustments=tuple(planner.step_adjustments) if planner.started else (),
        replans=planner.replan_count if planner.started else 0,
        model=robot.model,
        gravity=gravity,
        log=log.finish(ticks),
    )
