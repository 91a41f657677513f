"""Settings of the MuJoCo closed loop (:mod:`rtgait.sim.loop`), and what its start and length are made of."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco

from rtgait.core.analysis.rollout import ScheduledChange
from rtgait.core.laws.stepping import StepAdjustment
from rtgait.core.planner.online import OnlinePlanner
from rtgait.core.push import Push
from rtgait.sim.contact import FallLimits
from rtgait.sim.drive_mode import DriveMode, check_drive
from rtgait.stack.estimators import DEFAULT_STATE, StateSource, check_state

__all__ = [
    "LANDING_WINDOW", "LoopOptions", "end_tick", "minimum_jerk", "run_length", "timing_headroom",
    "walk_length",
]  # fmt: skip

LANDING_WINDOW = 0.5
"""Longest time after a step's planned touch-down (s) in which its foot must be found on the floor; the double
support that follows the landing, when shorter, is the window."""


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
        reactions: ``(time, react)`` pairs: ``react(planner, t)`` is called once, at the first tick ``t`` (s, walk
            clock) at or after ``time``, after ``on_tick`` and before the footstep changes (an obstacle seen then:
            :class:`~rtgait.core.obstacle.avoid.ObstacleReaction`).
        duration: for a walk by command that ``on_tick`` ends: simulate this long after the walk's start (s)
            instead of a length known in advance; ``stop_after_steps`` is then not needed.
        replay_period: the robot's whole configuration is recorded every this many seconds (rounded to whole
            control ticks) for the 3D replay (:attr:`SimResult.replay_q`); 0.04 s is the replay's 25 frames per
            second, and keeps a minute of walking to 1500 rows.
        state: what the controller acts on: ``"estimated"`` (default), the kinematic-inertial estimator on the
            simulated robot's sensor readings (with their noise, bias and latency: ``SimConfig.sensors``), as on a
            robot; ``"truth"``, the simulator's ground truth, to tell the controller's doing from the estimator's
            (:func:`rtgait.stack.estimators.make_estimator`).
        drive: how the joints are driven (:mod:`rtgait.sim.drive_mode`): ``"position"``, the drives' own gains
            (``SimConfig.gains``); ``"torque"``, the motion carried by the feed-forward torques under a tenth of the
            robot's gains.
        feedforward: whether each command carries the feed-forward torques of whole-body inverse dynamics
            (:mod:`rtgait.stack.feedforward`, the DCM law's commanded wrench); ``None``: on with the robot's gains
            (``SimConfig.gains = "robot"``) or torque drive, off with the stiff gains in position drive. Torque
            drive needs them.
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
    reactions: tuple[tuple[float, Callable[[OnlinePlanner, float], object]], ...] = ()
    duration: float | None = None
    state: StateSource = DEFAULT_STATE
    drive: DriveMode = "position"
    feedforward: bool | None = None

    def __post_init__(self) -> None:
        check_state(self.state, "LoopOptions.state")
        check_drive(self.drive, "LoopOptions.drive")
        if self.feedforward is not None and not isinstance(self.feedforward, bool):
            raise ValueError(f"LoopOptions.feedforward must be true, false or None, got {self.feedforward!r}")
        if self.drive == "torque" and self.feedforward is False:
            raise ValueError("LoopOptions.drive 'torque' needs the feed-forward torques (feedforward None or True)")
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

    def feeds_forward(self, gains: str) -> bool:
        """Whether the loop's commands carry feed-forward torques with the drives' own gains ``gains``
        (``SimConfig.gains``): :attr:`feedforward`, or by default with the robot's gains or torque drive."""
        if self.feedforward is not None:
            return self.feedforward
        return gains == "robot" or self.drive == "torque"

    @property
    def lead(self) -> float:
        """Length of the start transition (s): the walk starts this long after the run."""
        return self.start_ramp + self.start_hold


def minimum_jerk(s: float) -> float:
    """0 -> 1 over ``s`` in [0, 1] with zero velocity and acceleration at both ends."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def walk_length(planner: OnlinePlanner, n_steps: int) -> float:
    """Time from the start of a walk of ``n_steps`` steps until its COG is at rest (s)."""
    timing = planner.config.timing
    return (
        timing.start
        + n_steps * timing.single_support
        + (n_steps - 1) * timing.double_support
        + timing.end
        + timing.settle
    )


def timing_headroom(adjust: StepAdjustment | None, n_steps: int, single_support: float, dt: float) -> int:
    """Ticks a walk of ``n_steps`` steps of ``single_support`` s may outgrow its planned length by when step timing
    adaptation (``adjust``) holds stances longer: every step held to ``max_single_support``. 0 when no step can be
    lengthened."""
    if adjust is None or not adjust.adapt_timing or adjust.limits.max_single_support is None:
        return 0
    return math.ceil(n_steps * max(0.0, adjust.limits.max_single_support - single_support) / dt)


def end_tick(end_time: float, options: LoopOptions, k0: int, dt: float) -> int:
    """The tick after which a run whose walk comes to rest at ``end_time`` (s, walk clock) is over: ``options.after``
    later (``k0``: the walk's first tick)."""
    return k0 + math.floor((end_time + options.after) / dt + 1e-9) + 1


def run_length(
    planner: OnlinePlanner, options: LoopOptions, stop_after: int | None, k0: int, dt: float
) -> tuple[int, float, int | None]:
    """How long a run lasts: the walk's steps, when it has come to rest (s, walk clock) and the run's ticks, the
    start transition's ``k0`` included (control period ``dt``, s).

    A walk of footsteps, or by command stopped after ``stop_after`` steps (then ``stop_after + 1`` steps, the last
    closing the feet), is known in advance; a walk by command ended by ``options.on_tick`` lasts
    ``options.duration`` (its steps are counted afterwards: 0 here); one with neither has no end (``inf``, ``None``
    ticks).
    """
    if planner.n_steps is None and stop_after is None:
        if options.duration is None:
            return 0, math.inf, None
        return 0, options.duration, k0 + math.floor(options.duration / dt + 1e-9) + 1
    n_steps = planner.n_steps if stop_after is None else stop_after + 1
    assert n_steps is not None
    walk_end = walk_length(planner, n_steps)
    return n_steps, walk_end, end_tick(walk_end, options, k0, dt)
