"""The ``[actuation]`` table of a robot description: per-joint (or per group of joints) PD gains, armature and torque
limits, motor types, the control period, the physics step and the command's delay on the bus; parsed by
:func:`rtgait.robot.description.parse_robot`, resolved into each joint's drive by :mod:`rtgait.sim.actuation` and
:mod:`rtgait.sim.motors`.

Two sets of gains: ``kp``/``kd`` (or, where not given, gains derived from the URDF) are the simulation's stiff
servos; ``robot_kp``/``robot_kd`` are the gains the real robot's low-level controller runs (cited in each
description). ``SimConfig.gains`` picks one.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from rtgait.robot.motor_types import MotorType

__all__ = [
    "DEFAULT_ARMATURE_PER_TORQUE",
    "DEFAULT_CONTROL_DT",
    "DEFAULT_DAMPING_RATIO",
    "DEFAULT_NATURAL_FREQUENCY",
    "DEFAULT_PHYSICS_DT",
    "ActuationSpec",
    "ActuatorGroup",
    "JointActuationSpec",
    "MotorType",
]

DEFAULT_CONTROL_DT = 0.001
"""Control period (s) without ``actuation.control_dt``: 1 kHz, the usual rate of a humanoid's joint loop."""
DEFAULT_PHYSICS_DT = 0.001
"""Physics step (s) of the MuJoCo model without ``actuation.physics_dt``."""
DEFAULT_NATURAL_FREQUENCY = 10.0
"""Loaded natural frequency (Hz) of the derived gains (see :mod:`rtgait.sim.actuation`)."""
DEFAULT_DAMPING_RATIO = 1.0
"""Damping ratio of the derived kd on the joint's drive and limb: critical."""
DEFAULT_ARMATURE_PER_TORQUE = 5e-4
"""Default armature per N m of effort limit (s^2): rotor inertia J of a motor of torque T behind a gear of ratio N
gives ``J N^2 = (J / T) N effort``; brushless motors have ``J / T`` near 1e-5 s^2, so this is a gear of ratio 50
(Unitree's planetary gears of ratio 10-25: 1.2e-4 to 1.8e-4 s^2; harmonic drives of ratio 100: about 1e-3)."""


@dataclass(frozen=True)
class ActuatorGroup:
    """One ``[[actuation.joints]]`` entry: values for the joints whose names match one of its patterns.

    Attributes:
        match: ``fnmatch`` patterns on URDF joint names (``*``, ``?``, ``[seq]``).
        kp: position gain (N m/rad), or ``None`` to derive it.
        kd: damping gain (N m s/rad), or ``None`` to derive it.
        armature: rotor inertia reflected to the joint (kg m^2), given or as ``rotor_inertia * gear_ratio^2``.
        effort_limit: torque limit (N m), or ``None`` for the URDF's.
        natural_frequency: this group's target natural frequency (Hz) for derived gains, or ``None``.
        damping_ratio: this group's damping ratio for a derived kd, or ``None``.
        robot_kp: the real robot's position gain (N m/rad), or ``None``.
        robot_kd: the real robot's damping gain (N m s/rad), or ``None``.
        motor: the name of the joints' motor type (``[actuation.motors.<name>]``), or ``None``.
    """

    match: tuple[str, ...]
    kp: float | None = None
    kd: float | None = None
    armature: float | None = None
    effort_limit: float | None = None
    natural_frequency: float | None = None
    damping_ratio: float | None = None
    robot_kp: float | None = None
    robot_kd: float | None = None
    motor: str | None = None

    def matches(self, joint: str) -> bool:
        """Whether ``joint`` matches one of the group's patterns (case-sensitive)."""
        return any(fnmatch.fnmatchcase(joint, pattern) for pattern in self.match)


@dataclass(frozen=True)
class JointActuationSpec:
    """What a description says about one joint's actuator (units as :class:`ActuatorGroup`'s); ``None``: derive
    it from the URDF (the robot's gains and the motor type: none given); ``armature_per_torque`` (s^2) gives the
    armature when none is given."""

    kp: float | None
    kd: float | None
    armature: float | None
    effort_limit: float | None
    natural_frequency: float
    damping_ratio: float
    armature_per_torque: float
    robot_kp: float | None = None
    robot_kd: float | None = None
    motor: MotorType | None = None


@dataclass(frozen=True)
class ActuationSpec:
    """The ``[actuation]`` table (all optional; the defaults when a description has none).

    Attributes:
        control_dt: period at which the controller sends joint references (s).
        physics_dt: the MuJoCo model's physics step (s), a divisor of ``control_dt``: the step at which the robot's
            outcomes have converged (``docs/robots.md``); ``rtgait simulate --physics-dt`` overrides it.
        natural_frequency: default target natural frequency of a loaded joint (Hz).
        damping_ratio: default damping ratio of the derived kd.
        armature_per_torque: default armature per N m of effort limit (s^2), :data:`DEFAULT_ARMATURE_PER_TORQUE`.
        command_delay: control periods between a command's writing and the drives' applying it (a bus that delivers
            it in the next cycle: 1).
        motors: the ``[actuation.motors.<name>]`` tables, by name.
        groups: the ``[[actuation.joints]]`` entries, in file order (a later one wins).
    """

    control_dt: float = DEFAULT_CONTROL_DT
    physics_dt: float = DEFAULT_PHYSICS_DT
    natural_frequency: float = DEFAULT_NATURAL_FREQUENCY
    damping_ratio: float = DEFAULT_DAMPING_RATIO
    armature_per_torque: float = DEFAULT_ARMATURE_PER_TORQUE
    command_delay: int = 0
    motors: Mapping[str, MotorType] = field(default_factory=lambda: MappingProxyType({}))
    groups: tuple[ActuatorGroup, ...] = ()
