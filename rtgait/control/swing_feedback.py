"""Swing-foot placement feedback: the swing foot's measured position steered onto its target, the translation
counterpart of :mod:`rtgait.control.sole_level`'s eq. (2).

The IK computes its joint references as if the joints reached them. On soft drives they do not: G1's stance hip (kp
60 N m/rad) gives a few degrees under the trunk's weight when the model's masses are off, and the whole body above
it, the swinging leg with it, turns about the stance foot by that much; the swing foot then hangs 1-4 cm off its
target at the end of its swing although its own joints track theirs. The estimate sees it: the swing sole's
position is the stance sole's composed with the encoders' kinematics and the IMU's attitude, so the stance joints'
deflection is in it. Each foot in the air gets an offset ``u`` (world frame, m) added to its IK target:

    u' = (p_target - p_measured) / T_w,        |u_k| <= u_max   (each axis k)                     (1)

``p_target`` the foot's target before the offset, ``p_measured`` the estimate's sole position, ``T_w`` the
``time_constant`` (s). It is an integral action on the placement error: at rest ``p_measured = p_target``, whatever
static deflection the stance leg has. While the foot carries load (a support foot, or a swing foot that touched
down) ``u`` decays to zero over ``T_r`` (``return_time``); a foot in the air without an estimate (NaN) holds its offset:

    u' = -u / T_r                                                                                 (2)

so that a standing foot's target returns to the plan's; the offset a landing leaves is the deflection the foot is
lifted with again at its next swing, where eq. (1) learns it anew.

Only the robot's own senses enter (IMU attitude and encoders, through the estimate). The estimate's noise reaches
``u`` through a low-pass of time constant ``T_w``: G1's IMU (8.7 mrad) over a 0.6 m leg, 5 mm per tick, is some 0.8
mm in ``u`` at ``T_w`` = 50 ms and a 2 ms control period (``sigma sqrt(dt / 2 T_w)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtgait.estimation.state import FootState

__all__ = ["SwingFeedback", "SwingFeedbackSettings"]

Pose = tuple[float, float, float, float]


@dataclass(frozen=True)
class SwingFeedbackSettings:
    """Settings of :class:`SwingFeedback` (module docstring).

    Attributes:
        time_constant: ``T_w`` of eq. (1) (s), in (0, 1e4].
        max_offset: ``u_max``, the largest offset on each axis (m), in [0, 0.1].
        return_time: ``T_r`` of eq. (2) (s), in (0, 1e4].
    """

    time_constant: float = 0.05
    max_offset: float = 0.03
    return_time: float = 0.5

    def __post_init__(self) -> None:
        ranges = {"time_constant": (0.0, 1e4), "max_offset": (0.0, 0.1), "return_time": (0.0, 1e4)}
        for field in fields(self):
            low, high = ranges[field.name]
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
            low_ok = number and (value >= low if field.name == "max_offset" else value > low)
            if not (low_ok and value <= high):
                raise ValueError(f"SwingFeedbackSettings.{field.name} must be within [{low:g}, {high:g}], "
                                 f"got {value!r}")  # fmt: skip
            object.__setattr__(self, field.name, float(value))


class SwingFeedback:
    """The offsets of both feet's targets (eqs. (1), (2)); :meth:`update` each tick.

    Args:
        dt: the control period (s).
        settings: :class:`SwingFeedbackSettings`.
    """

    def __init__(self, dt: float, settings: SwingFeedbackSettings | None = None) -> None:
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        self.settings = s = settings or SwingFeedbackSettings()
        self._gain = -math.expm1(-dt / s.time_constant)
        self._decay = math.exp(-dt / s.return_time)
        self.reset()

    def reset(self) -> None:
        """Zero the offsets."""
        self._offsets = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]  # left, right: x, y, z (m)

    @property
    def offsets(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """The ``(left, right)`` offsets ``(x, y, z)`` (m) of the last :meth:`update`."""
        left, right = self._offsets
        return (left[0], left[1], left[2]), (right[0], right[1], right[2])

    def update(self, left: Pose, right: Pose, measured: tuple[FootState, FootState], support: str) -> tuple[Pose, Pose]:
        """One tick: the feet's targets ``(x, y, z, yaw)`` (m, rad) with their offsets. ``measured``: the estimate's
        left and right feet; ``support``: the support the controller acts on (``"double"``, ``"left"``,
        ``"right"``); a foot it does not count on and that carries no load is in the air."""
        out = []
        limit = self.settings.max_offset
        for offset, target, foot, side in zip(self._offsets, (left, right), measured, ("left", "right"), strict=True):
            x, y, z, _ = foot.pose
            in_air = support not in ("double", side) and not foot.loaded
            if in_air:
                if math.isfinite(x + y + z):  # else (no estimate of the foot) the offset holds
                    for k, value in enumerate((x, y, z)):
                        u = offset[k] + self._gain * (target[k] - value)
                        offset[k] = -limit if u < -limit else (limit if u > limit else u)
            else:
                for k in range(3):
                    offset[k] *= self._decay
            out.append((target[0] + offset[0], target[1] + offset[1], target[2] + offset[2], target[3]))
        return out[0], out[1]
