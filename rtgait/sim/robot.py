"""The simulated robot behind :class:`~rtgait.interface.robot.RobotInterface`: MuJoCo's state read as the robot's
encoders and drives report it, joint commands written to its position-controlled drives, and the simulator's truth
on its own channel (:class:`~rtgait.interface.robot.GroundTruthSource`).

The drives are MuJoCo position actuators with the gains of the robot description's ``[actuation]``
(:mod:`rtgait.sim.actuation`): a command's ``q_ref`` and ``dq_ref`` are interpolated linearly over the control
period's physics substeps. What it does not simulate yet is refused, not ignored: gains other than the drives' own,
feed-forward torques. The readings carry the encoders and the drives' torques; the IMU and the feet's force sensors
are not simulated (``None``), so the only estimator that can run on it today is the ground-truth one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.command import JointCommand
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth
from rtgait.sim.actuation import ReferenceInterpolator
from rtgait.sim.ground_truth import GroundTruthReader
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
    """

    def __init__(self, sim: SimModel, data: mujoco.MjData, joints: np.ndarray) -> None:
        self.sim, self.data = sim, data
        self.joint_names = sim.joint_names
        self.servo = ReferenceInterpolator(sim.actuation, joints)
        self.reader = GroundTruthReader.for_sim(sim)
        self.substeps = sim.substeps
        self._model, self._ctrl = sim.model, data.ctrl
        self._snapshot: StepSnapshot | None = None

    # ----- RobotInterface ------------------------------------------------------------------------------------------
    def read(self) -> SensorReadings:
        """The encoders and the drives' torques now."""
        data, sim = self.data, self.sim
        return SensorReadings(
            float(data.time), data.qpos[sim.qpos_index], data.qvel[sim.dof_index], data.actuator_force.copy()
        )

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
        """The truth of the state the last physics step started from (module :mod:`rtgait.sim.ground_truth`),
        stamped ``t`` (s; default ``data.time``); ``velocities``: whether ``mj_subtreeVel`` already ran on it."""
        return self.reader.read(self.data, t, self._snapshot, velocities)

    # ----- physics -------------------------------------------------------------------------------------------------
    def substep(self, i: int) -> StepSnapshot | None:
        """Physics substep ``i`` (0 to ``substeps - 1``) of the control period, the drives at their interpolated
        references; the first substep's contacts and sites are read once (:mod:`rtgait.sim.step_snapshot`) and
        returned: the state the step started from, which the next tick's truth reads again when it is the period's
        only substep."""
        self.servo.apply(i, self._ctrl)
        mujoco.mj_step(self._model, self.data)
        if i == 0:
            snapshot = self._snapshot = read_snapshot(self.data) if self.substeps == 1 else None
            return snapshot if snapshot is not None else read_snapshot(self.data)
        return None
