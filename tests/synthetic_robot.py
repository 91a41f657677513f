"""A Talos-sized robot for the controller's tests on synthetic measurements: its sole, planner settings, mass and
a measured foot's state built from the load and centre of pressure a test gives it."""

from __future__ import annotations

import math

from rtgait.control.controller import RobotInfo
from rtgait.core.geometry.footsteps import SoleRect, Timing
from rtgait.core.planner.online import PlannerConfig
from rtgait.estimation.state import FootState

SOLE = SoleRect(front=0.105, back=0.105, inner=0.065, outer=0.065)
CONFIG = PlannerConfig(
    cog_height=0.84, timing=Timing(0.7, 0.1, start=0.6, end=0.6, settle=0.8), step_width=0.2,
    connection="quasi-real-time",
)  # fmt: skip
INFO = RobotInfo(mass=90.0, sole=SOLE, leg_length=0.84)
WEIGHT = 90.0 * 9.81  # N
DT = 0.001  # s: the control period


def foot_state(pose, fz, cop, loaded) -> FootState:
    """A measured foot at ``pose`` (x, y, z, yaw) carrying ``fz`` (N) with its CoP at world ``cop``."""
    x, y, _, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    local = (c * (cop[0] - x) + s * (cop[1] - y), -s * (cop[0] - x) + c * (cop[1] - y))
    torque = (fz * local[1], -fz * local[0], 0.0)
    return FootState((0.0, 0.0, fz), torque, fz, cop, local, tuple(pose), 0.0, 0.0, 0.0, loaded, 4 if loaded else 0)
