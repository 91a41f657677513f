"""What the online planner hands a controller every tick, and its record of each replanning.

A sample is read by name in both of its forms:

* :class:`SampleValues`: the 23 floats of one instant as a named tuple, what
  :meth:`~rtgait.core.planner.online.OnlinePlanner.sample_values` returns every control tick: made in one step from
  the values, read by field (``values.dcm_x``) through a C-level item getter, and still a tuple for code that
  unpacks it or makes an array of it;
* :class:`GaitSample`: the same values as a numpy vector with the time, support and phase, what
  :meth:`~rtgait.core.planner.online.OnlinePlanner.sample` returns; its properties give each quantity as an array.

Tables of samples (one row per tick, :data:`SAMPLE_FIELDS` order: rollouts, run outputs) read a quantity's columns
through :class:`SampleColumns`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class SampleValues(NamedTuple):
    """The planner's sample at one instant, as plain floats (SI units, yaw in rad).

    The COG's height is ``zc`` on level ground (its vertical velocity and acceleration zero); off the flat floor it
    follows the footholds' heights (the 3D-DCM/VRP form, ``docs/method.md``) and the feet's ``z`` are the footholds'
    heights and the swing's. The reference
    ZMP is the one the footsteps alone ask for; it differs from the planned ZMP in a connecting segment. The DCM
    (capture point) is ``xi = c + c'/w``, horizontal.
    """

    cog_x: float
    cog_y: float
    cog_z: float
    cog_vx: float
    cog_vy: float
    cog_vz: float
    cog_ax: float
    cog_ay: float
    cog_az: float
    zmp_x: float
    zmp_y: float
    zmp_ref_x: float
    zmp_ref_y: float
    lfoot_x: float
    lfoot_y: float
    lfoot_z: float
    lfoot_yaw: float
    rfoot_x: float
    rfoot_y: float
    rfoot_z: float
    rfoot_yaw: float
    dcm_x: float
    dcm_y: float

    @property
    def cog(self) -> tuple[float, float, float]:
        """COG position (m)."""
        return (self.cog_x, self.cog_y, self.cog_z)

    @property
    def left_foot(self) -> tuple[float, float, float, float]:
        """Left foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return (self.lfoot_x, self.lfoot_y, self.lfoot_z, self.lfoot_yaw)

    @property
    def right_foot(self) -> tuple[float, float, float, float]:
        """Right foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return (self.rfoot_x, self.rfoot_y, self.rfoot_z, self.rfoot_yaw)


SAMPLE_FIELDS: tuple[str, ...] = SampleValues._fields
"""The names of a sample's values, in the order of :attr:`GaitSample.values` and of a table's columns."""


def _columns(first: str, last: str) -> slice:
    """The columns of the fields ``first`` to ``last`` (inclusive) in a row of :data:`SAMPLE_FIELDS` order."""
    return slice(SAMPLE_FIELDS.index(first), SAMPLE_FIELDS.index(last) + 1)


class SampleColumns:
    """Where each quantity of a sample sits in a row of :data:`SAMPLE_FIELDS` order (slices), for code that holds
    samples as a float table: ``rollout.values[:, SampleColumns.left_foot]`` is the left foot's ``(x, y, z, yaw)``
    at every tick. A single value's column is ``SAMPLE_FIELDS.index(name)``."""

    cog = _columns("cog_x", "cog_z")
    cog_vel = _columns("cog_vx", "cog_vz")
    cog_acc = _columns("cog_ax", "cog_az")
    zmp = _columns("zmp_x", "zmp_y")
    zmp_reference = _columns("zmp_ref_x", "zmp_ref_y")
    left_foot = _columns("lfoot_x", "lfoot_yaw")
    right_foot = _columns("rfoot_x", "rfoot_yaw")
    dcm = _columns("dcm_x", "dcm_y")


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
        return self.values[SampleColumns.cog]

    @property
    def cog_vel(self) -> np.ndarray:
        """COG velocity (m/s)."""
        return self.values[SampleColumns.cog_vel]

    @property
    def cog_acc(self) -> np.ndarray:
        """COG acceleration (m/s^2)."""
        return self.values[SampleColumns.cog_acc]

    @property
    def zmp(self) -> np.ndarray:
        """Planned ZMP on the ground (m)."""
        return self.values[SampleColumns.zmp]

    @property
    def zmp_reference(self) -> np.ndarray:
        """ZMP the footsteps alone would ask for (m); differs from :attr:`zmp` in a connecting segment."""
        return self.values[SampleColumns.zmp_reference]

    @property
    def left_foot(self) -> np.ndarray:
        """Left foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[SampleColumns.left_foot]

    @property
    def right_foot(self) -> np.ndarray:
        """Right foot pose ``(x, y, z, yaw)`` (m, rad)."""
        return self.values[SampleColumns.right_foot]

    @property
    def dcm(self) -> np.ndarray:
        """Divergent component of motion (capture point) ``xi = c + c'/w`` of the plan, horizontal (m)."""
        return self.values[SampleColumns.dcm]

    # The centre of mass under the name most libraries use (placo, Pinocchio, mc_rtc): the same values.
    com = cog
    com_vel = cog_vel
    com_acc = cog_acc

    def left_foot_transform(self) -> np.ndarray:
        """Left foot pose as a 4x4 homogeneous transform (world from foot; m), as placo and Pinocchio give poses."""
        return foot_transform(self.left_foot)

    def right_foot_transform(self) -> np.ndarray:
        """Right foot pose as a 4x4 homogeneous transform (world from foot; m)."""
        return foot_transform(self.right_foot)


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
