"""The simulated robot behind :class:`~rtgait.interface.robot.RobotInterface`: MuJoCo's state read as the robot's
encoders and drives report it, joint commands written to its position-controlled drives, and the simulator's truth
on its own channel (:class:`~rtgait.interface.robot.GroundTruthSource`).

The drives are MuJoCo position actuators with the gains of the robot description's ``[actuation]``
(:mod:`rtgait.sim.actuation`): a command's ``q_ref`` and ``dq_ref`` are interpolated linearly over the control
period's physics substeps. A **damping** command (``kp`` all 0, ``kd`` given, no torque or all 0: Unitree's damping
mode, the one the stack's safety layer sends, :mod:`rtgait.stack.safety`) switches each drive to

    tau = kd (dq_ref - dq)                                                             (N m)

within its torque limit: the actuator's gain becomes ``kd`` on ``ctrl = dq_ref`` and its bias ``-kd dq``, integrated
implicitly like the servos' damping. MuJoCo has no per-data gains: they are set in the model's actuator parameters,
so one :class:`SimRobot` drives a model at a time; a new one, and the next position command, put the servo gains
back (that command is interpolated from the last one before the damping). What it does not simulate yet is refused,
not ignored: other gains, feed-forward torques. The readings are those of the robot description's ``[sensors]``
(:mod:`rtgait.sim.sensors`): encoders, joint torques, the IMU and the feet's force sensors where the robot has them.
With a model error (:mod:`rtgait.sim.model_error`) the encoders read the joints plus their zero offsets, and the
drives servo those readings to the commanded references.
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
        self.servo = ReferenceInterpolator(sim.actuation, joints, sim.encoder_offsets)
        self.reader = GroundTruthReader.for_sim(sim)
        self.sensors = SensorModel(sim)
        self.substeps = sim.substeps
        self._model, self._ctrl = sim.model, data.ctrl
        self._servos()  # the model's actuators as built, whatever a robot before this one left
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
        """The drives' references for the coming control period (the arrays are kept: pass new ones each period):
        a position command, or a damping command (module docstring).

        Raises:
            ValueError: a command with other gains or with feed-forward torques, which the simulated drives do not
                take; a damping command with gains that are not finite and >= 0, or a velocity that is not finite.
        """
        if command.kp is None and command.kd is None and command.torques is None:
            if self._damping is not None:
                self._servos()
            self.servo.command(command.positions, command.velocities)
            return
        self._damp(command)

    def _damp(self, command: JointCommand) -> None:
        """Switch the drives to damping with ``command``'s ``kd`` and ``dq_ref`` (module docstring)."""
        kp, kd, torques, n = command.kp, command.kd, command.torques, len(self.joint_names)
        if kp is None or kd is None or np.any(kp != 0.0) or (torques is not None and np.any(torques != 0.0)):
            raise ValueError(
                "the simulated drives take position commands (JointCommand.kp, kd and torques None) or damping "
                "commands (kp all 0, kd given, torques None or 0): other gains and feed-forward torques are not "
                "simulated yet"
            )
        kd = np.asarray(kd, dtype=float)
        velocity = np.asarray(command.velocities, dtype=float)
        if kd.shape != (n,) or not (np.isfinite(kd).all() and (kd >= 0.0).all()):
            raise ValueError(f"a damping command's kd must be {n} finite gains >= 0 N m s/rad, got {command.kd!r}")
        if velocity.shape != (n,) or not np.isfinite(velocity).all():
            raise ValueError(f"a damping command's velocities must be {n} finite values (rad/s)")
        model = self._model
        model.actuator_gainprm[:, 0] = kd  # force = kd ctrl - kd dq, ctrl = dq_ref
        model.actuator_biasprm[:, 1] = 0.0
        model.actuator_biasprm[:, 2] = -kd
        self._damping = velocity.copy()
        self._apply = self._damp_apply

    def _damp_apply(self, i: int, ctrl: np.ndarray) -> None:
        """Substep ``i``'s controls in damping: the velocity reference."""
        ctrl[:] = self._damping

    def _servos(self) -> None:
        """The drives back to their position servos (:func:`rtgait.sim.actuation.add_actuators`'s parameters)."""
        actuation, model = self.sim.actuation, self._model
        model.actuator_gainprm[:, 0] = actuation.kp
        model.actuator_biasprm[:, 1] = -actuation.kp
        model.actuator_biasprm[:, 2] = -actuation.kd
        self._damping: np.ndarray | None = None
        self._apply = self.servo.apply

    @property
    def damping(self) -> bool:
        """Whether the drives are in damping (the last command was a damping command)."""
        return self._damping is not None

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
        self._apply(i, self._ctrl)
        mujoco.mj_step(self._model, self.data)
        self._last = None

    def first_substep(self) -> tuple[StepSnapshot, ContactSums]:
        """The control period's first physics substep, and the contacts and sites of the state it started from,
        read and decoded once (:mod:`rtgait.sim.step_snapshot`, :mod:`rtgait.sim.contact_reading`): the run's
        contact record reads them, and so does the next tick's truth when this is the period's only substep."""
        self._apply(0, self._ctrl)
        mujoco.mj_step(self._model, self.data)
        snapshot = read_snapshot(self.data)
        last = (snapshot, self.reader.contacts.read(self.data, snapshot))
        self._last = last if self.substeps == 1 else None
        return last
