"""The simulated robot behind :class:`~rtgait.interface.robot.RobotInterface`: MuJoCo's state read as the robot's
encoders and drives report it, joint commands written to its position-controlled drives, and the simulator's truth
on its own channel (:class:`~rtgait.interface.robot.GroundTruthSource`).

The drives are MuJoCo position actuators with the gains of the robot description's ``[actuation]``
(:mod:`rtgait.sim.actuation`): a command's ``q_ref`` and ``dq_ref`` are interpolated linearly over the control
period's physics substeps. What it does not simulate yet is refused, not ignored: gains other than the drives' own,
feed-forward torques. The readings are those of the robot description's ``[sensors]`` (:mod:`rtgait.sim.sensors`):
encoders, joint torques, the IMU and the feet's force sensors where the robot has them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.command import JointCommand
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth
from rtgait.sim.actuation import ReferenceInterpolator
from rtgait.sim.contact_reading import ContactSums
from rtgait.sim.ground_truth import GroundTruthReader
from rtgait.sim.sensors import SensorModel
from rtgait.sim.step_snapshot import StepSnapshot, read_snapshot

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["SimRobot"]


class SimRobot:
    """A robot in MuJoCo physics (module docstring).

    Args:
        sim: the simulated robot's model.
        data: its MuJoCo state.
        joints: the joint positions the drives hold at the start (rad), in :attr:`joint_names` order.

    Attributes:
        joint_names: the moving joints, the order of every per-joint array read or written.
        sensors: the sensors' noise, biases and latency behind :meth:`read` (:class:`~rtgait.sim.sensors.SensorModel`,
            with the settings of ``sim.config.sensors``).
    """

    def __init__(self, sim: SimModel, data: mujoco.MjData, joints: np.ndarray) -> None:
        self.sim, self.data = sim, data
        self.joint_names = sim.joint_names
        self.servo = ReferenceInterpolator(sim.actuation, joints)
        self.reader = GroundTruthReader.for_sim(sim)
        self.sensors = SensorModel(sim)
        self.substeps = sim.substeps
        self._model, self._ctrl = sim.model, data.ctrl
        # The first substep's contacts and sites, decoded once, when they are also the next tick's truth.
        self._last: tuple[StepSnapshot, ContactSums] | None = None

    # ----- RobotInterface ------------------------------------------------------------------------------------------
    def read(self) -> SensorReadings:
        """The sensors' readings now (:mod:`rtgait.sim.sensors`: after a physics step, of the state it started
        from, like :meth:`ground_truth`), sampled at ``data.time``. Each call is one control tick of the noise's
        walks and the latency: call it once a tick."""
        data = self.data
        return self.sensors.read(data.sensordata, float(data.time))

    def write(self, command: JointCommand) -> None:
        """The drives' references for the coming control period (the arrays are kept: pass new ones each period).

        Raises:
            ValueError: a command with gains or feed-forward torques, which the simulated drives do not take.
        """
        if command.kp is not None or command.kd is not None or command.torques is not None:
            raise ValueError(
                "the simulated drives run the robot description's [actuation] gains and take no feed-forward "
                "torque: leave JointCommand.kp, kd and torques None"
            )
        self.servo.command(command.positions, command.velocities)

    # ----- GroundTruthSource ---------------------------------------------------------------------------------------
    def ground_truth(self, t: float | None = None, velocities: bool = False) -> GroundTruth:
        """The truth of the state now (:mod:`rtgait.sim.ground_truth`), stamped ``t`` (s; default ``data.time``).
        With one physics substep a control period, the contacts the last :meth:`substep` decoded are this state's
        and are not decoded again; ``velocities``: whether ``mj_subtreeVel`` already ran on that state."""
        last = self._last
        if last is None:
            return self.reader.read(self.data, t)
        return self.reader.read(self.data, t, last[0], velocities, last[1])

    @property
    def last_contacts(self) -> tuple[StepSnapshot, ContactSums] | None:
        """The contacts and sites of the state now, as the last :meth:`first_substep` read and decoded them, when
        that was the period's only substep (``None`` otherwise): what the next :meth:`ground_truth` reads."""
        return self._last

    # ----- physics -------------------------------------------------------------------------------------------------
    def substep(self, i: int) -> None:
        """Physics substep ``i`` (0 to ``substeps - 1``) of the control period, the drives at their interpolated
        references."""
        self.servo.apply(i, self._ctrl)
        mujoco.mj_step(self._model, self.data)
        self._last = None

    def first_substep(self) -> tuple[StepSnapshot, ContactSums]:
        """The control period's first physics substep, and the contacts and sites of the state it started from,
        read and decoded once (:mod:`rtgait.sim.step_snapshot`, :mod:`rtgait.sim.contact_reading`): the run's
        contact record reads them, and so does the next tick's truth when this is the period's only substep."""
        self.servo.apply(0, self._ctrl)
        mujoco.mj_step(self._model, self.data)
        snapshot = read_snapshot(self.data)
        last = (snapshot, self.reader.contacts.read(self.data, snapshot))
        self._last = last if self.substeps == 1 else None
        return last
