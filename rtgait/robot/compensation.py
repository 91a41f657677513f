"""The paper's Appendix A on a real robot: measure the angular momentum of the whole-body motion, correct the
COG in closed form so that its ZMP shift is cancelled, and solve the inverse kinematics again.

The planner assumes the pendulum ZMP ``c - c''/w^2``; the legs' and trunk's angular momentum move the real
(multibody) ZMP by ``(-L'_y, L'_x) / (M g)``. :func:`rtgait.core.lipm.angular.fit_correction` turns that shift,
expanded per walking phase in a truncated Fourier series, into a COG correction ``dc``; the corrected motion's
multibody ZMP is then compared with the planned one again.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.lipm.angular import DEFAULT_ORDER, FourierCorrection, angular_zmp_offset, fit_correction
from rtgait.core.lipm.closed_form import omega
from rtgait.robot.dynamics import MultibodyCheck, check_motion
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import JointTrajectory, whole_body_motion


@dataclass(frozen=True)
class Compensation:
    """The corrected motion and what it changed.

    Attributes:
        order: Fourier order per phase.
        correction: the closed-form COG correction ``dc``.
        cog_offset: ``dc`` at every tick, ``(k, 2)`` (m).
        motion: the whole-body motion with the corrected COG.
        check: its multibody check against the planned ZMP.
    """

    order: int
    correction: FourierCorrection
    cog_offset: np.ndarray
    motion: JointTrajectory
    check: MultibodyCheck


def compensate_angular_momentum(
    robot: RobotModel,
    rollout: Rollout,
    check: MultibodyCheck,
    cog_height: float,
    gravity: float,
    order: int = DEFAULT_ORDER,
) -> Compensation:
    """Correct the COG of the walk ``rollout`` for the angular momentum measured in ``check`` and redo the IK.

    Args:
        robot: the robot.
        rollout: the planned walk.
        check: multibody check of the uncorrected motion (its angular momentum rate is what is cancelled).
        cog_height: the planner's COG height (m), which sets the pendulum frequency.
        gravity: (m/s^2).
        order: Fourier order per phase (the paper uses 3).
    """
    offset = angular_zmp_offset(check.angular_momentum_rate, robot.mass, gravity)
    correction = fit_correction(rollout.times, offset, rollout.phase_breaks(), omega(cog_height, gravity), order)
    cog_offset = correction.evaluate(rollout.times)[0]
    motion = whole_body_motion(robot, rollout, cog_offset=cog_offset)
    return Compensation(order, correction, cog_offset, motion, check_motion(motion, rollout))
