"""A planned walk on a robot: whole-body motion, multibody check and, optionally, angular-momentum compensation.

This is what ``rtgait plan SCENARIO --robot NAME`` runs after planning; it returns everything the command writes
(joint table, summary numbers, replay inputs) so the command itself stays thin.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from rtgait.core.analysis.rollout import Rollout
from rtgait.robot.compensation import Compensation, compensate_angular_momentum
from rtgait.robot.dynamics import MultibodyCheck, check_motion
from rtgait.robot.model import RobotModel
from rtgait.robot.motion import JointTrajectory, whole_body_motion

FOOT_ERRORS = ("left_position", "right_position")


@dataclass(frozen=True)
class RobotRun:
    """The walk on the robot. ``motion``/``check`` are the final ones (compensated when compensation ran).

    Attributes:
        robot: the robot model.
        motion: joint trajectory that is written out.
        check: its multibody check against the planned ZMP.
        uncompensated: motion and check before the compensation (``None`` when it did not run).
        compensation: the compensation step (``None`` when it did not run).
        ik_seconds: wall time of all whole-body IK passes (s).
    """

    robot: RobotModel
    motion: JointTrajectory
    check: MultibodyCheck
    uncompensated: tuple[JointTrajectory, MultibodyCheck] | None
    compensation: Compensation | None
    ik_seconds: float

    def summary(self) -> dict[str, Any]:
        """The robot's part of ``summary.json`` (m unless stated)."""
        summary: dict[str, Any] = {
            "robot": self.robot.name,
            "robot_mass": self.robot.mass,
            **motion_numbers(self.motion, self.check),
            "ik_time_per_tick_us": self.ik_seconds / self._ik_ticks() * 1e6,
        }
        if self.compensation is not None and self.uncompensated is not None:
            summary["angular_momentum_compensation"] = {
                "order": self.compensation.order,
                "cog_correction_max": axes(np.abs(self.compensation.cog_offset).max(axis=0)),
                "before": motion_numbers(*self.uncompensated),
                "after": motion_numbers(self.motion, self.check),
            }
        return summary

    def _ik_ticks(self) -> int:
        return len(self.motion.times) * (1 if self.compensation is None else 2)


def axes(values: np.ndarray) -> dict[str, float]:
    """``{"x": .., "y": ..}`` from a pair of values."""
    return {"x": float(values[0]), "y": float(values[1])}


def motion_numbers(motion: JointTrajectory, check: MultibodyCheck) -> dict[str, Any]:
    """Largest IK errors and multibody ZMP error (max and RMS per axis) of a motion (m)."""
    errors = motion.max_errors
    error = check.zmp_error
    return {
        "ik_cog_error_max": errors["cog"],
        "ik_foot_error_max": max(errors[name] for name in FOOT_ERRORS),
        "multibody_zmp_error_max": axes(np.abs(error).max(axis=0)),
        "multibody_zmp_error_rms": axes(np.sqrt((error**2).mean(axis=0))),
    }


def run_on_robot(
    robot: RobotModel,
    rollout: Rollout,
    cog_height: float,
    gravity: float,
    compensation_order: int | None = None,
) -> RobotRun:
    """Whole-body motion of ``robot`` for the planned walk, its multibody check, and the Appendix A
    compensation when ``compensation_order`` is given.

    Raises:
        rtgait.robot.motion.UnreachableError: the robot cannot follow the plan.
    """
    began = time.perf_counter()
    motion = whole_body_motion(robot, rollout)
    ik_seconds = time.perf_counter() - began
    check = check_motion(motion, rollout)
    if compensation_order is None:
        return RobotRun(robot, motion, check, None, None, ik_seconds)
    began = time.perf_counter()
    compensation = compensate_angular_momentum(robot, rollout, check, cog_height, gravity, compensation_order)
    ik_seconds += time.perf_counter() - began
    return RobotRun(robot, compensation.motion, compensation.check, (motion, check), compensation, ik_seconds)


def visual_model(robot: RobotModel) -> pin.GeometryModel:
    """The robot's visual meshes on its full model, for the 3D replay."""
    description = robot.description
    return pin.buildGeomFromUrdf(
        robot.full_model,
        str(description.urdf),
        pin.GeometryType.VISUAL,
        package_dirs=[str(Path(folder)) for folder in description.package_dirs],
    )
