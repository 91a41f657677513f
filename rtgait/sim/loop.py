"""The closed loop in MuJoCo: the simulated robot (:class:`~rtgait.sim.robot.SimRobot`) and the controller stack
(:class:`~rtgait.stack.walking_stack.WalkingStack`: estimator -> controller -> whole-body IK -> joint command), once
per control period.

Every control tick (``sim.control_dt``: 1 ms for Talos, 2 ms for G1) of the walk, at time ``t`` on the walk's clock:

1. **estimate** (:attr:`LoopOptions.state`: ``"truth"``, the
   :class:`~rtgait.estimation.ground_truth.GroundTruthEstimator` on the simulator's truth,
   :mod:`rtgait.sim.ground_truth`; ``"estimated"``, the
   :class:`~rtgait.estimation.kinematic_inertial.KinematicInertialEstimator` on the simulated sensors' readings,
   :mod:`rtgait.sim.sensors`): per-foot contact wrench, centre of pressure and pose, the ZMP, the COM and its
   velocity, the DCM, and the landings since the last tick. They are read from the kinematics and contact forces the
   last physics step computed, i.e. of the state one physics step before ``t``: a real robot's sensors lag by a
   sample too, and reading them costs no extra ``mj_forward`` (with one physics step a period, its contacts as the
   last tick's record decoded them, :mod:`rtgait.sim.contact_reading`);
2. the walk's scheduled inputs (:mod:`rtgait.sim.loop_inputs`): the ``on_tick`` hook, the footstep changes due at
   ``t`` (at their connection mode's deadline, as :func:`rtgait.core.analysis.rollout.rollout` does) and the velocity
   commands due go to the planner; a walk by command is stopped after its steps;
3. **control** (:class:`~rtgait.control.controller.WalkingController`, the level asked for): the planner's sample, with
   the level's feedback, re-anchoring, step adjustment and landing handling (:mod:`rtgait.control.landings`), gives
   the IK's COM and feet targets and the foot force control's ankle tilts;
4. **IK**: the whole-body IK, warm-started from the previous tick, turns them into joint angles (always one
   Gauss-Newton iteration, so the solution varies smoothly and its finite difference is a clean joint velocity);
   the ankle tilts are added to the ankle joints (:func:`~rtgait.robot.ankles.add_ankle_offsets`);
5. those angles and their velocity become the joint references of the PD servos (:mod:`rtgait.sim.actuation`),
   with the feed-forward torques of inverse dynamics when :attr:`LoopOptions.feedforward` says so (by default with
   the robot's gains or torque drive, whose low gains every command then carries: :mod:`rtgait.sim.drive_mode`),
   interpolated linearly over the physics substeps of the period, and ``mj_step`` advances the physics by
   ``sim.substeps`` steps, the servo torques recomputed at each.

Recorded each tick, at the tick's time (the first substep's contacts): the measured ZMP (centre of pressure of the
sole-floor contact forces), the base pose, the COG, which feet touch the floor, on how many corners of their sole
boxes, how far each sole is tilted, where each sole is, whether the legs touch each other
(:mod:`rtgait.sim.contact`), the joint torques (their mean over the period's substeps), and the commanded
configuration. The run ends early when the robot falls (:class:`FallLimits`). A foot that carries most of the load
and tilts beyond :attr:`FallLimits.tip_angle` from the tilt it was commanded (the IK's sole target of the tick
before: level, a sloped foothold's surface, or anywhere from its foothold's tilt to a planned toe-off's while the
heel rises) has *tipped over*: recorded (:attr:`SimResult.tipped`), not an end, since a robot may recover from it.

The walk starts from half-sitting, whose COG is higher than the planner's constant COG height: a short transition
(:mod:`rtgait.sim.loop_start`) moves the IK's COG target to the walk's start before the planner's clock begins. The
stack is built by :mod:`rtgait.sim.loop_stack`.

``open-loop`` gives the IK the planner's sample unchanged (the paper's assumption); the levels are described in
:mod:`rtgait.control.controller`.

:class:`ClosedLoop` is the loop one tick per :meth:`~ClosedLoop.step`, for callers that act between ticks (a live
viewer sets the velocity command, pushes, switches the controller level); :func:`rtgait.sim.run_loop.run_sim_loop`
steps one to the walk's end. The record (:mod:`rtgait.sim.loop_record`) is the whole run, or for an open-ended run a
ring of its last seconds, so that its memory stays bounded however long it lasts; :meth:`ClosedLoop.result` makes it a
:class:`SimResult` with the walk's outcome (:mod:`rtgait.sim.loop_result`). What a caller reads and does between
ticks (the last tick's values, a push, the result) is :class:`~rtgait.sim.loop_readout.LoopReadout`'s.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import mujoco

from rtgait.control.controller import ControlEvent, WalkingController
from rtgait.core.geometry.support import SUPPORT_CODES
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push
from rtgait.interface.task_targets import IKTargets
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.ik_terms import SMOOTH_LIMITS
from rtgait.sim.contact import ContactMonitor, FallLimits, Landings, Pushes
from rtgait.sim.drive_mode import with_gains
from rtgait.sim.drive_summary import ComTracking
from rtgait.sim.loop_inputs import WalkInputs
from rtgait.sim.loop_options import (
    LANDING_WINDOW,
    LoopOptions,
    end_tick,
    run_length,
    timing_headroom,
)  # fmt: skip
from rtgait.sim.loop_push import LivePush
from rtgait.sim.loop_readout import LoopReadout
from rtgait.sim.loop_record import TickRecord, TickValues
from rtgait.sim.loop_stack import build_stack, open_loop_controller
from rtgait.sim.loop_start import StartTransition, start_balance
from rtgait.sim.model import SimModel
from rtgait.sim.result import SimResult
from rtgait.sim.robot import SimRobot
from rtgait.sim.row_packing import row_packer
from rtgait.sim.tick_log import TickLog
from rtgait.stack.setup import start_pose

if TYPE_CHECKING:
    from rtgait.estimation.state import Measurement

__all__ = [
    "LANDING_WINDOW",
    "ClosedLoop",
    "FallLimits",
    "LoopOptions",
    "SimResult",
    "TickValues",
]

_NO_COG, _NO_FOOT = (math.nan,) * 3, (math.nan,) * 4  # the IK's targets while the stack damps


class ClosedLoop(LoopReadout):
    """The closed loop of :func:`~rtgait.sim.run_loop.run_sim_loop`, one control tick per :meth:`step` (see the
    module docstring).

    Drive it by hand (``while loop.step(): ...``, e.g. a live viewer changing the velocity command, pushing or
    switching the controller level between ticks) or through :func:`~rtgait.sim.run_loop.run_sim_loop`;
    :meth:`result` makes the
    :class:`SimResult` of the ticks recorded so far. After a step, :attr:`last` holds that tick's values (time,
    phase, planned, commanded and measured ZMP, measured and planned DCM, the IK's COG and feet targets),
    :meth:`footprints` the plan's footprints, :attr:`base_position` and :attr:`steps_completed` the outcome so far.

    Args:
        sim, controller, options, ik, data: as :func:`~rtgait.sim.run_loop.run_sim_loop`.
        keep: how much to record: ``None`` (default) the whole run, whose length must then be known in advance (a
            walk of footsteps, ``stop_after_steps`` or ``duration``); a time (s) keeps a ring of the last
            ``keep`` seconds (at least one tick: ``keep=0`` records only the last tick), and a walk by command may
            then have no end (:attr:`n_ticks` is ``None``; it runs until the caller stops stepping).

    Raises:
        ValueError: as :func:`~rtgait.sim.run_loop.run_sim_loop`; a negative ``keep``.
    """

    def __init__(
        self,
        sim: SimModel,
        controller: WalkingController | OnlinePlanner,
        options: LoopOptions | None = None,
        *,
        ik: WholeBodyIK | None = None,
        data: mujoco.MjData | None = None,
        keep: float | None = None,
    ) -> None:
        options = options or LoopOptions()
        robot, model = sim.robot, sim.model
        if ik is None:
            # The feed-forward differences the IK's reference twice: keep its rate continuous near joint limits.
            ik = WholeBodyIK(robot, SMOOTH_LIMITS if options.feeds_forward(sim.config.gains) else None)
        if ik.robot is not robot:
            raise ValueError(f"the IK solver was built for another model of {ik.robot.name!r}, not this simulation's")
        if isinstance(controller, OnlinePlanner):
            controller = open_loop_controller(sim, controller)
        dt = sim.control_dt
        if abs(controller.dt - dt) > 1e-12 * dt:
            raise ValueError(
                f"the controller runs every {controller.dt:g} s, the simulation's control period is {dt:g} s"
            )
        if keep is not None and not (math.isfinite(keep) and keep >= 0.0):
            raise ValueError(f"keep must be a duration >= 0 s (or None for the whole run), got {keep}")
        planner = controller.planner
        self.sim, self.controller, self.planner, self.options, self.dt = sim, controller, planner, options, dt

        stop_after = options.stop_after_steps
        if planner.n_steps is not None:
            stop_after = None  # a walk of footsteps ends by itself
        elif stop_after is None and options.duration is None and keep is None:
            raise ValueError("a walk by velocity command needs LoopOptions.stop_after_steps or duration to end")
        self._cog_start, self._left_start, self._right_start = start_pose(planner)
        # The start configuration: half-sitting's COG over the planner's standing feet, soles level. Half-sitting
        # itself may differ from it by a milliradian (a sole not quite level); starting from the IK's own solution
        # keeps the first ticks free of a step in the servo references, which the velocity reference would amplify.
        self._cog_half_sitting = robot.cog_half_sitting.tolist()
        targets = IKTargets(self._cog_half_sitting, self._left_start, self._right_start)
        q, _ = ik.solve(targets, robot.q_half_sitting, 200, 1e-9)
        if data is None:
            data = sim.new_data(q=q)
        else:
            sim.reset(data, q=q)
        self.data = data
        self.k0 = k0 = math.ceil(options.lead / dt - 1e-9)  # the walk's first tick: the transition's come before it
        self._n_steps, self._walk_end, n_ticks = run_length(planner, options, stop_after, k0, dt)
        self._n_ticks_planned = n_ticks
        self.n_ticks = n_ticks
        """Ticks the run lasts (the start transition included), ``None`` for an open-ended walk by command; a walk
        whose steps step timing adaptation holds longer lasts longer (up to :attr:`_longest` ticks)."""
        adjust = controller.options.step_adjustment or planner.config.step_adjustment
        headroom = 0
        if n_ticks is not None and options.duration is None:
            headroom = timing_headroom(adjust, self._n_steps, planner.config.timing.single_support, dt)
        self._longest = None if n_ticks is None else n_ticks + headroom
        self._can_grow = headroom > 0
        if keep is None:
            assert self._longest is not None  # refused above
            capacity = self._longest
        else:  # a ring of `keep` seconds (at most the run)
            ring = max(1, round(keep / dt))
            capacity = ring if self._longest is None else min(ring, self._longest)

        # ----- the record, allocated once ------------------------------------------------------------------------
        # The replay's record: a whole qpos every few ticks only (a 1 kHz record of ~40 coordinates would be 30
        # times more than a 25 fps replay shows).
        replay_every = max(1, round(options.replay_period / dt))
        self.record = TickRecord(capacity, model.nu, robot.model.nq, model.nq, replay_every)
        if model.opt.cone != mujoco.mjtCone.mjCONE_PYRAMIDAL:  # pragma: no cover - the model builder keeps the default
            raise ValueError("the closed loop measures contact forces of pyramidal friction cones only")
        self.gravity = float(-model.opt.gravity[2])
        self.threshold = options.contact_threshold * robot.mass * self.gravity
        self.contacts = ContactMonitor(
            data, sim.left_sole_site, sim.right_sole_site, capacity, self.threshold, options.falls, dt, sim.terrain
        )
        self._pushes = Pushes(sim, data, options.pushes)
        self.pushes: list[Push] = list(options.pushes)
        """The pushes of the run: the scheduled ones and those given to :meth:`push`."""
        self._live = LivePush(sim, data, planner.config.cog_height, self.gravity)  # push(), from a live session
        # The robot behind its interface, and the stack that drives it (loop_stack.py).
        self.robot = SimRobot(sim, data, q[7:])
        start_feet = (self._left_start, self._right_start)
        self.stack, estimator, feed, self.drive_gains = build_stack(
            sim, controller, ik, q, options, self.gravity, start_feet
        )
        """The gains every command carries (torque drive), ``None``: the drives' own."""
        self.com_tracking = ComTracking()
        """The walk's COM tracking errors, planned vs estimated and vs true (:mod:`rtgait.sim.drive_summary`)."""
        self.feedforward_clipped: int | None = None if feed is None else 0
        """The walk's ticks at which the safety layer clipped a feed-forward torque; ``None``: no feed-forward."""
        self._limits = self.stack.safety.clip
        self._clips_seen = 0
        self.start_balance = start_balance(
            sim, controller, self.stack, self.drive_gains, self.gravity, (self._cog_start, *start_feet)
        )
        """The start transition's DCM law (with feed-forward torques and a closed-loop level), ``None``: none."""
        self._start = StartTransition(
            self.stack, options.start_ramp, self._cog_half_sitting, self._cog_start, *start_feet,
            self.start_balance, self._estimate,
        )  # fmt: skip
        self.landings = Landings(max(min(planner.config.timing.double_support, LANDING_WINDOW), dt), self.threshold)

        # ----- loop state ----------------------------------------------------------------------------------------
        # The complete per-tick record (sim.parquet) of a whole run; a ring run (a live session) keeps none.
        self.log = TickLog(sim, data, self.robot.drives, capacity, planner.w) if keep is None else None
        # The hook, footstep changes, velocity commands and stop of the walk, at their times (loop_inputs.py).
        on_stop = self._follow_walk_end if self._can_grow else None  # steps held longer before the walk had an end
        self._inputs = WalkInputs(planner, options, stop_after, on_stop)
        self._walk_inputs = self._inputs.update
        self.events: list[ControlEvent] = []
        self._events_kept = math.inf if keep is None else keep  # an open-ended run keeps the last `keep` seconds
        # What every tick uses, bound once: a tuple unpacked into locals costs less than a dozen attribute lookups
        # (MuJoCo's arrays of fixed size are views that stay valid).
        robot_, stack = self.robot, self.stack
        # A feed-forward computed at the sensed state reads the joints; the truth's estimator reads no encoders, so
        # on the truth it gets the joints' true positions and velocities (robot.py, joint_truth).
        feed = stack.feedforward
        joint_truth = robot_.joint_truth if estimator.reads_truth and feed is not None and feed.tracking else None
        self._hot = (
            stack.estimate, stack.control, self._start.tick, robot_.ground_truth, robot_.write, robot_.first_substep,
            robot_.substep, self.contacts, self.landings, self._pushes.update, self._live.update, data, data.qpos,
            data.subtree_com[sim.base_body], data.site_xpos, data.actuator_force, sim.left_sole_site,
            sim.right_sole_site, sim.substeps, estimator.reads_truth, robot_.read, joint_truth, dt, k0,
            -1 if n_ticks is None else n_ticks,
        )  # fmt: skip
        r = self.record
        # The rows of Python numbers are written by struct packing into the arrays' bytes (the same float64s for
        # half the cost of a numpy assignment from a tuple).
        self._rows = (
            row_packer(r.planned), row_packer(r.cog_planned), r.cog, r.base, r.support, r.torque, r.commanded,
            r.replay_qpos, r.replay_soles, r.capacity, r.replay_every, r.replay_capacity,
        )  # fmt: skip
        self._over = False
        self.k = 0
        """Ticks run so far."""
        self.fell, self.fall_time, self.fall_cause = False, None, None
        self.t = self.time_of(0)
        """Time of the last tick run (s, walk clock); before the first, the first's."""
        self.phase = -1
        """The planner's phase at the last tick (-1 during the start transition)."""
        self.zmp_measured: tuple[float, float] = (math.nan, math.nan)
        """The measured ZMP at the last tick (m), NaN while no foot touches the floor."""
        self.left_foot, self.right_foot = self._left_start, self._right_start
        """The feet's IK targets ``(x, y, z, yaw)`` at the last tick (m, rad)."""
        self.cog_target: Sequence[float] = self._cog_half_sitting
        """The COG target given to the IK at the last tick (m)."""
        self._began: float | None = None
        self._ended: float | None = None

    # ----- the tick ------------------------------------------------------------------------------------------------
    def time_of(self, k: int) -> float:
        """Time of tick ``k`` on the walk's clock (s)."""
        return (k - self.k0) * self.dt

    @property
    def done(self) -> bool:
        """Whether the run is over: fallen, or its last tick run."""
        return self._over

    def step(self) -> bool:
        """Run one control tick (module docstring: measure, footstep changes, control, IK, servos, physics).

        Returns:
            ``False`` when the robot fell at this tick (the run is over), else ``True``; see also :attr:`done`.

        Raises:
            RuntimeError: the run is already over.
        """
        if self._over:
            raise RuntimeError("the closed loop is over (fallen or at its last tick): make its result()")
        (estimate, control, start, ground_truth, write, first_substep, substep, contacts, landings, pushes, live_push,
         data, qpos, base_com, site_xpos, actuator_force, left_site, right_site, n_sub, estimator_reads_truth, read,
         joint_truth, dt, k0, n_ticks) = self._hot  # fmt: skip
        ((pack_planned, planned_bytes, planned_row), (pack_cog, cog_bytes, cog_row), cog, bases, support, torque,
         commanded, replay_qpos, replay_soles, capacity, replay_every, replay_capacity) = self._rows  # fmt: skip
        if self._began is None:
            self._began = time.perf_counter()
        k = self.k
        i = k % capacity  # the record's row of this tick
        t = (k - k0) * dt
        pushes(t)
        live_push(t)

        # ----- references ---------------------------------------------------------------------------------------
        if k < k0:  # the start transition (loop_start.py): no controller, no plan
            made, target_cog, (planned_x, planned_y), (command_x, command_y), dcm, dcm_planned = start(k, t, dt)
            left_foot, right_foot = self._left_start, self._right_start
            code, phase = 0, -1
            out = measurement = truth = None
        else:
            # With one physics step a period, the last tick's record ran mj_subtreeVel on the state estimated now.
            if estimator_reads_truth:
                truth = ground_truth(t, self.log is not None)
                measurement = estimate(None if joint_truth is None else joint_truth(t), truth)
            else:  # the sensors' readings, stamped on the walk's clock (their sampling time, latency kept)
                readings = read()
                measurement = estimate(readings._replace(t=readings.t - (data.time - t)), None)
                # The truth of the same instant, for the log's estimation errors only (a live ring keeps no log).
                truth = ground_truth(t, True) if self.log is not None else None
            if k == k0:
                self.stack.start(0.0, measurement)
                self._inputs.start()
            if measurement is not None:  # None: the safety layer found a fault, the stack damps (stack.safety)
                self._walk_inputs(t, data)
            made = control(t, measurement)
            out = made.targets
            if out is None:  # the safety layer has tripped (stack.safety): the damping command, no targets, no plan
                target_cog, left_foot, right_foot = _NO_COG, _NO_FOOT, _NO_FOOT
                planned_x = planned_y = command_x = command_y = math.nan
                code, phase = 0, -1
                dcm = dcm_planned = (math.nan, math.nan)
            else:
                target_cog = out.com
                left_foot, right_foot = out.left_foot, out.right_foot
                offset = out.com_offset
                self.com_tracking.add(
                    (target_cog[0] - offset[0], target_cog[1] - offset[1]),
                    measurement.com,
                    base_com,  # type: ignore[union-attr]
                )
                planned_x, planned_y = out.zmp_planned
                command_x, command_y = out.zmp_command
                code, phase = SUPPORT_CODES[out.planned_support], out.phase
                dcm, dcm_planned = measurement.dcm, out.dcm_planned  # type: ignore[union-attr]
                if out.events:
                    self._log(out.events)
                    if self._can_grow and any(e.kind == "step-adjustment" for e in out.events):
                        self._follow_walk_end()

        # The commanded configuration: the IK's base and the command's joints (the ankle tilts added).
        command = made.command
        if self.feedforward_clipped is not None and k >= k0:
            clips = self._limits.torque_ticks
            if clips != self._clips_seen:
                self.feedforward_clipped += 1
                self._clips_seen = clips
        row = commanded[i]
        row[:7] = made.q[:7]
        row[7:] = command.positions
        write(with_gains(command, self.drive_gains))

        # ----- physics: the control period's substeps -----------------------------------------------------------
        base = bases[i]
        base[:] = qpos[0:7]  # the state at t, before the steps integrate it to t + dt
        replay_row = (k // replay_every) % replay_capacity if k % replay_every == 0 else -1
        if replay_row >= 0:
            replay_qpos[replay_row] = qpos
        tau = torque[i]
        # mj_step computes the kinematics, contacts and forces of the state it starts from: the state at t.
        snapshot, sums = first_substep()
        tau[:] = actuator_force
        if replay_row >= 0:
            replay_soles[replay_row, 0] = site_xpos[left_site]
            replay_soles[replay_row, 1] = site_xpos[right_site]
        cog[i] = base_com
        zx, zy, fl, fr = contacts.record(i, t, sums, snapshot)
        stack = self.stack
        if stack.ik_feet is not None:  # this tick's command: the soles' tilts the next record compares with
            contacts.command(*stack.ik_feet, stack.toe_off)
        if self.log is not None:
            self.log.record(i, left_foot, right_foot, out, measurement, self.controller.level, truth)
        for j in range(1, n_sub):
            substep(j)
            tau += actuator_force
        if n_sub > 1:
            tau *= 1.0 / n_sub
        pack_planned(planned_bytes, i * planned_row, planned_x, planned_y, command_x, command_y, *dcm, *dcm_planned)
        pack_cog(cog_bytes, i * cog_row, *target_cog)
        support[i] = code
        landings.update(t, phase, code, fl, fr)

        # ----- the last tick's values, and falls ----------------------------------------------------------------
        self.k, self.t, self.phase, self.zmp_measured = k + 1, t, phase, (zx, zy)
        self.left_foot, self.right_foot, self.cog_target = left_foot, right_foot, target_cog
        cause = contacts.fall(base)
        if cause is not None:
            self.fell, self.fall_time, self.fall_cause = True, t, cause
            self._finish()
            return False
        if k + 1 == n_ticks:
            self._finish()
        return True

    def _estimate(self, t: float) -> Measurement | None:
        """The stack's estimate at ``t`` (s, walk clock): of the truth, or of the sensors' readings stamped on the
        walk's clock (their sampling time, latency kept); ``None`` when the safety layer finds a fault."""
        estimate, ground_truth = self.stack.estimate, self.robot.ground_truth
        if self._hot[19]:  # the estimator reads the truth (as step() does)
            joint_truth = self._hot[21]
            return estimate(None if joint_truth is None else joint_truth(t), ground_truth(t, self.log is not None))
        readings = self.robot.read()
        return estimate(readings._replace(t=readings.t - (self.data.time - t)), None)

    def _follow_walk_end(self) -> None:
        """A step's timing changed: the run lasts until the walk as it is now has come to rest (``after`` later), no
        shorter than planned and at most the record's headroom (:func:`~rtgait.sim.loop_options.timing_headroom`)."""
        end = self.planner.end_time
        if not math.isfinite(end):  # a walk by command not stopped yet: followed when it is (WalkInputs' on_stop)
            return
        planned = self._hot[-1]
        wanted = end_tick(end, self.options, self.k0, self.dt)
        n_ticks = min(max(wanted, self._n_ticks_planned, self.k + 1), self._longest)  # type: ignore[type-var]
        if n_ticks != planned:
            self.n_ticks = n_ticks
            self._hot = (*self._hot[:-1], n_ticks)

    def _log(self, events: Sequence[ControlEvent]) -> None:
        """Keep the controller's events: all of them, or those of the last ``keep`` seconds."""
        self.events.extend(events)
        if len(self.events) > 4096 and math.isfinite(self._events_kept):
            oldest = events[-1].t - self._events_kept
            self.events = [e for e in self.events if e.t >= oldest]

    def _finish(self) -> None:
        """The run is over: the clock stops and the pushes are lifted."""
        self._over = True
        if self._ended is None:
            self._ended = time.perf_counter()
            self._pushes.clear()
            self._live.clear()
