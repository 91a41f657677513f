"""The walking state a controller acts on, as an estimator gives it each tick: the feet's wrenches, centres of
pressure, poses and loads, the ZMP of both feet, the centre of mass (COM) with its velocity, the divergent component
of motion (DCM) and the feet's landings.

World frame, z up, SI units. The sole frame of a foot has x forward, y left and z out of the sole; a sole's
orientation is ``R = Rz(yaw) Ry(pitch) Rx(roll)``. The DCM is ``xi = c + c'/w`` with the planner's
``w = sqrt(g / z_c)``.
"""

from __future__ import annotations

from typing import NamedTuple

from rtgait.core.geometry.footsteps import Footstep, Side

__all__ = ["FootState", "Landing", "Measurement"]


class FootState(NamedTuple):
    """One foot at one tick (world frame unless said otherwise; SI units).

    Attributes:
        force: contact force of the ground on the foot ``(fx, fy, fz)`` (N).
        torque: its moment about the sole frame origin ``(tx, ty, tz)`` (N m).
        normal_force: ``fz``, the vertical force (N); the floor is horizontal, so this is its normal force.
        cop: centre of pressure on the sole plane ``(x, y)`` (m); NaN below the measurer's ``min_force``.
        cop_local: the same in the sole frame (x forward, y left) (m); NaN likewise.
        pose: sole frame ``(x, y, z, yaw)`` (m, rad), yaw of the sole's x axis projected on the ground.
        roll, pitch: the sole's remaining rotation, ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (rad).
        tilt: angle between the sole normal and the vertical (rad).
        loaded: the load state after hysteresis (module docstring).
        contacts: contact points of the foot with the environment.
    """

    force: tuple[float, float, float]
    torque: tuple[float, float, float]
    normal_force: float
    cop: tuple[float, float]
    cop_local: tuple[float, float]
    pose: tuple[float, float, float, float]
    roll: float
    pitch: float
    tilt: float
    loaded: bool
    contacts: int

    def footstep(self, side: Side) -> Footstep:
        """The foot's pose as a planner footprint (x, y, yaw)."""
        x, y, _, yaw = self.pose
        return Footstep(x, y, yaw, side)


class Landing(NamedTuple):
    """A swing foot touched down: its measured sole pose at the tick the load crossed the landing threshold.

    Attributes:
        t: the tick's time (s).
        side: ``"left"`` or ``"right"``.
        x, y, z, yaw: sole frame position (m) and heading (rad).
        roll, pitch: the sole's remaining rotation (rad).
        normal_force: vertical force on the foot at that tick (N).
    """

    t: float
    side: Side
    x: float
    y: float
    z: float
    yaw: float
    roll: float
    pitch: float
    normal_force: float

    def footstep(self) -> Footstep:
        """Where it landed, as a planner footprint."""
        return Footstep(self.x, self.y, self.yaw, self.side)


class Measurement(NamedTuple):
    """Everything measured at one control tick (world frame, SI units); see the module docstring.

    Attributes:
        t: the tick's time (s), as given by the caller.
        com: centre of mass ``(x, y, z)`` (m).
        com_vel: its velocity (m/s).
        dcm: horizontal divergent component of motion ``c + c'/w`` (m).
        zmp: ZMP of both feet on the ground plane (m); NaN when no foot carries ``min_force``.
        normal_force: vertical force on both feet together (N).
        left, right: the feet.
        landings: landings detected at this tick (usually none).
        other_contacts: contacts of the robot with the environment that are not on a sole (a knee, a hand): 0
            while walking.
    """

    t: float
    com: tuple[float, float, float]
    com_vel: tuple[float, float, float]
    dcm: tuple[float, float]
    zmp: tuple[float, float]
    normal_force: float
    left: FootState
    right: FootState
    landings: tuple[Landing, ...]
    other_contacts: int

    @property
    def support(self) -> str:
        """Which feet are loaded: ``"double"``, ``"left"``, ``"right"`` or ``"none"``."""
        left, right = self.left.loaded, self.right.loaded
        if left and right:
            return "double"
        return "left" if left else ("right" if right else "none")
