"""A walk in MuJoCo from start to end: the closed loop (:class:`~rtgait.sim.loop.ClosedLoop`, one control tick per
step) stepped until the walk's last tick, or until the robot falls, with its whole record as a
:class:`~rtgait.sim.result.SimResult`.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import mujoco

from rtgait.control.controller import WalkingController
from rtgait.core.planner.online import OnlinePlanner
from rtgait.robot.ik import WholeBodyIK
from rtgait.sim.loop import ClosedLoop
from rtgait.sim.loop_options import LoopOptions
from rtgait.sim.model import SimModel
from rtgait.sim.result import SimResult

__all__ = ["run_sim_loop"]


def run_sim_loop(
    sim: SimModel,
    controller: WalkingController | OnlinePlanner,
    options: LoopOptions | None = None,
    *,
    ik: WholeBodyIK | None = None,
    data: mujoco.MjData | None = None,
    progress: Callable[[float], None] | None = None,
) -> SimResult:
    """Walk the controller's walk with the simulated robot ``sim`` in closed loop (see :mod:`rtgait.sim.loop`): a
    :class:`~rtgait.sim.loop.ClosedLoop` stepped to the walk's end, or until the robot falls.

    Args:
        sim: the MuJoCo model of the robot.
        controller: a controller level (:func:`rtgait.control.controller.make_controller`, its period ``sim``'s
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
    loop = ClosedLoop(sim, controller, options, ik=ik, data=data)
    n_ticks = loop.n_ticks
    assert n_ticks is not None  # a whole record needs a known length
    report_every = max(n_ticks // 50, 1)
    step = loop.step
    began = time.perf_counter()
    k = 0
    while step() and not loop.done:  # the run may grow: step timing adaptation can hold a stance longer
        if progress is not None and k % report_every == 0:
            progress(min(k / n_ticks, 1.0))
        k += 1
    wall = time.perf_counter() - began
    if progress is not None:
        progress(1.0)
    return loop.result(wall_time=wall)
