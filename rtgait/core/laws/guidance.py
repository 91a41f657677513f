"""Hand-guided walking (the paper's Section 6): a force at the robot's hand sets the next steps.

An operator leads the robot by the hand; the wrist force/torque sensor reads the pull. An admittance turns the
horizontal force, expressed in the robot's heading frame, into a forward/lateral speed and the vertical torque
into a yaw rate; the planner walks that command with the quasi-real-time connection, so each new step is decided
one double support before it lifts off and the COG has a whole single support to follow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rtgait.core.planner.online import OnlinePlanner, VelocityCommand


def _deadband(value: float, band: float) -> float:
    """Zero inside ``[-band, band]``, shifted linearly outside, so the command starts from zero without a jump."""
    if abs(value) <= band:
        return 0.0
    return value - math.copysign(band, value)


def _clip(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


@dataclass(frozen=True)
class Admittance:
    """Hand force to walking command: ``v = (F - deadband) / damping``, saturated.

    Attributes:
        linear_damping: force per speed (N s/m): a 12 N pull beyond the deadband asks for 0.2 m/s at 60.
        yaw_damping: torque per yaw rate (N m s/rad).
        force_deadband: forces below this do not move the robot (N): sensor noise and arm sway.
        torque_deadband: (N m).
        max_forward, max_lateral: speed limits (m/s).
        max_yaw_rate: (rad/s).
    """

    linear_damping: float = 60.0
    yaw_damping: float = 20.0
    force_deadband: float = 5.0
    torque_deadband: float = 1.0
    max_forward: float = 0.2
    max_lateral: float = 0.05
    max_yaw_rate: float = 0.3

    def __post_init__(self) -> None:
        for name in ("linear_damping", "yaw_damping", "max_forward", "max_lateral", "max_yaw_rate"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"admittance {name} must be finite and > 0, got {value}")
        for name in ("force_deadband", "torque_deadband"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"admittance {name} must be finite and >= 0, got {value}")

    def command(self, force_x: float, force_y: float, torque_z: float, heading: float) -> VelocityCommand:
        """Walking command for a hand force ``(force_x, force_y)`` (N, world frame), a torque about the vertical
        ``torque_z`` (N m) and the robot's heading (rad)."""
        for name, value in (("force_x", force_x), ("force_y", force_y), ("torque_z", torque_z), ("heading", heading)):
            if not math.isfinite(value):
                raise ValueError(f"hand {name} must be finite, got {value}")
        c, s = math.cos(heading), math.sin(heading)
        forward = c * force_x + s * force_y  # the pull in the robot's own frame
        lateral = -s * force_x + c * force_y
        return VelocityCommand(
            vx=_clip(_deadband(forward, self.force_deadband) / self.linear_damping, self.max_forward),
            vy=_clip(_deadband(lateral, self.force_deadband) / self.linear_damping, self.max_lateral),
            wz=_clip(_deadband(torque_z, self.torque_deadband) / self.yaw_damping, self.max_yaw_rate),
        )


class HandGuide:
    """Feeds a planner walking by command with the admittance's reading of the hand, once per step.

    The command is handed over only when the next quasi-real-time deadline comes, so every step is planned from
    the pull at its decision time, as in the paper's experiment; between deadlines the force is ignored.
    """

    def __init__(self, planner: OnlinePlanner, admittance: Admittance | None = None) -> None:
        if planner.config.connection != "quasi-real-time":
            raise ValueError("hand-guided walking uses the quasi-real-time connection (the paper's Section 6)")
        if planner.n_steps is not None:
            raise ValueError("hand-guided walking needs a planner walking by command: OnlinePlanner(config, None)")
        self.planner = planner
        self.admittance = admittance or Admittance()
        self.command = VelocityCommand()
        self._decided_step = 0

    def update(self, t: float, force_x: float, force_y: float, torque_z: float, heading: float) -> bool:
        """Call every tick before ``planner.sample(t)``; returns True when a new command was handed over."""
        step = self.planner.first_open_step()
        window_opens = self.planner.change_deadline(step) - self.planner.config.timing.double_support
        if step == self._decided_step or t < window_opens:
            return False
        self._decided_step = step
        command = self.admittance.command(force_x, force_y, torque_z, heading)
        if command != self.command:
            self.command = command
            self.planner.set_velocity(command.vx, command.vy, command.wz)
            return True
        return False
