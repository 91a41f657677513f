"""The stack's feed-forward torques: whole-body inverse dynamics of the IK's motion with the wrenches the controller
asks of the feet.

Per tick, from the IK's configuration ``q``:

1. its velocity and acceleration by low-passed backward differences (:class:`~rtgait.robot.motion_rates.MotionRates`);
2. RNEA and the wrench ``W`` the feet must give the robot for that motion
   (:class:`~rtgait.robot.inverse_dynamics.InverseDynamics`);
3. the desired split: the controller's commanded ZMP shared between the feet in contact as the foot force control
   shares it (:func:`~rtgait.control.foot_control.split_zmp`: load ratio and a CoP per foot); without a controller
   (:meth:`~rtgait.stack.walking_stack.WalkingStack.hold`) the motion's own ZMP in double support;
4. the feet's wrenches nearest that split that sum to ``W`` within the soles' contact wrench cones
   (:mod:`rtgait.robot.contact_wrenches`: closed form, a QP when a cone binds);
5. ``tau = RNEA_joints - sum J^T w`` (N m), which the stack's safety layer clips to the joints' torque limits and
   counts (:mod:`rtgait.stack.command_limits`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from rtgait.control.foot_control import split_zmp
from rtgait.robot.contact_wrenches import DEFAULT_FRICTION
from rtgait.robot.inverse_dynamics import InverseDynamics
from rtgait.robot.motion_rates import DEFAULT_RATE_FILTER, MotionRates

if TYPE_CHECKING:
    import numpy as np

    from rtgait.control.settings import ControlTargets
    from rtgait.core.geometry.footsteps import SoleRect
    from rtgait.interface.task_targets import IKTargets
    from rtgait.robot.contact_wrenches import WrenchDistribution
    from rtgait.robot.model import RobotModel

__all__ = ["FeedForward"]

_CONTACT = {"double": (True, True), "left": (True, False), "right": (False, True)}  # the feet carrying load
_INFEASIBLE = 1.0  # N: a residual beyond rounding and the QP's weighting (rtgait.robot.contact_wrenches.SUM_WEIGHT)


class FeedForward:
    """Feed-forward joint torques for each tick's IK solution (module docstring).

    Args:
        robot: the loaded robot.
        sole: the sole rectangle (m), the controller's.
        dt: the control period (s).
        friction: the floor's Coulomb friction coefficient.
        rate_filter: the time constant of the velocity's and acceleration's low-pass (s).

    Attributes:
        dynamics: the inverse dynamics (its distributor's ``qp_count`` counts the ticks the QP ran).
        rates: the IK motion's velocity and acceleration.
        last: the last tick's wrench distribution (``None`` before the first).
        ticks: ticks computed.
        infeasible: ticks whose required wrench no distribution within the cones gave (the motion's ZMP outside the
            support polygon, or its horizontal force beyond friction).
    """

    def __init__(
        self,
        robot: RobotModel,
        sole: SoleRect,
        dt: float,
        friction: float = DEFAULT_FRICTION,
        rate_filter: float = DEFAULT_RATE_FILTER,
    ) -> None:
        self.dynamics = InverseDynamics(robot, sole, friction)
        self.rates = MotionRates(robot.model, dt, rate_filter)
        self.sole = sole
        self.last: WrenchDistribution | None = None
        self.ticks = self.infeasible = 0

    def reset(self) -> None:
        """Forget the motion: the next configuration starts at rest."""
        self.rates.reset()

    def torques(self, q: np.ndarray, targets: IKTargets, out: ControlTargets | None) -> np.ndarray:
        """The joints' feed-forward torques (N m, in joint order) for the IK's configuration ``q``, the IK's
        ``targets`` (their feet are the split's) and the controller's output (``None``: no controller)."""
        v, a = self.rates.update(q)
        dynamics = self.dynamics
        required = dynamics.update(q, v, a)
        left, right = targets.left_foot, targets.right_foot
        if out is None:
            support = "double"
            frames = dynamics.sole_frames
            zmp = required.zmp(0.5 * float(frames[0][2, 3] + frames[1][2, 3]))
        else:
            support, zmp = out.support, out.zmp_command
        if not (math.isfinite(zmp[0]) and math.isfinite(zmp[1])):  # no upward force (a fall): split in the middle
            zmp = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
        split = split_zmp(zmp, left, right, self.sole, support)
        distribution = dynamics.distribute(_CONTACT[support], split.left_ratio, split.left_cop, split.right_cop)
        self.last = distribution
        self.ticks += 1
        if distribution.residual > _INFEASIBLE:
            self.infeasible += 1
        return dynamics.torques(distribution.wrenches)
