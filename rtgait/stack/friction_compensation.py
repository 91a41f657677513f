"""Compensation of the joints' friction in the feed-forward torques, from the motor types of the robot description
(:mod:`rtgait.robot.motor_types`): what a drive that knows its gears' friction only roughly adds to its torque.

Per joint, at the reference's joint velocity ``dq_ref`` (rad/s)::

    tau_f = alpha (F_c tanh(dq_ref / v_s) + b dq_ref)                                                  (N m)

with ``F_c`` and ``b`` the description's Coulomb (N m) and viscous (N m s/rad) friction of the joint's motor type.

**Why all of it** (``alpha`` = :data:`IDENTIFIED_FRACTION` = 1): the robot's friction differs from the bench's
(friction in planetary and harmonic gears falls as they warm up and grows with the load they carry, by some tens of
per cent), so the compensation is sometimes more than there is. On the reference's velocity that surplus is a torque
along the reference's motion, which the drive's own PD takes up (a joint ahead of its reference by ``(alpha F_c -
F) / k_p``); it does not feed the joint's own velocity back, so it cannot act as negative damping, as a compensation on
the measured velocity would. Compensating less leaves a dead band: on G1 with the motor model, the true friction drawn
within +-30 % of the identified one (``--model-error 0``), fig8 falls at 6.5 s with ``alpha = 0.7`` and walks with
``alpha = 1`` (``docs/robots.md``, "G1 at its own gains with the motor model").

**Why the reference's velocity**, not the measured one: the command's (:mod:`rtgait.stack.feedforward`: the IK's
motion with the feet's tilts at the ankles, which the drives are told to follow) is smooth and known ahead,
so the compensation neither amplifies the encoders' noise nor switches sign at every small vibration; at
standstill it is zero, and the stiction that then holds the joint only helps. The sign is smoothed over
:data:`STICTION_SPEED` (``v_s``): ten to a hundred times below the joints' speeds in a gait (0.5 to 5 rad/s), so a
moving joint gets the full compensation and a reference hovering around zero none.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from rtgait.estimation.joint_friction import JointFriction, checked_friction

if TYPE_CHECKING:
    from rtgait.robot.model import RobotModel

__all__ = ["IDENTIFIED_FRACTION", "STICTION_SPEED", "FrictionCompensation", "identified_friction"]

IDENTIFIED_FRACTION = 1.0
"""``alpha``: the share of the identified friction compensated (module docstring)."""

STICTION_SPEED = 0.05
"""``v_s`` (rad/s): the speed over which the Coulomb part's sign is smoothed (module docstring)."""


class FrictionCompensation:
    """The module docstring's ``tau_f`` per joint.

    Args:
        coulomb: ``F_c`` per joint (N m), ``>= 0``.
        viscous: ``b`` per joint (N m s/rad), ``>= 0``.
        fraction: ``alpha``, in ``[0, 1]``.
        speed: ``v_s`` (rad/s), ``> 0``.
    """

    def __init__(
        self,
        coulomb: np.ndarray,
        viscous: np.ndarray,
        fraction: float = IDENTIFIED_FRACTION,
        speed: float = STICTION_SPEED,
    ) -> None:
        coulomb, viscous = checked_friction(coulomb, viscous, speed)
        if not (math.isfinite(fraction) and 0.0 <= fraction <= 1.0):
            raise ValueError(f"the compensated fraction must be in [0, 1], got {fraction}")
        self.coulomb = fraction * coulomb
        """``alpha F_c`` per joint (N m)."""
        self.viscous = fraction * viscous
        """``alpha b`` per joint (N m s/rad)."""
        self._per_speed = 1.0 / speed

    @classmethod
    def of(cls, robot: RobotModel, fraction: float = IDENTIFIED_FRACTION) -> FrictionCompensation:
        """The compensation of ``robot``'s joints (``robot.joint_names`` order) from its description's motor types;
        a joint without a motor type gets none."""
        friction = identified_friction(robot)
        return cls(friction.coulomb, friction.viscous, fraction)

    def torques(self, velocity: np.ndarray) -> np.ndarray:
        """``tau_f`` (N m, a new array) at the joints' reference velocities ``velocity`` (rad/s)."""
        torque = np.tanh(velocity * self._per_speed)
        torque *= self.coulomb
        torque += self.viscous * velocity
        return torque


def identified_friction(robot: RobotModel) -> JointFriction:
    """The friction of ``robot``'s joints (``robot.joint_names`` order) as its description's motor types identify
    it (:mod:`rtgait.estimation.joint_friction`); a joint without a motor type has none."""
    coulomb, viscous = [], []
    for name in robot.joint_names:
        motor = robot.description.joint_actuation(name).motor
        coulomb.append(0.0 if motor is None else motor.coulomb_friction)
        viscous.append(0.0 if motor is None else motor.viscous_friction)
    return JointFriction(np.array(coulomb), np.array(viscous))
