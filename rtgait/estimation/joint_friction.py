"""The identified friction of a robot's joints at their measured velocities: what separates a motor's torque (read
from its current, G1's ``tau_est``) from the torque its gears pass on to the link.

Per joint, at the encoder's velocity ``dq`` (rad/s)::

    tau_f = F_c tanh(dq / v_s) + b dq                                                                    (N m)

``F_c`` the Coulomb and ``b`` the viscous friction (N m, N m s/rad) of the joint's motor type, as a bench
identification gives them. The sign of the Coulomb part is smoothed over :data:`MEASURED_STICTION_SPEED`: five times
the encoders' velocity noise on G1 (0.02 rad/s at 500 Hz), so that a joint at rest, whose stiction takes any value
within ``+-F_c`` and which the sign of a noisy velocity cannot tell, is given a small share of ``F_c`` at random rather
than all of it, and a joint moving at a gait's speed (0.5 to 5 rad/s) all of it.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MEASURED_STICTION_SPEED", "JointFriction", "checked_friction"]

MEASURED_STICTION_SPEED = 0.1
"""``v_s`` (rad/s): the speed over which the Coulomb part's sign is smoothed (module docstring)."""


class JointFriction:
    """The module docstring's ``tau_f`` per joint.

    Args:
        coulomb: ``F_c`` per joint (N m), ``>= 0``.
        viscous: ``b`` per joint (N m s/rad), ``>= 0``.
        speed: ``v_s`` (rad/s), ``> 0``.

    Raises:
        ValueError: arrays of different shapes or not 1-D, negative or non-finite values, a speed not > 0.
    """

    def __init__(self, coulomb: np.ndarray, viscous: np.ndarray, speed: float = MEASURED_STICTION_SPEED) -> None:
        coulomb, viscous = checked_friction(coulomb, viscous, speed)
        self.coulomb, self.viscous, self.speed = coulomb, viscous, float(speed)

    def torques(self, velocity: np.ndarray) -> np.ndarray:
        """``tau_f`` (N m, a new array) at the joints' velocities ``velocity`` (rad/s)."""
        torque = np.tanh(np.asarray(velocity, dtype=float) / self.speed)
        torque *= self.coulomb
        torque += self.viscous * velocity
        return torque


def checked_friction(coulomb: np.ndarray, viscous: np.ndarray, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """``coulomb`` (N m) and ``viscous`` (N m s/rad) friction per joint as new float arrays, checked with the stiction
    ``speed`` (rad/s).

    Raises:
        ValueError: arrays of different shapes or not 1-D, negative or non-finite values, a speed not > 0.
    """
    coulomb, viscous = np.array(coulomb, dtype=float), np.array(viscous, dtype=float)
    if coulomb.shape != viscous.shape or coulomb.ndim != 1:
        raise ValueError(f"coulomb and viscous friction must be two arrays of one shape, got {coulomb.shape} "
                         f"and {viscous.shape}")  # fmt: skip
    for name, values in (("coulomb", coulomb), ("viscous", viscous)):
        if not (np.isfinite(values).all() and (values >= 0.0).all()):
            raise ValueError(f"{name} friction must be finite and >= 0, got {values!r}")
    if not (math.isfinite(speed) and speed > 0.0):
        raise ValueError(f"the stiction speed must be > 0 rad/s, got {speed}")
    return coulomb, viscous
