"""The ground-truth estimator: the walking state read off the simulator's truth, for comparison and ``--state truth``.

It is what a perfect estimator would give: the COM and its velocity as the simulator has them, and each foot's
wrench, centre of pressure, pose and load from the contact forces summed on it (:mod:`rtgait.estimation.feet`), with
landings detected by :mod:`rtgait.estimation.load`. The DCM is ``xi = c + c'/w`` with the planner's
``w = sqrt(g / z_c)``, so that it compares with the plan's.
"""

from __future__ import annotations

import math

from rtgait.estimation.feet import FeetFromWrenches
from rtgait.estimation.load import DEFAULT_LANDING_FRACTION, DEFAULT_MIN_UNLOADED_TIME, LoadHysteresis
from rtgait.estimation.state import Landing, Measurement
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth

__all__ = ["GroundTruthEstimator"]

_NO_LANDINGS: tuple[Landing, ...] = ()
_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class GroundTruthEstimator:
    """The walking state from the simulator's truth (module docstring).

    Args:
        omega: pendulum frequency ``w = sqrt(g / z_c)`` of the planner (1/s), for the DCM.
        weight: the robot's weight (N), for the default thresholds.
        landing_force: load at which a foot counts as loaded and, after flight, as landed (N); default
            :data:`~rtgait.estimation.load.DEFAULT_LANDING_FRACTION` of the weight.
        release_force: load below which a foot counts as unloaded (N); default half of ``landing_force``.
        min_unloaded_time: least flight time of a landing (s).
        min_force: least load (N) for which a CoP or a ZMP is given; default 0.1 % of the weight.
        ground_height: height of the ZMP's plane (m); ``None``: the soles' (:mod:`rtgait.estimation.feet`).
    """

    reads_truth = True

    def __init__(
        self,
        omega: float,
        weight: float,
        *,
        landing_force: float | None = None,
        release_force: float | None = None,
        min_unloaded_time: float = DEFAULT_MIN_UNLOADED_TIME,
        min_force: float | None = None,
        ground_height: float | None = None,
    ) -> None:
        if not (math.isfinite(omega) and omega > 0.0):
            raise ValueError(f"omega must be > 0 (1/s), got {omega}")
        if not (math.isfinite(weight) and weight > 0.0):
            raise ValueError(f"the robot's weight must be > 0 N, got {weight}")
        self.omega, self.weight = float(omega), float(weight)
        landing = DEFAULT_LANDING_FRACTION * weight if landing_force is None else float(landing_force)
        release = 0.5 * landing if release_force is None else float(release_force)
        self.load = LoadHysteresis(landing, release, min_unloaded_time)
        self.min_force = 1e-3 * weight if min_force is None else float(min_force)
        self.feet = FeetFromWrenches(self.load, self.min_force, ground_height)

    def reset(self) -> None:
        """Forget the feet's load states: the next update takes them as they are, without landings."""
        self.load.reset()

    def update(self, readings: SensorReadings | None, truth: GroundTruth | None) -> Measurement:
        """The walking state of ``truth`` (``readings`` are not read)."""
        if truth is None:
            raise ValueError("the ground-truth estimator needs the simulator's ground truth, got None")
        t, left, right = truth.t, truth.left, truth.right
        feet = self.feet
        (lx, ly, lz), (lmx, lmy, lmz) = left.force, left.moment
        (rx, ry, rz), (rmx, rmy, rmz) = right.force, right.moment
        left_foot, left_landing = feet.foot(
            0, t, lx, ly, lz, lmx, lmy, lmz, left.contacts, left.sole_position, left.sole_rotation
        )
        right_foot, right_landing = feet.foot(
            1, t, rx, ry, rz, rmx, rmy, rmz, right.contacts, right.sole_position, right.sole_rotation
        )
        landings = _NO_LANDINGS
        if left_landing is not None or right_landing is not None:
            landings = tuple(landing for landing in (left_landing, right_landing) if landing is not None)
        self.load.prime()
        zmp, total = feet.zmp(left_foot, right_foot)
        (cx, cy, cz), (vx, vy, vz) = truth.com, truth.com_vel
        w = self.omega
        return _new_tuple(
            Measurement,
            (t, (cx, cy, cz), (vx, vy, vz), (cx + vx / w, cy + vy / w), zmp, total, left_foot, right_foot, landings,
             truth.other_contacts),
        )  # fmt: skip
