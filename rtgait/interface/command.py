"""What a controller writes to a robot's joints at one control tick.

One entry per joint, in the robot's joint order, as a real robot's drive takes it (Unitree's ``LowCmd``, a
ros2_control joint with position, velocity and effort command interfaces): the drive applies

    tau = tau_ff + kp (q_ref - q) + kd (dq_ref - dq)                                   (N m)

with the measured ``q``, ``dq``. Gains left ``None`` mean the drive's own (those the robot description's
``[actuation]`` table gives the simulated drives); a feed-forward torque left ``None`` means none.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["GAIN_SETS", "JointCommand"]

GAIN_SETS = ("stiff", "robot")
"""The drives' own gain sets, those a command without gains gets: ``"stiff"``, servos derived stiff enough to follow
any reference (a simulation's), or ``"robot"``, the gains the real robot's drives run (its description's
``[actuation]`` table).
"""


class JointCommand(NamedTuple):
    """The joints' references for one control period (module docstring).

    Attributes:
        positions: position references ``q_ref`` (rad), shape ``(n,)``.
        velocities: velocity references ``dq_ref`` (rad/s), shape ``(n,)``.
        torques: feed-forward torques ``tau_ff`` (N m), shape ``(n,)``; ``None``: none.
        kp: position gains (N m/rad), shape ``(n,)``; ``None``: the drive's own.
        kd: velocity gains (N m s/rad), shape ``(n,)``; ``None``: the drive's own.
    """

    positions: np.ndarray
    velocities: np.ndarray
    torques: np.ndarray | None = None
    kp: np.ndarray | None = None
    kd: np.ndarray | None = None
