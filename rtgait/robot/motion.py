"""Whole-body joint trajectories from a planned walk: the planner's COG and feet, tick by tick, through the IK.

The planner gives the COG and each foot as ``(x, y, z, yaw)`` of its sole point (the ankle's projection on the
sole); those are exactly the IK's targets, the sole level or, on sloped footholds, tilted to their surface
(:mod:`rtgait.core.geometry.foot_tilt`). A walk the robot
cannot follow (a step longer than its legs, a COG higher than it can reach) is detected from the IK's errors and
raised as :class:`UnreachableError`, never returned as a silently different motion.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from rtgait.core.analysis.rollout import Rollout
from rtgait.core.geometry.foot_tilt import is_tilted, tilted_feet
from rtgait.core.geometry.toe_off import changes_height, toe_off_feet
from rtgait.core.planner.config import PlannerConfig, VelocityLimits
from rtgait.core.planner.sample import SampleColumns
from rtgait.interface.task_targets import IKTargets
from rtgait.robot.description import RobotError
from rtgait.robot.ik import WholeBodyIK
from rtgait.robot.model import BASE_COLUMNS, RobotModel
from rtgait.scenario.scenario import Scenario
from rtgait.scenario.walking_table import walking_for

__all__ = [
    "ERROR_FIELDS",
    "ERROR_LIMITS",
    "JointTrajectory",
    "RobotWalk",
    "UnreachableError",
    "robot_scenario",
    "walking_robot",
    "whole_body_motion",
]

ERROR_FIELDS = (
    "cog",
    "left_position",
    "left_orientation",
    "right_position",
    "right_orientation",
    "torso_orientation",
    "pelvis_orientation",
)
"""Columns of :attr:`JointTrajectory.errors`: COG and feet position errors (m), orientation errors (rad)."""

ERROR_LIMITS = {
    "cog": 0.01,
    "left_position": 0.005,
    "left_orientation": 0.05,
    "right_position": 0.005,
    "right_orientation": 0.05,
    "torso_orientation": 0.1,
}
"""Largest IK error (m or rad) a motion may have at any tick before the walk counts as out of reach. A reachable
walk is tracked to micrometres, so these only separate "reachable" from "not". The pelvis orientation is a soft
preference of the IK, not a requirement, and has no limit."""

_LABELS = {
    "cog": "COG error",
    "left_position": "left foot error",
    "left_orientation": "left foot orientation error",
    "right_position": "right foot error",
    "right_orientation": "right foot orientation error",
    "torso_orientation": "torso orientation error",
    "pelvis_orientation": "pelvis orientation error",
}


class UnreachableError(ValueError):
    """The robot cannot follow the planned walk: the IK's error exceeded its limit. One line says where."""


@dataclass(frozen=True, eq=False)
class JointTrajectory:
    """A whole-body motion sampled at the rollout's ticks.

    Attributes:
        robot: the robot it moves.
        times: tick times (s), shape ``(k,)``.
        q: configurations of the reduced model (base pose, then :attr:`joint_names`), shape ``(k, nq)``.
        cog_target: the COG targets the IK tracked (m), shape ``(k, 3)``: the planned COG plus any offset.
        errors: IK errors per tick measured by forward kinematics, columns :data:`ERROR_FIELDS` (m, rad).
        iterations: Gauss-Newton iterations per tick.
    """

    robot: RobotModel
    times: np.ndarray
    q: np.ndarray
    cog_target: np.ndarray
    errors: np.ndarray
    iterations: np.ndarray

    @property
    def joint_names(self) -> tuple[str, ...]:
        """URDF names of the moving joints, in the order of ``q[:, 7:]``."""
        return self.robot.joint_names

    def error(self, name: str) -> np.ndarray:
        """One error column by its :data:`ERROR_FIELDS` name (m or rad), shape ``(k,)``."""
        return self.errors[:, ERROR_FIELDS.index(name)]

    @property
    def max_errors(self) -> dict[str, float]:
        """Largest error of each kind over the motion (m or rad), keyed by :data:`ERROR_FIELDS`."""
        return {name: float(value) for name, value in zip(ERROR_FIELDS, self.errors.max(axis=0), strict=True)}

    @property
    def q_full(self) -> np.ndarray:
        """Configurations of the full model (locked joints at half-sitting), shape ``(k, full nq)``."""
        return self.robot.full_configuration(self.q)

    def table(self, full: bool = True) -> tuple[tuple[str, ...], np.ndarray]:
        """Header and rows for a CSV file: ``t`` (s), the base (``base_x`` .. ``base_qw``: m and a unit
        quaternion x, y, z, w), then one column per joint by URDF name (rad or m).

        Args:
            full: every joint of the URDF (locked ones at their half-sitting angle); ``False``: moving joints only.
        """
        if full:
            names, q = self.robot.full_joint_names, self.q_full
        else:
            names, q = self.joint_names, self.q
        if q.shape[1] != len(BASE_COLUMNS) + len(names):
            # Continuous joints (two coordinates, cos and sin) have no single angle column.
            raise ValueError("the model has joints with more than one coordinate; no one-column-per-joint table")
        return ("t", *BASE_COLUMNS, *names), np.column_stack([self.times, q])


@dataclass(frozen=True)
class RobotWalk(Scenario):
    """A scenario as walked by one robot, whose :meth:`planner_config` carries the robot's bounds on walks by
    velocity command (the scenario format has no such fields: they belong to the robot, not to the walk).

    Attributes:
        velocity_limits: the robot description's ``[velocity]`` table; ``None``: the planner's defaults.
    """

    velocity_limits: VelocityLimits | None = None

    def planner_config(self) -> PlannerConfig:
        """The scenario's planner config with the robot's velocity-walk bounds, those of its timing's COG sway
        (:meth:`~rtgait.core.planner.config.VelocityLimits.apply`)."""
        config = super().planner_config()
        return config if self.velocity_limits is None else self.velocity_limits.apply(config)


def walking_robot(robot: RobotModel, scenario: Scenario) -> RobotModel:
    """``robot`` as it walks ``scenario``: its description's ``walking.cog_height`` and ``walking.toe_release``
    replaced by those the scenario's ``[walking.<name>]`` table asks of it (:mod:`rtgait.scenario.walking_table`).

    ``robot`` itself when the scenario asks nothing of it or asks its own values, so that a model built for the
    returned robot (a MuJoCo scene) is built for ``robot`` too, and applying it twice changes nothing.
    """
    entry = walking_for(scenario.walking, robot.name)
    if entry is None:
        return robot
    description = robot.description
    asked = {
        key: value
        for key, value in (("cog_height", entry.cog_height), ("toe_release", entry.toe_release))
        if value is not None and value != getattr(description, key)
    }
    if not asked:
        return robot
    return dataclasses.replace(robot, description=dataclasses.replace(description, **asked))


def robot_scenario(scenario: Scenario, robot: RobotModel) -> RobotWalk:
    """``scenario`` walked by ``robot``: its nominal COG height (or the one the scenario's ``[walking.<name>]`` asks
    of it, :func:`walking_robot`), its step width at half-sitting, its sole and, when
    its description has a ``[velocity]`` table, its bounds on walks by velocity command (:class:`RobotWalk`).

    Raises:
        RobotError: the description's ``velocity.min_step_width`` is wider than the robot's stance.
    """
    limits = robot.description.velocity
    for i, table in enumerate(() if limits is None else limits.every_table()):
        narrowest = table.min_step_width
        if narrowest is not None and narrowest > robot.step_width:
            key = "velocity.min_step_width" if i == 0 else f"velocity.more_sway[{i - 1}].min_step_width"
            raise RobotError(
                f"{key} ({narrowest:g} m) must be at most the stance of {robot.name} at half-sitting "
                f"({robot.step_width:.4f} m): it is the narrowest stance a sideways walk closes to"
            )
    values = {f.name: getattr(scenario, f.name) for f in dataclasses.fields(Scenario)}
    cog_height = walking_robot(robot, scenario).description.cog_height
    values.update(cog_height=cog_height, step_width=robot.step_width, sole=robot.description.sole)
    return RobotWalk(**values, velocity_limits=limits)


def _where(rollout: Rollout, k: int) -> str:
    """Which part of the walk tick ``k`` belongs to, in words (phases as in :mod:`rtgait.core.geometry.footsteps`)."""
    phase = int(rollout.phase[k])
    if phase == 0:
        return "the start of the walk"
    # Phase 2i - 1 is step i's single support, 2i the double support after it lands.
    return f"step {(phase + 1) // 2}"


def whole_body_motion(
    robot: RobotModel,
    rollout: Rollout,
    cog_offset: np.ndarray | None = None,
    *,
    iterations: int = 2,
    limits: dict[str, float] | None = None,
    ik: WholeBodyIK | None = None,
) -> JointTrajectory:
    """Joint trajectory of ``robot`` following the planned walk ``rollout``.

    The first tick is solved from half-sitting to convergence; every later tick makes ``iterations`` Gauss-Newton
    iterations from the previous tick's solution (always the same number, so the residual errors, micrometres,
    vary smoothly and finite differences of the motion stay clean).

    Args:
        robot: the robot.
        rollout: the planned walk (COG at constant height, feet poses per tick).
        cog_offset: optional ``(k, 2)`` offsets (m) added to the planned COG x and y, e.g. the angular-momentum
            compensation of the paper's Appendix A.
        iterations: Gauss-Newton iterations per tick after the first.
        limits: error limits overriding :data:`ERROR_LIMITS` (m or rad, same keys).
        ik: the solver to use (default: a :class:`~rtgait.robot.ik.WholeBodyIK` with default weights).

    Raises:
        UnreachableError: at the first tick whose IK error exceeds its limit, naming the step, time and error.
        ValueError: ``cog_offset`` of the wrong shape or not finite.
    """
    times = np.asarray(rollout.times, dtype=float)
    n = len(times)
    cog = rollout.values[:, SampleColumns.cog].copy()
    if cog_offset is not None:
        offset = np.asarray(cog_offset, dtype=float)
        if offset.shape != (n, 2):
            raise ValueError(f"cog_offset must have shape ({n}, 2) (one x, y offset per tick, m), got {offset.shape}")
        if not np.isfinite(offset).all():
            raise ValueError("cog_offset must be finite")
        cog[:, :2] += offset
    left = rollout.values[:, SampleColumns.left_foot].tolist()
    right = rollout.values[:, SampleColumns.right_foot].tolist()
    if is_tilted(rollout.footprints):  # soles turned to the footholds' surfaces (foot_tilt.py)
        tilted = [tilted_feet(rollout.footprints, a, b) for a, b in zip(left, right, strict=True)]
        left, right = [a for a, _ in tilted], [b for _, b in tilted]
    if changes_height(rollout.footprints):  # the rear heel rolls onto its toe before a step up or down (toe_off.py)
        front = robot.description.sole.front
        zmp = rollout.values[:, SampleColumns.zmp].tolist()
        if not is_tilted(rollout.footprints):
            left = [(*a[:4], 0.0, 0.0) for a in left]
            right = [(*b[:4], 0.0, 0.0) for b in right]
        release = robot.description.toe_release
        rolled = [
            toe_off_feet(rollout.footprints, front, a, b, z, release) for a, b, z in zip(left, right, zmp, strict=True)
        ]
        left, right = [a for a, _ in rolled], [b for _, b in rolled]
    cog_rows = cog.tolist()
    limit = dict(ERROR_LIMITS)
    if limits:
        unknown = set(limits) - set(ERROR_FIELDS)
        if unknown:
            raise ValueError(f"unknown error limit {sorted(unknown)[0]!r}: known are {', '.join(ERROR_FIELDS)}")
        limit.update(limits)
    limit_row = np.array([limit.get(name, np.inf) for name in ERROR_FIELDS])
    solver = ik or WholeBodyIK(robot)
    if solver.robot is not robot:
        raise ValueError(f"the IK solver was built for robot {solver.robot.name!r}, not this {robot.name!r} model")

    q_out = np.empty((n, robot.model.nq))
    errors = np.empty((n, len(ERROR_FIELDS)))
    used = np.empty(n, dtype=int)
    q = robot.q_half_sitting
    for k in range(n):
        targets = IKTargets(cog_rows[k], left[k], right[k])
        if k == 0:
            # From half-sitting to the walk's first pose (the COG lowered to the walking height): many steps.
            q, result = solver.solve(targets, q, max_iterations=200, tolerance=1e-7)
        else:
            q, result = solver.solve(targets, q, max_iterations=iterations, tolerance=0.0)
        q_out[k] = q
        row = errors[k]
        row[:] = result[: len(ERROR_FIELDS)]
        used[k] = result.iterations
        if (row > limit_row).any():
            worst = int(np.argmax(row / limit_row))
            name = ERROR_FIELDS[worst]
            unit = "rad" if "orientation" in name else "m"
            raise UnreachableError(
                f"{_where(rollout, k)} at t={times[k]:.3f} s is out of reach for {robot.name}: "
                f"{_LABELS[name]} {row[worst]:.3f} {unit} (limit {limit_row[worst]} {unit})"
            )
    return JointTrajectory(robot=robot, times=times, q=q_out, cog_target=cog, errors=errors, iterations=used)
