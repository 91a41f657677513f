"""How the loop drives the joints (``LoopOptions.drive``): position servos, or torques with low gains.

* ``"position"``: every command leaves its gains out, so the drives apply their own (``SimConfig.gains``); the
  command's feed-forward torque, when the stack computes one, adds to the servo.
* ``"torque"``: the motion is carried by the feed-forward torques of whole-body inverse dynamics
  (:mod:`rtgait.stack.feedforward`), the DCM law's commanded wrench included, and every command carries low gains
  around its references, :data:`TORQUE_GAIN_FRACTION` of the robot's own (``robot_kp``, ``robot_kd`` of the
  description, whatever ``SimConfig.gains``), as torque-controlled walking does on Talos (TSID, mc_rtc's torque
  mode: the joint loops only damp the motion and hold the posture against what the model misses).

The gains of torque drive are ``kp_t = 0.1 kp_robot`` and ``kd_t = 0.1 kd_robot`` (N m/rad, N m s/rad): G1's ankles
4 N m/rad against gravity's toppling stiffness of some 210 N m/rad, TALOS's hips and knees 100 N m/rad. A damping
command (``kp`` all 0, the safety layer's) keeps its own gains.

The feed-forward of torque drive is computed at the sensed state and carries the joints' tracking stiffness
(:mod:`rtgait.stack.measured_motion`); its damping, ``2 I_j w`` (the inertia beyond each joint times twice the
tracking's frequency), is added to the commands' ``kd``: the drives damp on the joint's velocity at every physics
step, as the velocity loop of a real drive does, where the controller's damping would act a control period late.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np

from rtgait.sim.actuation import resolve_actuation

if TYPE_CHECKING:
    from rtgait.interface.command import JointCommand
    from rtgait.sim.model import SimModel
    from rtgait.stack.measured_motion import MeasuredMotion

__all__ = ["DRIVE_MODES", "TORQUE_GAIN_FRACTION", "DriveMode", "check_drive", "torque_gains", "with_gains"]

DriveMode = Literal["position", "torque"]
DRIVE_MODES: tuple[str, ...] = ("position", "torque")
"""The drive modes (module docstring)."""

TORQUE_GAIN_FRACTION = 0.1
"""Torque drive's gains as a fraction of the robot's own (module docstring)."""


def check_drive(drive: object, name: str = "drive") -> None:
    """Raise ``ValueError`` unless ``drive`` is one of :data:`DRIVE_MODES`."""
    if drive not in DRIVE_MODES:
        raise ValueError(f"{name} must be one of {', '.join(DRIVE_MODES)}, got {drive!r}")


def torque_gains(sim: SimModel, tracking: MeasuredMotion | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(kp, kd)`` of torque drive for ``sim``'s joints (N m/rad, N m s/rad): :data:`TORQUE_GAIN_FRACTION` of the
    robot's own gains, and with ``tracking`` its joints' damping added to ``kd`` (module docstring).

    Raises:
        ValueError: the description gives no ``robot_kp``/``robot_kd`` for a joint.
    """
    actuation = sim.actuation
    own = resolve_actuation(sim.robot, actuation.control_dt, actuation.physics_dt, gains="robot")
    kd = TORQUE_GAIN_FRACTION * own.kd
    if tracking is not None:
        kd = kd + tracking.damping
    return TORQUE_GAIN_FRACTION * own.kp, kd


def with_gains(command: JointCommand, gains: tuple[np.ndarray, np.ndarray] | None) -> JointCommand:
    """``command`` with ``gains`` when it leaves its own out (a damping command keeps its gains); itself without."""
    if gains is None or command.kp is not None:
        return command
    return command._replace(kp=gains[0], kd=gains[1])
