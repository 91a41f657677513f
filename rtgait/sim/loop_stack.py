"""The controller stack the MuJoCo closed loop drives (:class:`~rtgait.sim.loop.ClosedLoop`), built for one run.

The estimator (:attr:`~rtgait.sim.loop_options.LoopOptions.state`: the ground-truth one on the simulator's truth, the
kinematic-inertial one on the robot's sensors, its world frame the walk's standing feet, the DCM with the planner's
``w`` in 1/s), the controller level, the whole-body IK and, when the options ask for them, the feed-forward torques
(the IK's motion through inverse dynamics, the DCM law's wrench at the feet, N m) with the drives' gains: the robot's
own, or torque drive's low gains that every command then carries (:mod:`rtgait.sim.drive_mode`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from rtgait.control.controller import ControllerOptions, WalkingController
from rtgait.robot.controller_info import robot_info
from rtgait.sim.drive_mode import torque_gains
from rtgait.stack.estimators import make_estimator
from rtgait.stack.feedforward import FeedForward
from rtgait.stack.friction_compensation import FrictionCompensation, identified_friction
from rtgait.stack.measured_motion import MeasuredMotion
from rtgait.stack.walking_stack import WalkingStack

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy as np

    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.estimation.estimator import Estimator
    from rtgait.robot.ik import WholeBodyIK
    from rtgait.sim.loop_options import LoopOptions
    from rtgait.sim.model import SimModel

__all__ = ["LoopStack", "build_stack", "open_loop_controller"]


def open_loop_controller(sim: SimModel, planner: OnlinePlanner) -> WalkingController:
    """The ``open-loop`` level around ``planner`` (not started): the plan alone, as the paper assumes."""
    info = robot_info(sim.robot, gains=sim.config.gains)
    return WalkingController("open-loop", planner, info, sim.control_dt, ControllerOptions())


class LoopStack(NamedTuple):
    """The stack of one run and the parts of it the loop reads each tick."""

    stack: WalkingStack
    estimator: Estimator
    feedforward: FeedForward | None
    """The feed-forward torques, ``None``: position servos alone."""
    drive_gains: tuple[np.ndarray, np.ndarray] | None
    """The gains every command carries (torque drive), ``None``: the drives' own."""


def build_stack(
    sim: SimModel,
    controller: WalkingController,
    ik: WholeBodyIK,
    q: np.ndarray,
    options: LoopOptions,
    gravity: float,
    start_feet: tuple[Sequence[float], Sequence[float]],
) -> LoopStack:
    """The stack of a run of ``sim`` from configuration ``q`` (the IK's start solution), ``gravity`` (m/s^2) and the
    walk's standing feet ``start_feet`` (left, right: ``(x, y, z, yaw)``, m, rad)."""
    robot = sim.robot
    left, right = start_feet
    # With the motor model the joints have their gears' friction: the estimate of the feet's wrenches from the joint
    # torques takes its identified value out of them, and the feed-forward compensates it.
    friction = identified_friction(robot) if sim.config.motor_model else None
    estimator = make_estimator(
        options.state, robot, controller.planner.w, gravity=gravity, start_feet=(tuple(left), tuple(right)),
        joint_friction=friction, sensor_noise=sim.config.sensors.noise,
    )  # fmt: skip
    # Feed-forward torques are computed at the sensed state; torque drive adds the tracking of the IK's motion
    # (measured_motion.py).
    feed = None
    if options.feeds_forward(sim.config.gains):
        tracking = MeasuredMotion(robot, track=options.drive == "torque")
        compensation = FrictionCompensation.of(robot) if friction is not None else None
        feed = FeedForward(robot, controller.sole, sim.control_dt, friction=sim.config.friction,
                           tracking=tracking, friction_compensation=compensation)  # fmt: skip
    stack = WalkingStack(estimator, controller, ik, q, feedforward=feed)
    gains = torque_gains(sim, feed.tracking if feed is not None else None) if options.drive == "torque" else None
    return LoopStack(stack, estimator, feed, gains)
