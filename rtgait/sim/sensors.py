"""The simulated robot's sensor readings, as its real sensors report them.

MuJoCo's sensors (:mod:`rtgait.sim.sensor_sites`) give the true values, all of one state: read after ``mj_step``,
the state that step started from (one physics step before ``data.time``), the same state as the simulator's truth
(:mod:`rtgait.sim.ground_truth`); read after ``mj_forward``, the state now.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rtgait.interface.readings import ImuReading, SensorReadings, Wrench

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["SensorModel"]

_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


class SensorModel:
    """The readings of a simulated robot's sensors (module docstring).

    Args:
        sim: the simulated robot's model (its :attr:`~rtgait.sim.model.SimModel.sensors` layout).
    """

    def __init__(self, sim: SimModel) -> None:
        layout = sim.sensors
        if layout is None:  # pragma: no cover - build_sim_model always lays them out
            raise ValueError("the simulated robot's model has no sensors")
        self.layout = layout
        self.joint_torques = sim.robot.description.sensors.joint_torques

    def read(self, sensordata: np.ndarray, t: float) -> SensorReadings:
        """The readings stamped ``t`` (s) from MuJoCo's ``sensordata``."""
        layout = self.layout
        values = sensordata[layout.start : layout.stop].copy()
        n = layout.joints
        imu = left = right = None
        k = 3 * n
        if layout.imu:
            q, gyro, accel = values[k : k + 4].tolist(), values[k + 4 : k + 7].tolist(), values[k + 7 : k + 10].tolist()
            imu = _new_tuple(ImuReading, (tuple(q), tuple(gyro), tuple(accel)))
            k += 10
        if layout.feet:
            # MuJoCo's sign: the wrench on the foot from the leg; the reading's: on the leg from the foot.
            w = (-values[k : k + 12]).tolist()
            left = _new_tuple(Wrench, (tuple(w[0:3]), tuple(w[3:6])))
            right = _new_tuple(Wrench, (tuple(w[6:9]), tuple(w[9:12])))
        torques = values[2 * n : 3 * n] if self.joint_torques else None
        return _new_tuple(SensorReadings, (t, values[:n], values[n : 2 * n], torques, imu, left, right))
