"""The MuJoCo closed loop's start transition (:class:`~rtgait.sim.loop.ClosedLoop`), before the planner's clock runs.

The walk starts from half-sitting, whose COG is higher than the planner's constant COG height: for
:attr:`~rtgait.sim.loop_options.LoopOptions.start_ramp` seconds the IK's COG target moves on a minimum-jerk profile

    c_ref(k) = c_0 + s(k dt / T) (c_1 - c_0),    s(u) = 10 u^3 - 15 u^4 + 6 u^5 (1 after the ramp)

from half-sitting's COG ``c_0`` to the walk's start ``c_1`` (m; ``T`` the ramp, s), then holds it at rest
(``start_hold``), over the planner's standing feet. It runs at negative times on the walk's clock, with no feedback;
drives too soft to hold the robot up get the DCM law around the ramp (:mod:`rtgait.sim.start_balance`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from rtgait.interface.task_targets import IKTargets
from rtgait.sim.loop_options import minimum_jerk
from rtgait.sim.start_balance import StartBalance, minimum_jerk_rates, needs_balance

if TYPE_CHECKING:
    import numpy as np

    from rtgait.control.controller import WalkingController
    from rtgait.estimation.state import Measurement
    from rtgait.sim.model import SimModel
    from rtgait.stack.walking_stack import StackOutput, WalkingStack

__all__ = ["StartTransition", "start_balance"]

_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing


def start_balance(
    sim: SimModel,
    controller: WalkingController,
    stack: WalkingStack,
    drive_gains: tuple[np.ndarray, np.ndarray] | None,
    gravity: float,
    start_feet: tuple[Sequence[float], Sequence[float], Sequence[float]],
) -> StartBalance | None:
    """The start transition's DCM law, with feed-forward torques and a closed-loop level on ankles too soft to hold
    the robot (:func:`~rtgait.sim.start_balance.needs_balance`), else ``None``; ``start_feet``: the walk's start COG
    and feet (m)."""
    if stack.feedforward is None or controller.feedback is None:
        return None
    cog_start, left, right = start_feet
    ankles = stack.ankles
    kp = sim.actuation.kp if drive_gains is None else drive_gains[0]
    stiffness = float(kp[ankles.left_pitch] + kp[ankles.right_pitch])
    if needs_balance(stiffness, sim.robot.mass, gravity, cog_start[2]):
        return StartBalance(controller, left, right)
    return None


class StartTransition:
    """The references of the start transition's ticks (module docstring), given to ``stack``'s hold command.

    Args:
        stack: the run's stack.
        ramp: the ramp's duration ``T`` (s).
        cog_half_sitting, cog_start: ``c_0`` and ``c_1`` (m).
        left, right: the standing feet ``(x, y, z, yaw)`` (m, rad).
        balance: the DCM law of soft drives, ``None``: none.
        estimate: the stack's estimate at a time (s, walk clock), ``None`` when the safety layer finds a fault.
    """

    def __init__(
        self,
        stack: WalkingStack,
        ramp: float,
        cog_half_sitting: Sequence[float],
        cog_start: Sequence[float],
        left: Sequence[float],
        right: Sequence[float],
        balance: StartBalance | None,
        estimate: Callable[[float], Measurement | None],
    ) -> None:
        self.stack, self.ramp, self.balance, self.estimate = stack, ramp, balance, estimate
        self.cog_half_sitting, self.cog_start, self.left, self.right = cog_half_sitting, cog_start, left, right

    def tick(self, k: int, t: float, dt: float) -> tuple[
        StackOutput, list[float], tuple[float, float], tuple[float, float], tuple[float, float], tuple[float, float]
    ]:  # fmt: skip
        """Tick ``k`` (at ``t`` s on the walk's clock, ``dt`` s the period): the stack's command, the COG target (m),
        the planned and commanded ZMP (m), the measured and planned DCM (m; NaN without the DCM law)."""
        ramp = self.ramp
        s = minimum_jerk(k * dt / ramp) if ramp > 0.0 else 1.0
        target_cog = [a + s * (b - a) for a, b in zip(self.cog_half_sitting, self.cog_start, strict=True)]
        planned_x = command_x = target_cog[0]
        planned_y = command_y = target_cog[1]
        dcm = dcm_planned = (math.nan, math.nan)
        targets = _new_tuple(IKTargets, (target_cog, self.left, self.right, None))
        balance, stack = self.balance, self.stack
        if balance is None and stack.feedforward is not None and stack.feedforward.tracking is not None:
            made = stack.hold(targets, t, None, self.estimate(t))  # the feed-forward torques at the sensed state
        elif balance is None:
            made = stack.hold(targets, t)
        else:  # soft drives: the DCM law around the ramp, through the feed-forward torques (start_balance.py)
            state = self.estimate(t)
            if state is None:  # the safety layer found a fault: the stack damps
                made = stack.control(t, None)
            else:
                rate, acceleration = minimum_jerk_rates(k * dt / ramp, ramp) if k * dt < ramp else (0.0, 0.0)
                delta = [b - a for a, b in zip(self.cog_half_sitting[:2], self.cog_start[:2], strict=True)]
                (command_x, command_y), (planned_x, planned_y), dcm_planned = balance.update(
                    state.dcm, target_cog, (rate * delta[0], rate * delta[1]),
                    (acceleration * delta[0], acceleration * delta[1]),
                )  # fmt: skip
                dcm = state.dcm
                made = stack.hold(targets, t, (command_x - planned_x, command_y - planned_y), state)
        return made, target_cog, (planned_x, planned_y), (command_x, command_y), dcm, dcm_planned
