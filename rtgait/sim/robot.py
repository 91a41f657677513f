"""The simulated robot behind :class:`~rtgait.interface.robot.RobotInterface`: MuJoCo's state read as the robot's
encoders and drives report it, joint commands written to its drives, and the simulator's truth on its own channel
(:class:`~rtgait.interface.robot.GroundTruthSource`).

The drives take the whole :class:`~rtgait.interface.command.JointCommand`, as G1's motors and a ros_control joint do:
``tau = tau_ff + kp (q_ref - q) + kd (dq_ref - dq)`` at every physics step, within the torque limit or the motor's
envelope, the gains left out of a command the description's (``SimConfig.gains``), a command applied
``SimConfig.command_delay`` periods after it is written (:mod:`rtgait.sim.drives`). A **damping** command (``kp`` all
0, ``kd`` given: Unitree's damping mode, the one the stack's safety layer sends, :mod:`rtgait.stack.safety`) is one
of them: ``tau = kd (dq_ref - dq)``. MuJoCo has no per-data gains: the drives set them in the model's actuator
parameters, so one :class:`SimRobot` drives a model at a time; a new one puts the model's own gains back. The
readings are those of the robot description's ``[sensors]`` (:mod:`rtgait.sim.sensors`): encoders, joint torques (the
drives'), the IMU and the feet's force sensors where the robot has them. With a model error
(:mod:`rtgait.sim.model_error`) the encoders read the joints plus their zero offsets, and the drives servo those
readings to the commanded references.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.interface.command import JointCommand
from rtgait.interface.readings import SensorReadings
from rtgait.interface.truth import GroundTruth
from rtgait.sim.contact_reading import ContactSums
from rtgait.sim.drives import Drives
from rtgait.sim.ground_truth import GroundTruthReader
from rtgait.sim.implicit_wrench import ImplicitStepWrench
from rtgait.sim.sensor_sites import FOOT_SITES
from rtgait.sim.sensors import SensorModel, applied_damping
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
        drives: the joints' drives (:class:`~rtgait.sim.drives.Drives`): the command they apply now, their gains.
        sensors: the sensors' noise, biases and latency behind :meth:`read` (:class:`~rtgait.sim.sensors.SensorModel`,
            with the settings of ``sim.config.sensors``).
    """

    def __init__(self, sim: SimModel, data: mujoco.MjData, joints: np.ndarray) -> None:
        self.sim, self.data = sim, data
        self.joint_names = sim.joint_names
        self.drives = Drives(sim, data, joints)  # the model's own gains, whatever a robot before this one left
        self.reader = GroundTruthReader.for_sim(sim)
        self.sensors = SensorModel(sim)
        self.substeps = sim.substeps
        self._model, self._ctrl = sim.model, data.ctrl
        self._apply = self.drives.apply
        # The feet's force sensors read with the acceleration the step integrates (module docstring).
        self._wrench = None
        if self.sensors.layout.feet:
            sites = [mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_SITE, FOOT_SITES[s]) for s in ("left", "right")]
            self._wrench = ImplicitStepWrench(sim.model, tuple(sites))
        # The first substep's contacts and sites, decoded once, when they are also the next tick's truth.
        self._last: tuple[StepSnapshot, ContactSums] | None = None

    # ----- RobotInterface ------------------------------------------------------------------------------------------
    def read(self) -> SensorReadings:
        """The sensors' readings now (:mod:`rtgait.sim.sensors`: after a physics step, of the state it started
        from, like :meth:`ground_truth`), sampled at ``data.time``. Each call is one control tick of the noise's
        walks and the latency: call it once a tick."""
        data, sensors = self.data, self.sensors
        damping = None
        if sensors.joint_torques:
            # The drives' torque over the step from the sampled state, not MuJoCo's of that state alone.
            n, start, model = sensors.layout.joints, sensors.layout.start, self._model
            ranges = model.actuator_forcerange
            limited = model.actuator_forcelimited.astype(bool)
            damping = applied_damping(
                self.drives.kd, data.sensordata[start + n : start + 2 * n], data.qvel[self.sim.dof_index],
                data.actuator_force, np.where(limited, ranges[:, 0], -np.inf), np.where(limited, ranges[:, 1], np.inf),
            )  # fmt: skip
        feet = None if self._wrench is None else self._wrench.correction(data)
        return sensors.read(data.sensordata, float(data.time), damping, feet)

    def write(self, command: JointCommand) -> None:
        """The drives' command for the coming control period (module docstring; without a command delay the arrays
        are kept: pass new ones each period).

        Raises:
            ValueError: an array of the wrong shape or not finite, or gains that are not >= 0.
        """
        self.drives.command(command)

    @property
    def damping(self) -> bool:
        """Whether the drives hold no position (the command they apply has ``kp`` all 0: damping)."""
        return self.drives.damping

    # ----- GroundTruthSource ---------------------------------------------------------------------------------------
    def ground_truth(self, t: float | None = None, velocities: bool = False) -> GroundTruth:
        """The truth of the state now (:mod:`rtgait.sim.ground_truth`), stamped ``t`` (s; default ``data.time``).
        With one physics substep a control period, the contacts the last :meth:`substep` decoded are this state's
        and are not decoded again; ``velocities``: whether ``mj_subtreeVel`` already ran on that state."""
        last = self._last
        if last is None:
            return self.reader.read(self.data, t)
        return self.reader.read(self.data, t, last[0], velocities, last[1])

    def joint_truth(self, t: float) -> SensorReadings:
        """The joints' true positions (rad) and velocities (rad/s), of the state :meth:`ground_truth` reads (the one
        the last physics step started from), stamped ``t`` (s): the encoders' reading without their noise, offsets
        or latency, and nothing else (no torques, IMU or force sensors). What a feed-forward computed at the sensed
        state reads when the estimator reads the truth, which has no joints (:mod:`rtgait.stack.measured_motion`)."""
        layout = self.sensors.layout
        n, start = layout.joints, layout.start
        values = self.data.sensordata[start : start + 2 * n].copy()
        return SensorReadings(t, values[:n], values[n:])

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
        if self._wrench is not None and i == self.substeps - 1:
            self._wrench.keep_velocity(self.data)
        mujoco.mj_step(self._model, self.data)
        self._last = None

    def first_substep(self) -> tuple[StepSnapshot, ContactSums]:
        """The control period's first physics substep, and the contacts and sites of the state it started from,
        read and decoded once (:mod:`rtgait.sim.step_snapshot`, :mod:`rtgait.sim.contact_reading`): the run's
        contact record reads them, and so does the next tick's truth when this is the period's only substep."""
        self._apply(0, self._ctrl)
        if self._wrench is not None and self.substeps == 1:
            self._wrench.keep_velocity(self.data)
        mujoco.mj_step(self._model, self.data)
        snapshot = read_snapshot(self.data)
        last = (snapshot, self.reader.contacts.read(self.data, snapshot))
        self._last = last if self.substeps == 1 else None
        return last
