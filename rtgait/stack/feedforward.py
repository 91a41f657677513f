"""The stack's feed-forward torques: whole-body inverse dynamics of the IK's motion with the wrenches the controller
asks of the feet.

Per tick, from the IK's configuration ``q``:

1. its velocity and acceleration by low-passed backward differences (:class:`~rtgait.robot.motion_rates.MotionRates`;
   a tick on which a joint would move faster than its speed limit is a jump of the reference, not differenced);
2. RNEA and the wrench ``W`` the feet must give the robot for that motion
   (:class:`~rtgait.robot.inverse_dynamics.InverseDynamics`), its ZMP moved by the DCM law's correction (below);
3. the desired split: the controller's commanded ZMP shared between the feet in contact as the foot force control
   shares it (:func:`~rtgait.control.foot_control.split_zmp`: load ratio and a CoP per foot); without a controller
   (:meth:`~rtgait.stack.walking_stack.WalkingStack.hold`) the motion's own ZMP in double support;
4. the feet's wrenches nearest that split that sum to ``W`` within the soles' contact wrench cones
   (:mod:`rtgait.robot.contact_wrenches`: closed form, a QP when a cone binds);
5. ``tau = RNEA_joints - sum J^T w`` (N m), plus, on drives with friction, the part of it the drive compensates at
   the command's joint velocities (:mod:`rtgait.stack.friction_compensation`), which the stack's safety layer
   clips to the joints' torque limits and counts (:mod:`rtgait.stack.command_limits`).

**The wrench the DCM law commands.** The IK's motion follows the plan's COM (with the COM correction), so the
motion's wrench has the plan's ZMP ``p_ref``, not the commanded ``p_cmd = p_ref + (1 + k_p / w) e + ...``: feet that
gave only the motion's wrench would carry none of the balance feedback, which on drives of low gains must come from
the torques (the ankles' stiffness is below gravity's toppling stiffness ``m g h``). The required wrench ``(F, N)``
(world axes, about the origin) is therefore moved to the ZMP ``p + dp``, ``dp = p_cmd - p_ref`` the law's correction,
with its line of action still through the COM target ``c`` (the rate of angular momentum ``N - c x F`` kept):

    dF_xy = -F_z dp / (c_z - h),        dN = c x dF                                              (N, N m)

(``h`` the soles' mean height; the pendulum's ``c'' = w^2 (c - p)`` with ``w^2 = g / (c_z - h)``: the COM is asked the
acceleration that the commanded ZMP gives it). With the joints' rows of ``tau = RNEA - sum J^T w`` the legs then push
the floor with the commanded wrench, and the difference from the motion's accelerates the robot as the law asks.
``open-loop`` (``p_cmd = p_ref``) and :meth:`~rtgait.stack.walking_stack.WalkingStack.hold` move nothing.

**At the sensed state** (``tracking`` given and the tick's sensed joints passed; the closed loop always does): step 2
runs at the robot's sensed configuration and velocity (:mod:`rtgait.stack.measured_motion`: the base placed on the
stance sole as estimated, the joints at their encoders) with the IK's acceleration, instead of at the IK's own
configuration, so that gravity's torques are those of where the robot is. Torque drive's ``tracking`` adds the base's
task and the joints' tracking torques: the torques then carry the motion under low drive gains. The truth's estimator
reads no encoders: on it the simulator passes the joints' true positions and velocities
(:meth:`~rtgait.sim.robot.SimRobot.joint_truth`). Without sensed joints the tick falls back to the IK's configuration,
whose gravity torques leave a drive as soft as G1's waist nearly no stiffness (:mod:`rtgait.stack.measured_motion`,
"Position drive").
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rtgait.control.foot_control import split_zmp
from rtgait.robot.contact_wrenches import DEFAULT_FRICTION
from rtgait.robot.inverse_dynamics import InverseDynamics, RequiredWrench, wrench_zmp
from rtgait.robot.joint_limits import joint_limits
from rtgait.robot.motion_rates import DEFAULT_RATE_FILTER, MotionRates

if TYPE_CHECKING:
    from rtgait.control.settings import ControlTargets
    from rtgait.core.geometry.footsteps import SoleRect
    from rtgait.estimation.state import Measurement
    from rtgait.interface.body_kinematics import BodyKinematics
    from rtgait.interface.task_targets import IKTargets
    from rtgait.robot.contact_wrenches import WrenchDistribution
    from rtgait.robot.model import RobotModel
    from rtgait.stack.friction_compensation import FrictionCompensation
    from rtgait.stack.measured_motion import MeasuredMotion

__all__ = ["FeedForward", "commanded_wrench"]

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
        tracking: the sensed state and tracking acceleration to compute the torques at (module docstring); ``None``:
            the IK's configuration and motion.
        friction_compensation: the joints' friction to compensate at the command's joint velocities (the IK
            motion's without them; :mod:`rtgait.stack.friction_compensation`); ``None``: none (ideal drives).

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
        tracking: MeasuredMotion | None = None,
        friction_compensation: FrictionCompensation | None = None,
    ) -> None:
        self.dynamics = InverseDynamics(robot, sole, friction)
        self.tracking = tracking
        self.friction_compensation = friction_compensation
        self.rates = MotionRates(robot.model, dt, rate_filter, joint_limits(robot).velocity)
        self.sole = sole
        self.last: WrenchDistribution | None = None
        self.ticks = self.infeasible = 0

    def reset(self) -> None:
        """Forget the motion: the next configuration starts at rest."""
        self.rates.reset()

    def torques(
        self,
        q: np.ndarray,
        targets: IKTargets,
        out: ControlTargets | None,
        shift: tuple[float, float] | None = None,
        sensed: tuple[np.ndarray, np.ndarray, np.ndarray, Measurement, BodyKinematics | None] | None = None,
        velocities: np.ndarray | None = None,
    ) -> np.ndarray:
        """The joints' feed-forward torques (N m, in joint order) for the IK's configuration ``q``, the IK's
        ``targets`` (their feet are the split's) and the controller's output (``None``: no controller; then
        ``shift`` (m), when given, moves the motion's ZMP as the controller's ``p_cmd - p_ref`` does, e.g. the start
        transition's law, :mod:`rtgait.sim.start_balance`). ``sensed``: the commanded joints (rad), the encoders'
        positions (rad) and velocities (rad/s) and the tick's estimate, with which a ``tracking`` feed-forward
        computes the torques at the sensed state (module docstring), and the estimator's kinematics of those encoder
        readings (``None``: computed again, :mod:`rtgait.stack.measured_motion`). ``velocities``: the command's joint
        velocity references (rad/s, the joints' order), at which the friction is compensated (``None``: the IK
        motion's)."""
        v, a = self.rates.update(q)
        # The friction is compensated at the velocity the drives are told to follow: the command's, which holds the
        # feet's tilts at the ankles that the IK's motion leaves out (else the IK motion's, before the sensed state's).
        joint_velocities = v[6:] if velocities is None else velocities
        dynamics = self.dynamics
        if self.tracking is not None and sensed is not None:
            q, v, a = self.tracking.update(q, v, a, *sensed)
        # The wrench as Python floats from here to the distribution (the same arithmetic as on arrays, fewer calls).
        wrench = dynamics.compute(q, v, a)
        left, right = targets.left_foot, targets.right_foot
        rows = dynamics.sole_rows
        floor = 0.5 * (rows[0][2][3] + rows[1][2][3])
        if out is None:
            support = "double"
            if shift is not None and math.isfinite(shift[0] + shift[1]):
                wrench = _moved(wrench, shift, targets.cog, floor)
                dynamics.require_values(wrench)
            zmp = wrench_zmp(wrench, floor)
        else:
            support, zmp = out.support, out.zmp_command
            shift = (zmp[0] - out.zmp_planned[0], zmp[1] - out.zmp_planned[1])
            if (shift[0] != 0.0 or shift[1] != 0.0) and math.isfinite(shift[0] + shift[1]):
                wrench = _moved(wrench, shift, out.com, floor)
                dynamics.require_values(wrench)
        if not (math.isfinite(zmp[0]) and math.isfinite(zmp[1])):  # no upward force (a fall): split in the middle
            zmp = (0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1]))
        split = split_zmp(zmp, left, right, self.sole, support)
        distribution = dynamics.distribute(_CONTACT[support], split.left_ratio, split.left_cop, split.right_cop)
        self.last = distribution
        self.ticks += 1
        if distribution.residual > _INFEASIBLE:
            self.infeasible += 1
        torques = dynamics.torques(distribution.wrenches)
        if self.tracking is not None and sensed is not None:
            torques += self.tracking.feedback
        if self.friction_compensation is not None:
            torques += self.friction_compensation.torques(joint_velocities)
        return torques


def commanded_wrench(
    required: RequiredWrench, shift: tuple[float, float], com: tuple[float, float, float], floor: float
) -> RequiredWrench:
    """``required`` (world axes, about the origin; N, N m) with its ZMP moved by ``shift`` (m), its line of action
    kept through ``com`` (m) over the floor at height ``floor`` (m): the module docstring's ``dF``, ``dN``; unchanged
    without an upward force or with the COM not above the floor."""
    values = [*required.force.tolist(), *required.moment.tolist()]
    moved = _moved(values, shift, com, floor)
    if moved is values:
        return required
    return RequiredWrench(np.array(moved[:3]), np.array(moved[3:]))


def _moved(
    wrench: list[float], shift: tuple[float, float], com: tuple[float, float, float], floor: float
) -> list[float]:
    """:func:`commanded_wrench` on the wrench as six Python floats (force then moment); ``wrench`` itself when
    unchanged."""
    fx, fy, fz, nx, ny, nz = wrench
    height = com[2] - floor
    if not (fz > 0.0 and height > 0.0):
        return wrench
    dfx, dfy = -fz * shift[0] / height, -fz * shift[1] / height
    cx, cy, cz = com
    # The sums as the arrays' were: F + (dF_x, dF_y, 0) and N + c x dF.
    return [fx + dfx, fy + dfy, fz + 0.0, nx + -cz * dfy, ny + cz * dfx, nz + (cx * dfy - cy * dfx)]
