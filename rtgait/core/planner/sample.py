"""What the online planner hands a controller every tick, and its record of each replanning."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

SAMPLE_FIELDS = (
    "cog_x", "cog_y", "cog_z", "cog_vx", "cog_vy", "cog_vz", "cog_ax", "cog_ay", "cog_az",
    "zmp_x", "zmp_y", "zmp_ref_x", "zmp_ref_y",
    "lfoot_x", "lfoot_y", "lfoot_z", "lfoot_yaw", "rfoot_x", "rfoot_y", "rfoot_z", "rfoot_yaw",
    "dcm_x", "dcm_y",
)  # fmt: skip
"""Order of the values in :attr:`GaitSample.values` (SI units, yaw in rad)."""


class GaitSample(NamedTuple):
    """Everything a controller needs at one instant. ``values`` is ordered as :data:`SAMPLE_FIELDS`.

    ``support`` is ``"double"``, ``"left"`` or ``"right"`` (the foot on the ground); ``phase`` the phase index.
    An immutable tuple rather than a dataclass: one is made every control tick, and a tuple is made fastest.
    """

    t: float
    values: np.ndarray
    support: str
    phase: int

    @property
    def cog(self) -> np.ndarray:
        """COG position (m)."""
        return self.values[0:3]

    @property
    def cog_vel(self) -> np.ndarray:
        """COG velocity (m/s)."""
        return self.values[3:6]

    @property
    def cog_acc(self) -> np.ndarray:
        """COG acceleration (m/s^2)."""
        return self.values[6:9]

    @property
    def zmp(self) -> np.ndarray:
        """Planned ZMP on the ground (m)."""
        return self.values[9:11]

    @property
    def zmp_reference(self) -> np.ndarray:
        """ZMP the footsteps alone would ask for (m); differs from :attr:`zmp` in a connecting segment."""
        return self.values[11:13]

    @property
    def left_foot(self) -> np.ndarray:
        """Left foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[13:17]

    @property
    def right_foot(self) -> np.ndarray:
        """Right foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[17:21]

    @property
    def dcm(self) -> np.ndarray:
        """Divergent component of motion (capture point) ``xi = c + c'/w`` of the plan, horizontal (m)."""
        return self.values[21:23]

    # The centre of mass under the name most libraries use (placo, Pinocchio, mc_rtc): the same values.
    com = cog
    com_vel = cog_vel
    com_acc = cog_acc

    def left_foot_transform(self) -> np.ndarray:
        """Left foot pose as a 4x4 homogeneous transform (world from foot; m), as placo and Pinocchio give poses."""
        return foot_transform(self.values[13:17])

    def right_foot_transform(self) -> np.ndarray:
        """Right foot pose as a 4x4 homogeneous transform (world from foot; m)."""
        return foot_transform(self.values[17:21])


def foot_transform(pose: np.ndarray) -> np.ndarray:
    """4x4 homogeneous transform of a foot pose ``(x, y, z, yaw)`` (m, rad): rotation about z, then translation."""
    x, y, z, yaw = (float(v) for v in pose)
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]])


class PlanRecord(NamedTuple):
    """One replanning.

    Attributes:
        t: when the plan starts (s).
        phase: the phase its first segment belongs to.
        first_segment_end: when its free first segment ends (s).
        n_segments: segments in the plan.
        compute_time: wall time the replan took (s).
        reason: why it was made: ``"start"``, ``"double-support"`` (the paper's replanning), ``"request"``
            (:meth:`~rtgait.core.planner.online.OnlinePlanner.replan_now`), ``"dcm-error"`` or ``"touchdown"``.
    """

    t: float
    phase: int
    first_segment_end: float
    n_segments: int
    compute_time: float
    reason: str = "double-support"
