"""The motor model of the simulated drives (``SimConfig.motor_model``): each joint's torque-speed envelope and the
friction of its gears, from the motor types of the robot description (:mod:`rtgait.robot.motor_types`).

At every physics step, before MuJoCo evaluates the actuators, each actuator's force range becomes what its motor can
give at the joint's velocity ``dq`` (rad/s), within the joint's torque limit ``T_max`` (N m)::

    upper = min(T_max, T_drive(|dq|))  if dq >= 0  else  min(T_max, T_brake)
    lower = -min(T_max, T_drive(|dq|)) if dq <= 0  else -min(T_max, T_brake)

(``T_drive`` falls from the peak torque to zero at the no-load speed; ``T_brake`` does not fall). The PD torque of
the drive (:mod:`rtgait.sim.drives`) is clipped to it. At standstill both bounds are the peak torque.

Friction is MuJoCo's own, on each moving joint: ``frictionloss = F_c`` (Coulomb friction, solved as a constraint:
the joint sticks while less than ``F_c`` acts on it) and ``damping = b`` (viscous, integrated implicitly). It acts
between the joint's two links, not through the actuator: the drives' torque (``actuator_force``, the joint torque
the sensors read) is the motor's, before the gears' friction.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from rtgait.robot.model import RobotModel
from rtgait.sim.actuation import Actuation

__all__ = ["MotorModel", "add_friction", "resolve_motors"]


@dataclass(frozen=True, eq=False)
class MotorModel:
    """The motors of every moving joint, in ``joint_names`` order (module docstring).

    Attributes:
        joint_names: the moving joints.
        motors: each joint's motor type name.
        peak_torque: ``T_peak`` per joint (N m).
        braking_torque: ``T_brake`` per joint (N m).
        corner_speed: speed up to which the peak torque drives, per joint (rad/s).
        no_load_speed: speed at which the driving torque is zero, per joint (rad/s).
        coulomb_friction: ``F_c`` per joint (N m).
        viscous_friction: ``b`` per joint (N m s/rad).
        effort_limit: the joints' torque limits (N m; ``inf``: none), which cap the envelope.
    """

    joint_names: tuple[str, ...]
    motors: tuple[str, ...]
    peak_torque: np.ndarray
    braking_torque: np.ndarray
    corner_speed: np.ndarray
    no_load_speed: np.ndarray
    coulomb_friction: np.ndarray
    viscous_friction: np.ndarray
    effort_limit: np.ndarray

    def __post_init__(self) -> None:
        # What the per-step bounds need, computed once: the slope, the driving torque's cap and the braking torques.
        object.__setattr__(self, "_per_speed", self.peak_torque / (self.no_load_speed - self.corner_speed))
        object.__setattr__(self, "_drive_cap", np.minimum(self.peak_torque, self.effort_limit))
        brake = np.minimum(self.braking_torque, self.effort_limit)
        object.__setattr__(self, "_brake", (brake, -brake))

    def driving_torque(self, velocity: np.ndarray) -> np.ndarray:
        """``min(T_max, T_drive(|dq|))`` per joint at joint velocities ``velocity`` (rad/s), in N m (a new array)."""
        torque = np.abs(velocity)
        np.subtract(self.no_load_speed, torque, out=torque)
        np.multiply(torque, self._per_speed, out=torque)  # type: ignore[attr-defined]
        np.minimum(torque, self._drive_cap, out=torque)  # type: ignore[attr-defined]
        return np.maximum(torque, 0.0, out=torque)

    def bounds(self, velocity: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
        """Write the actuators' force bounds at joint velocities ``velocity`` (rad/s) into ``lower`` and ``upper``
        (e.g. the columns of ``model.actuator_forcerange``), in N m: the module docstring's."""
        drive = self.driving_torque(velocity)
        brake, against = self._brake  # type: ignore[attr-defined]
        upper[:] = np.where(velocity >= 0.0, drive, brake)
        lower[:] = np.where(velocity <= 0.0, np.negative(drive, out=drive), against)

    def standstill(self, out: np.ndarray) -> None:
        """Write the force ranges at standstill (``+-min(T_max, T_peak)``) into ``out`` (shape ``(n, 2)``, e.g.
        ``model.actuator_forcerange``)."""
        self.bounds(np.zeros(len(self.joint_names)), out[:, 0], out[:, 1])


def resolve_motors(robot: RobotModel, actuation: Actuation) -> MotorModel:
    """The motors of ``robot``'s moving joints, from its description's motor types, capped by ``actuation``'s torque
    limits.

    Raises:
        ValueError: a moving joint without a motor type (``motor`` in ``[[actuation.joints]]``).
    """
    description = robot.description
    types = []
    for name in actuation.joint_names:
        motor = description.joint_actuation(name).motor
        if motor is None:
            raise ValueError(
                f"the motor model needs a motor type for every moving joint: the description of {description.name} "
                f"gives none for {name} (motor in [[actuation.joints]], [actuation.motors.<name>])"
            )
        types.append(motor)
    return MotorModel(
        joint_names=actuation.joint_names,
        motors=tuple(m.name for m in types),
        peak_torque=np.array([m.peak_torque for m in types]),
        braking_torque=np.array([m.braking for m in types]),
        corner_speed=np.array([m.corner_speed for m in types]),
        no_load_speed=np.array([m.no_load_speed for m in types]),
        coulomb_friction=np.array([m.coulomb_friction for m in types]),
        viscous_friction=np.array([m.viscous_friction for m in types]),
        effort_limit=actuation.effort_limit.copy(),
    )


def add_friction(spec: mujoco.MjSpec, motors: MotorModel) -> None:
    """Give each moving joint of ``spec`` its motor's friction (module docstring), replacing the URDF's
    ``<dynamics>``, and make every actuator force-limited at the standstill range (the drives set the range at each
    step from then on)."""
    ranges = np.empty((len(motors.joint_names), 2))
    motors.standstill(ranges)
    for i, name in enumerate(motors.joint_names):
        joint = spec.joint(name)
        joint.frictionloss = float(motors.coulomb_friction[i])
        joint.damping = [float(motors.viscous_friction[i]), 0.0, 0.0]  # linear; no polynomial terms
        actuator = spec.actuator(name)
        actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.forcerange = [float(ranges[i, 0]), float(ranges[i, 1])]
