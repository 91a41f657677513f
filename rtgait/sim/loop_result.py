"""The outcome of a closed-loop run (:class:`rtgait.sim.loop.ClosedLoop`): its record and counts as one
:class:`~rtgait.sim.result.SimResult` (:func:`loop_result`, behind
:meth:`ClosedLoop.result <rtgait.sim.loop.ClosedLoop.result>`).

What it states about the walk, as the walk ended up rather than as it was set out:

* *steps planned*: a walk of footsteps, or one by command once stopped, counts the planner's steps at the end (step
  adjustment may have changed the walk); one by command not stopped yet, those it is set out for
  (``stop_after_steps + 1``, :func:`~rtgait.sim.loop_options.run_length`); one never to be stopped (ended by
  ``on_tick``, or open-ended), the steps that landed;
* *walk end* (s, walk clock): the planner's end time, where the walk comes to rest (a stance that step timing
  adaptation held longer ends it later); with ``LoopOptions.duration`` no later than the duration's end; an
  open-ended walk's is its last tick's time;
* the per-tick arrays of the record in tick order (a ring that has wrapped keeps its last ticks,
  :class:`~rtgait.sim.loop_record.TickRecord`), the replay's frames among them, and the controller's events from the
  first tick kept on.

Nothing here runs per tick: it is read once the run is over, or whenever a live caller asks for the record so far.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

from rtgait.sim.drive_summary import drive_summary
from rtgait.sim.result import SimResult

if TYPE_CHECKING:
    from rtgait.control.controller import ControlEvent, WalkingController
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.core.push import Push
    from rtgait.sim.contact import ContactMonitor, Landings
    from rtgait.sim.drive_summary import ComTracking
    from rtgait.sim.loop_options import LoopOptions
    from rtgait.sim.loop_record import TickRecord
    from rtgait.sim.model import SimModel
    from rtgait.sim.robot import SimRobot
    from rtgait.sim.tick_log import TickLog
    from rtgait.stack.walking_stack import WalkingStack

__all__ = ["RunState", "loop_result"]


class RunState(Protocol):
    """What the outcome is made of: the closed loop's state after its ticks (:class:`rtgait.sim.loop.ClosedLoop`)."""

    sim: SimModel
    planner: OnlinePlanner
    controller: WalkingController
    stack: WalkingStack
    options: LoopOptions
    record: TickRecord
    contacts: ContactMonitor
    landings: Landings
    log: TickLog | None
    robot: SimRobot
    events: Sequence[ControlEvent]
    pushes: Sequence[Push]
    k: int
    k0: int
    t: float
    dt: float
    gravity: float
    threshold: float
    fell: bool
    fall_time: float | None
    fall_cause: str | None
    com_tracking: ComTracking
    feedforward_clipped: int | None


def loop_result(loop: RunState, wall_time: float, n_steps: int, walk_end: float) -> SimResult:
    """The :class:`SimResult` of the ``loop.k`` ticks ``loop`` has run (at least one): the record's arrays, the
    walk's outcome (module docstring) and the wall-clock time ``wall_time`` (s) to report.

    Args:
        loop: the closed loop, stepped at least once.
        wall_time: the loop's wall-clock time (s).
        n_steps: the steps the run was set out for (0: a walk that was not known to end).
        walk_end: the walk's planned end when the run was set out (s, walk clock; ``inf``: not known).
    """
    planner, sim, options = loop.planner, loop.sim, loop.options
    robot = sim.robot
    ticks = loop.k
    if planner.started and planner.n_steps is not None:  # as the walk ended up (step adjustment may shorten it)
        n_steps = planner.n_steps
        walk_end = min(planner.end_time, walk_end) if options.duration is not None else planner.end_time
    elif n_steps == 0:  # ended by on_tick or open-ended, never stopped: the steps that landed
        n_steps = loop.landings.count
    if not math.isfinite(walk_end):
        walk_end = loop.t
    arrays = loop.record.arrays(ticks, loop.contacts, loop.threshold, loop.k0, loop.dt)
    replay_index, replay_qpos, replay_soles = loop.record.replay(ticks)
    first = float(arrays["times"][0])
    events = [e for e in loop.events if e.t >= first]
    log = loop.log.finish(ticks) if loop.log is not None else None
    config = sim.config
    settings = {
        "gains": config.gains, "drive": options.drive, "feedforward": loop.stack.feedforward is not None,
        "motor_model": config.motor_model, "command_delay": config.command_delay,
    }  # fmt: skip
    drive = drive_summary(
        sim, settings, arrays["torque"], None if log is None else log.joint_velocity, loop.feedforward_clipped,
        max(ticks - loop.k0, 0), loop.com_tracking,
    )  # fmt: skip
    return SimResult(
        **arrays,
        joint_names=sim.joint_names,
        control_dt=loop.dt,
        physics_dt=sim.timestep,
        run_start=first,
        walk_end=float(walk_end),
        steps_planned=n_steps,
        steps_completed=loop.landings.count,
        missed_landings=loop.landings.missed,
        fell=loop.fell,
        fall_time=loop.fall_time,
        fall_cause=loop.fall_cause,
        tipped=loop.contacts.tip_time is not None,
        tip_time=loop.contacts.tip_time,
        wall_time=wall_time,
        robot=robot.name,
        mass=robot.mass,
        controller=loop.controller.level,
        replay_index=replay_index,
        replay_q=sim.full_configurations(replay_qpos),
        replay_soles=replay_soles,
        footprints=tuple(planner.footprints()) if planner.started else (),
        pushes=tuple(loop.pushes),
        events=tuple(events),
        step_adjustments=tuple(planner.step_adjustments) if planner.started else (),
        replans=planner.replan_count if planner.started else 0,
        model=robot.model,
        gravity=loop.gravity,
        log=log,
        model_error=sim.model_error,
        safety_events=tuple(e for e in loop.stack.safety.events if e.t >= first),
        safety=loop.stack.safety.summary(),
        drive=drive,
        state=options.state,
        sensors=dataclasses.replace(sim.config.sensors, latency=loop.robot.sensors.latency),
    )
