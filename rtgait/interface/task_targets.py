"""What the walking controller asks of the joints each tick: the whole-body IK's task targets and the feet's tilts.

The controller (:mod:`rtgait.control`) writes them, the whole-body IK (:mod:`rtgait.robot.ik`) and the joint command
(:mod:`rtgait.robot.ankles`) read them; both sides import them from here, so neither imports the other.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

__all__ = ["FootOffsets", "IKTargets"]


class IKTargets(NamedTuple):
    """What the robot must do at one tick (world frame).

    Attributes:
        cog: COG position ``(x, y, z)`` (m).
        left_foot: left sole point ``(x, y, z, yaw)`` (m, rad); the sole is level. ``(x, y, z, yaw, pitch, roll)``:
            the sole tilted to a sloped foothold, ``Rz(yaw) Ry(pitch) Rx(roll)``
            (:mod:`rtgait.core.geometry.foot_tilt`).
        right_foot: right sole point, likewise.
        lean: the upper body's lean, a rotation vector (rad, world frame) applied to the upright torso and pelvis
            targets (the hip strategy, :mod:`rtgait.core.laws.hip_strategy`); ``None``: upright.
    """

    cog: np.ndarray | Sequence[float]
    left_foot: np.ndarray | Sequence[float]
    right_foot: np.ndarray | Sequence[float]
    lean: Sequence[float] | None = None


class FootOffsets(NamedTuple):
    """What foot force control adds to the feet targets: roll and pitch about the sole frame's x and y axes (rad),
    height (m)."""

    left_roll: float = 0.0
    left_pitch: float = 0.0
    left_height: float = 0.0
    right_roll: float = 0.0
    right_pitch: float = 0.0
    right_height: float = 0.0
