"""A controller stack made for a walk on a robot model: the controller level, its planner, the IK, the estimator,
and the standing configuration the walk starts from."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rtgait.control.controller import make_controller
from rtgait.interface.task_targets import IKTargets
from rtgait.robot.controller_info import robot_info
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.ik_terms import SMOOTH_LIMITS
from rtgait.stack.estimators import DEFAULT_STATE, StateSource, check_state, make_estimator
from rtgait.stack.feedforward import FeedForward
from rtgait.stack.walking_stack import WalkingStack

if TYPE_CHECKING:
    from rtgait.control.settings import ControllerOptions
    from rtgait.core.pendulum.loop import Controller
    from rtgait.core.planner.online import OnlinePlanner
    from rtgait.estimation.estimator import Estimator
    from rtgait.robot.model import RobotModel
    from rtgait.scenario.scenario import Scenario

__all__ = ["start_pose", "walking_stack"]


def start_pose(planner: OnlinePlanner) -> tuple[list[float], list[float], list[float]]:
    """COG ``(x, y, z)`` and feet ``(x, y, z, yaw)`` at the start of the walk: standing, COG between the feet.

    Read from the first two footprints rather than by sampling, so the planner stays unsampled (an early footstep
    change is still accepted at its deadline).
    """
    first, second = planner.footprints(1)[:2]
    left, right = (first, second) if first.side == "left" else (second, first)
    cog = [0.5 * (left.x + right.x), 0.5 * (left.y + right.y), planner.config.cog_height]
    return cog, [left.x, left.y, 0.0, left.yaw], [right.x, right.y, 0.0, right.yaw]


def walking_stack(
    robot: RobotModel,
    walk: Scenario,
    *,
    dt: float,
    level: Controller = "adaptive",
    options: ControllerOptions | None = None,
    estimator: Estimator | None = None,
    state: StateSource = DEFAULT_STATE,
    feedforward: bool = False,
) -> WalkingStack:
    """The stack that walks ``walk`` on ``robot`` at control period ``dt`` (s).

    Args:
        robot: the robot's model.
        walk: the scenario, made for the robot (:func:`rtgait.robot.motion.robot_scenario` gives it the robot's COG
            height, sole and step width).
        dt: the control period (s).
        level: the controller level (:mod:`rtgait.control.controller`).
        options: the controller's settings; default :class:`~rtgait.control.settings.ControllerOptions`.
        estimator: readings -> walking state; default the one ``state`` names.
        state: ``"estimated"`` (default: the kinematic-inertial estimator on the robot's sensors, its world frame
            the walk's standing feet) or ``"truth"`` (the ground-truth estimator, on a simulator's truth):
            :func:`rtgait.stack.estimators.make_estimator`.
        feedforward: fill each command's ``torques`` with the feed-forward torques of whole-body inverse dynamics
            (:class:`~rtgait.stack.feedforward.FeedForward`, the walk's sole, the floor's default friction); off by
            default (no torques: the commands of a position-controlled robot).

    The stack's configuration :attr:`WalkingStack.q` is the walk's standing start: the COG between the first two
    footprints at the walking height, the soles level (the IK solved from half-sitting). Start the robot there.
    """
    check_state(state)
    controller = make_controller(
        level, walk.planner_config(), walk.strides(), walk.sole, robot_info(robot), dt=dt, options=options,
        terrain=walk.placed_on,
    )  # fmt: skip
    # The feed-forward differences the IK's reference twice: keep its rate continuous near joint limits.
    ik = WholeBodyIK(robot, SMOOTH_LIMITS if feedforward else None)
    cog, left, right = start_pose(controller.planner)
    q, _ = ik.solve(IKTargets(cog, left, right), robot.q_half_sitting, 200, 1e-9)
    if estimator is None:
        planner = controller.planner
        feet = (tuple(left), tuple(right))
        estimator = make_estimator(state, robot, planner.w, gravity=planner.config.gravity, start_feet=feet)
    feed = FeedForward(robot, walk.sole, dt) if feedforward else None
    return WalkingStack(estimator, controller, ik, q, feedforward=feed)
