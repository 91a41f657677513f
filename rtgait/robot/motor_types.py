"""Motor types of a robot description (``[actuation.motors.<name>]``): what a joint's drive can give at each speed,
and the friction of its gears, seen at the joint.

The torque-speed envelope of a voltage-limited brushless drive, at joint speed ``w = |dq|`` (rad/s):

* torque **along** the motion (driving): the peak torque ``T_peak`` up to the corner speed ``w_c``, then falling
  linearly to zero at the no-load speed ``w_0``::

      T_drive(w) = T_peak min(1, max(0, (w_0 - w) / (w_0 - w_c)))                                    (N m)

  (``w_c = 0``: falling from standstill on, the envelope of a datasheet that gives only the stall torque and the
  no-load speed);
* torque **against** the motion (braking): ``T_brake``, whatever the speed: the back-EMF then adds to the supply
  voltage instead of opposing it, so only the current limit bounds the torque (Unitree's bench gives a larger
  braking than driving peak: ``Y2 > Y1``).

Friction in the gears and bearings, opposing the joint's motion: Coulomb ``F_c sign(dq)`` (N m), and viscous
``b dq`` (``b`` in N m s/rad); at standstill the Coulomb part holds up to ``F_c``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MOTOR_KEYS", "MotorType"]

MOTOR_KEYS = ("peak_torque", "no_load_speed", "corner_speed", "braking_torque", "coulomb_friction", "viscous_friction")
"""The keys of an ``[actuation.motors.<name>]`` table."""


@dataclass(frozen=True)
class MotorType:
    """One motor type, at the joint (after its gears): the module docstring's envelope and friction.

    Attributes:
        name: the type's name in the description (e.g. Unitree's ``"N7520-22.5"``).
        peak_torque: ``T_peak``, the most torque along the motion (N m).
        no_load_speed: ``w_0``, the speed at which the driving torque has fallen to zero (rad/s).
        corner_speed: ``w_c``, up to which the full peak torque drives (rad/s), below ``no_load_speed``.
        braking_torque: ``T_brake``, the most torque against the motion (N m); ``None``: ``peak_torque``.
        coulomb_friction: ``F_c`` (N m).
        viscous_friction: ``b`` (N m s/rad).
    """

    name: str
    peak_torque: float
    no_load_speed: float
    corner_speed: float = 0.0
    braking_torque: float | None = None
    coulomb_friction: float = 0.0
    viscous_friction: float = 0.0

    def __post_init__(self) -> None:
        where = f"motor type {self.name!r}"
        for key in ("peak_torque", "no_load_speed", "corner_speed", "coulomb_friction", "viscous_friction"):
            value = getattr(self, key)
            positive = key in ("peak_torque", "no_load_speed")
            if not (_finite(value) and (value > 0 if positive else value >= 0)):
                rule = "> 0" if positive else ">= 0"
                raise ValueError(f"{where}: {key} must be a finite number {rule}, got {value!r}")
        if self.corner_speed >= self.no_load_speed:
            raise ValueError(
                f"{where}: corner_speed ({self.corner_speed:g} rad/s) must be below no_load_speed "
                f"({self.no_load_speed:g} rad/s)"
            )
        brake = self.braking_torque
        if brake is not None and not (_finite(brake) and brake > 0):
            raise ValueError(f"{where}: braking_torque must be a finite number > 0, got {brake!r}")

    @property
    def braking(self) -> float:
        """``T_brake`` (N m)."""
        return self.peak_torque if self.braking_torque is None else self.braking_torque

    def driving_torque(self, speed: float | np.ndarray) -> float | np.ndarray:
        """``T_drive`` at joint speed ``speed`` (rad/s; its sign is ignored), in N m."""
        fraction = (self.no_load_speed - np.abs(speed)) / (self.no_load_speed - self.corner_speed)
        return self.peak_torque * np.clip(fraction, 0.0, 1.0)

    def friction_torque(self, velocity: float) -> float:
        """The friction torque on a joint turning at ``velocity`` (rad/s), opposing it (N m); 0 at standstill (where
        the Coulomb part holds whatever below ``F_c`` is applied)."""
        return -(self.coulomb_friction * float(np.sign(velocity)) + self.viscous_friction * velocity)


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
