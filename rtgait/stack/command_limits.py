"""The joint limits applied to every joint command, with a count of the ticks each joint was clipped at.

For each joint ``i`` with the limits of :class:`~rtgait.interface.joint_limits.JointLimits`:

    q_ref   in [lower_i + m, upper_i - m]         (rad; m: :data:`POSITION_MARGIN`, the range's middle if narrower)
    dq_ref  in [-velocity_i, velocity_i]          (rad/s)
    tau_ff  in [-torque_i, torque_i]              (N m)

The margin keeps the reference off the joint's mechanical stop, which a servo's tracking error would otherwise
drive it into. A value within its limits passes unchanged (the same array, no copy): clipping only changes what is
out of range. Counting is by tick: a joint clipped at a tick adds 1 to its count of that quantity.
"""

from __future__ import annotations

from operator import gt as _gt
from operator import lt as _lt
from typing import NamedTuple

import numpy as np

from rtgait.interface.joint_limits import JointLimits

__all__ = ["POSITION_MARGIN", "ClipCounts", "CommandLimits"]

POSITION_MARGIN = 0.01
"""How far inside its URDF range a joint's position reference is kept (rad, 0.57 degree)."""


class ClipCounts(NamedTuple):
    """Ticks at which each joint's reference was clipped, per quantity (one count per joint, in joint order).

    Attributes:
        position: ``q_ref`` brought into the range.
        velocity: ``dq_ref`` brought within the speed limit.
        torque: the feed-forward torque brought within the torque limit.
    """

    position: np.ndarray
    velocity: np.ndarray
    torque: np.ndarray


class CommandLimits:
    """Clips joint references to ``limits`` (module docstring) and counts the clipped ticks.

    Args:
        limits: the joints' limits.
        margin: how far inside the position range the reference is kept (rad), ``>= 0``.

    Raises:
        ValueError: a negative or non-finite margin.
    """

    def __init__(self, limits: JointLimits, margin: float = POSITION_MARGIN) -> None:
        if not (np.isfinite(margin) and margin >= 0.0):
            raise ValueError(f"the position margin must be >= 0 rad, got {margin}")
        self.limits, self.margin = limits, float(margin)
        lower, upper = limits.lower + margin, limits.upper - margin
        narrow = lower > upper  # a range narrower than two margins: its middle
        middle = 0.5 * (limits.lower + limits.upper)
        self.lower, self.upper = np.where(narrow, middle, lower), np.where(narrow, middle, upper)
        self.velocity, self.torque = limits.velocity, limits.torque
        self._minus_velocity, self._minus_torque = -limits.velocity, -limits.torque
        # The bounds as Python floats, for the check of the common path (nothing out of range).
        self._position_bounds = (self.lower.tolist(), self.upper.tolist())
        self._velocity_bounds = (self._minus_velocity.tolist(), self.velocity.tolist())
        self._torque_bounds = (self._minus_torque.tolist(), self.torque.tolist())
        n = len(limits.names)
        self.counts = ClipCounts(np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64))
        self.torque_ticks = 0
        """Ticks at which some joint's torque was clipped (the ticks at which ``counts.torque`` grew)."""

    def reset(self) -> None:
        """Zero the counts."""
        for counts in self.counts:
            counts[:] = 0
        self.torque_ticks = 0

    def positions(self, q: np.ndarray) -> np.ndarray:
        """``q`` (rad) within the range less the margin: ``q`` itself when it is, else a clipped copy."""
        return _clip(q, self.lower, self.upper, self._position_bounds, self.counts.position)

    def velocities(self, dq: np.ndarray) -> np.ndarray:
        """``dq`` (rad/s) within the speed limits: ``dq`` itself when it is, else a clipped copy."""
        return _clip(dq, self._minus_velocity, self.velocity, self._velocity_bounds, self.counts.velocity)

    def torques(self, tau: np.ndarray | None) -> np.ndarray | None:
        """``tau`` (N m) within the torque limits (``None`` passes): ``tau`` itself when it is, else a clipped copy."""
        if tau is None:
            return None
        clipped = _clip(tau, self._minus_torque, self.torque, self._torque_bounds, self.counts.torque)
        if clipped is not tau:
            self.torque_ticks += 1
        return clipped

    def counted(self) -> dict[str, dict[str, int]]:
        """The clipped ticks by quantity and joint, the joints never clipped left out (for a run's summary)."""
        names = self.limits.names
        return {
            quantity: {names[i]: int(counts[i]) for i in np.flatnonzero(counts)}
            for quantity, counts in zip(ClipCounts._fields, self.counts, strict=True)
        }


def _clip(
    values: np.ndarray, low: np.ndarray, high: np.ndarray, bounds: tuple[list[float], list[float]], counts: np.ndarray
) -> np.ndarray:
    """``values`` within ``[low, high]`` (``bounds``: the same as Python floats), the clipped entries counted;
    ``values`` itself when nothing is out (checked on Python floats, without a copy: a scalar comparison per joint
    costs less than numpy's calls on a few dozen numbers, and each comparison mapped in C less than a loop's)."""
    lows, highs = bounds
    listed = values.tolist()
    if len(listed) != len(lows):
        raise ValueError(f"expected {len(lows)} joint values, got {len(listed)}")
    if not (any(map(_lt, listed, lows)) or any(map(_gt, listed, highs))):
        return values
    below, above = values < low, values > high
    counts += below | above
    return np.minimum(np.maximum(values, low), high)
