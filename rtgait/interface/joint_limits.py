"""What the joints of a robot may do: position range, velocity and torque limits, one entry per joint.

Plain values in the robot's joint order (the order of :class:`~rtgait.interface.command.JointCommand`'s arrays), filled
from a robot model by :func:`rtgait.robot.joint_limits.joint_limits` (the URDF's ``<limit>``, the description's
torque limits) or by hand for a robot rtgait has no model of. A limit that is not known is ``inf`` (``-inf`` for a
lower position limit). SI units: rad, rad/s, N m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["JointLimits"]


@dataclass(frozen=True, eq=False)
class JointLimits:
    """The limits of each joint (module docstring).

    Attributes:
        names: the joints, in the order of every array below.
        lower, upper: the position range (rad), ``lower <= upper``.
        velocity: the speed limit (rad/s), ``> 0``; ``inf``: none.
        torque: the torque limit (N m), ``> 0``; ``inf``: none.

    Raises:
        ValueError: an array without one value per joint, NaN, a range with ``lower > upper``, or a velocity or
            torque limit that is not ``> 0``.
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    torque: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.names)
        for name in ("lower", "upper", "velocity", "torque"):
            values = np.array(getattr(self, name), dtype=float)
            if values.shape != (n,):
                raise ValueError(f"JointLimits.{name} must have one value per joint ({n}), got shape {values.shape}")
            if np.isnan(values).any():
                raise ValueError(f"JointLimits.{name} must not be NaN (inf: no limit)")
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        bad = np.flatnonzero(self.lower > self.upper)
        if bad.size:
            i = int(bad[0])
            raise ValueError(f"joint {self.names[i]}: lower limit {self.lower[i]} rad is above upper {self.upper[i]}")
        for name in ("velocity", "torque"):
            bad = np.flatnonzero(getattr(self, name) <= 0.0)
            if bad.size:
                raise ValueError(f"joint {self.names[int(bad[0])]}: the {name} limit must be > 0 (inf: none)")

    @classmethod
    def unlimited(cls, names: Sequence[str]) -> JointLimits:
        """No limit on any of ``names``."""
        n = len(names)
        return cls(tuple(names), np.full(n, -np.inf), np.full(n, np.inf), np.full(n, np.inf), np.full(n, np.inf))
