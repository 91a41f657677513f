"""Balance during the loop's start transition, for drives too soft to hold the robot up by stiffness alone.

During the start transition (:attr:`~rtgait.sim.loop_options.LoopOptions.start_ramp`, then ``start_hold``) the
controller has not started: the IK's COM target moves from half-sitting to the walk's start on a minimum-jerk profile
``c_ref(t)`` over the standing feet. Stiff position servos hold the robot on it. Under the robot's own gains they do
not: G1's ankles at 40 N m/rad are softer than gravity's toppling stiffness ``m g h`` (some 210 N m/rad), and the
robot falls within two seconds. Balance then has to come from feedback through the feed-forward torques, as in the
walk. This module gives the transition the walk's DCM law (:class:`~rtgait.core.laws.feedback.DcmFeedback`, the
controller's gains) around the ramp:

    xi_ref = c_ref + c_ref' / w,        p_ref = c_ref - c_ref'' / w^2,
    p_cmd  = p_ref + (1 + k_p / w) (xi - xi_ref) + (k_i / w) I        (inside the two feet's support polygon)

(horizontal axes, m; ``w`` the planner's pendulum frequency, 1/s). The feed-forward moves the IK motion's wrench by
``p_cmd - p_ref`` (:func:`~rtgait.stack.feedforward.commanded_wrench`). Only with feed-forward torques (the stiff
position-only runs are unchanged), and only where the servos cannot hold the robot (:func:`needs_balance`): the two
ankles' pitch stiffness below gravity's toppling stiffness ``m g h`` (``h`` the COM's height at the walk's start).
Where they can (TALOS's two ankles at 5,000 N m/rad each against some 850 N m/rad), the law is left out: the servos
hold the robot, and on TALOS's former undamped gains (Menagerie's, no ``kd``) its ankle torques excited the feet's
rocking.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

from rtgait.core.geometry.footsteps import Footstep
from rtgait.core.geometry.support import support_polygon

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rtgait.control.controller import WalkingController
    from rtgait.core.laws.feedback import DcmFeedback

__all__ = ["StartBalance", "minimum_jerk_rates", "needs_balance"]


def needs_balance(ankle_stiffness: float, mass: float, gravity: float, height: float) -> bool:
    """Whether ankles of summed pitch stiffness ``ankle_stiffness`` (N m/rad, both feet) are softer than gravity's
    toppling stiffness ``m g h`` of a robot of ``mass`` (kg) with its COM ``height`` (m) above the soles."""
    return ankle_stiffness < mass * gravity * height


def minimum_jerk_rates(s: float, duration: float) -> tuple[float, float]:
    """The first and second time derivatives (1/s, 1/s^2) of the minimum-jerk blend
    (:func:`~rtgait.sim.loop_options.minimum_jerk`) at the fraction ``s`` in [0, 1] of a ramp of ``duration`` (s);
    zero outside the ramp."""
    if not (duration > 0.0 and 0.0 < s < 1.0):
        return 0.0, 0.0
    rate = 30.0 * s * s * (1.0 - s) * (1.0 - s) / duration
    acceleration = (60.0 * s - 180.0 * s * s + 120.0 * s * s * s) / (duration * duration)
    return rate, acceleration


class StartBalance:
    """The DCM law of the start transition (module docstring).

    Args:
        controller: the walking controller, closed-loop (its law's gains, its sole, its planner's ``w``).
        left, right: the standing feet ``(x, y, z, yaw)`` (m, rad).
    """

    def __init__(self, controller: WalkingController, left: Sequence[float], right: Sequence[float]) -> None:
        feedback = controller.feedback
        if feedback is None:
            raise ValueError("the start transition's balance needs a closed-loop controller level")
        self.law: DcmFeedback = copy.deepcopy(feedback)
        self.law.reset()
        self.w = controller.planner.w
        feet = [Footstep(left[0], left[1], left[3], "left"), Footstep(right[0], right[1], right[3], "right")]
        self.polygon = support_polygon(feet, controller.sole)

    def update(
        self,
        dcm: Sequence[float],
        com: Sequence[float],
        com_rate: Sequence[float],
        com_acceleration: Sequence[float],
    ) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
        """The commanded ZMP, the reference ZMP and the reference DCM (m) for the measured DCM ``dcm`` and the ramp's
        COM, its velocity and acceleration (m, m/s, m/s^2)."""
        w = self.w
        dcm_ref = (com[0] + com_rate[0] / w, com[1] + com_rate[1] / w)
        zmp_ref = (com[0] - com_acceleration[0] / (w * w), com[1] - com_acceleration[1] / (w * w))
        out = self.law.update(zmp_ref, dcm_ref, (dcm[0], dcm[1]), self.polygon)
        return out.zmp, zmp_ref, dcm_ref
