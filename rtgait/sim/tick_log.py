"""The complete per-tick record of a walk in physics, beyond what :class:`~rtgait.sim.result.SimResult` keeps.

:class:`TickLog` preallocates every array once and fills one row per control tick with :meth:`TickLog.record`
(no allocation per tick: row assignments into the arrays and one MuJoCo call, ``mj_subtreeVel``);
:meth:`TickLog.finish` trims them to the ticks simulated and derives the rest with numpy, into a :class:`TickRecord`.

**Which instant.** :meth:`TickLog.record` is called right after the first physics step of tick ``k``: MuJoCo's
kinematics, velocities and actuator state then describe the state at the tick's time ``t`` (``mj_step`` computes them
for the state it starts from before integrating it), the same instant as the ZMP, COG, base pose and contacts that
:class:`~rtgait.sim.contact.ContactMonitor` records there. Measured at ``t``:

* joint positions and velocities: ``actuator_length / gear`` and ``actuator_velocity / gear`` (each actuator drives
  one joint through a joint transmission, so these are the joint's ``qpos`` and ``qvel``);
* the base's angular velocity ``w`` and the linear velocity of its origin ``p`` (world frame): MuJoCo's ``cvel`` of
  the base body is the spatial velocity ``(w, v_c)`` at the robot's subtree COM ``c``, so ``v_p = v_c + w x (p - c)``
  (``mj_objectVelocity`` would give the velocity at the base link's own centre of mass instead);
* the COM velocity, ``subtree_linvel`` of the base (``mj_subtreeVel``, the robot being the base's subtree);
* each sole frame's position and orientation (``site_xpos``, ``site_xmat``), turned into ``(x, y, z, yaw, pitch,
  roll)`` with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` as :mod:`rtgait.sim.measure` does.

The per-foot **contact wrench** and centre of pressure are the controller's own measurement of the tick
(:class:`~rtgait.sim.measure.Measurement`), which reads the contact forces of the last physics step, i.e. of the
state one physics step *before* ``t``: recording them costs nothing (measuring the contacts again at ``t`` would
cost as much as the controller's whole measurement, a tenth of a tick). They are NaN during the start transition,
when the controller does not measure yet.

Commanded at the tick: the joint velocity reference the servos were given (``ReferenceInterpolator.qd``), the IK's
sole targets ``(x, y, z, yaw)`` (the planner's feet with the controller's landing and force-control heights), the
support the controller acts on, its COM correction, the plan's COM velocity ``v = w (xi_plan - c_plan)`` (from the
plan's DCM ``xi_plan`` and COM ``c_plan``, the IK's COM target minus the correction), and the controller level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from rtgait.core.closed_loop import CONTROLLERS
from rtgait.sim.result import SUPPORT_CODES

if TYPE_CHECKING:
    from rtgait.sim.actuation import ReferenceInterpolator
    from rtgait.sim.control_settings import ControlTargets
    from rtgait.sim.measure import Measurement
    from rtgait.sim.model import SimModel

__all__ = ["LEVEL_CODES", "TickLog", "TickRecord"]

LEVEL_CODES = {level: code for code, level in enumerate(CONTROLLERS)}
"""Controller level per tick in :attr:`TickRecord.level`: its index in :data:`rtgait.core.closed_loop.CONTROLLERS`."""

# Columns of the per-tick scalar table, written with one assignment per tick.
_FOOT = 9  # force x, y, z (N), torque x, y, z (N m), CoP x, y (m), loaded (0/1): per foot, left then right
_PLAN = 2 * _FOOT  # COM correction x, y (m), planned COM velocity x, y (m/s), support code, level code
_SCALARS = _PLAN + 6
_NAN_FEET = (math.nan,) * (2 * _FOOT)
_NAN_PLAN = (math.nan,) * 4


@dataclass(frozen=True, eq=False)
class TickRecord:
    """What :class:`TickLog` recorded, one row per simulated tick (``k`` rows; world frame, SI units).

    Attributes:
        joint_position: measured joint positions at the tick (rad), shape ``(k, n)``, in the simulation's
            ``joint_names`` order (the torques' order).
        joint_velocity: measured joint velocities (rad/s), shape ``(k, n)``.
        joint_velocity_command: the joint velocity references the servos were given (rad/s), shape ``(k, n)``.
        base_linear_velocity: the floating base's velocity at its origin (m/s), shape ``(k, 3)``.
        base_angular_velocity: its angular velocity (rad/s), world frame, shape ``(k, 3)``.
        cog_velocity: measured COM velocity (m/s), shape ``(k, 3)``.
        sole_pose: each sole frame's ``(x, y, z, yaw, pitch, roll)`` (m, rad), shape ``(k, 2, 6)``, left then right.
        foot_target: the IK's sole targets ``(x, y, z, yaw)`` (m, rad), shape ``(k, 2, 4)``.
        force: contact force of the ground on each foot (N), shape ``(k, 2, 3)``; one physics step before the tick
            (module docstring); NaN during the start transition.
        torque: its moment about the sole frame's origin (N m), shape ``(k, 2, 3)``; likewise.
        cop: each foot's centre of pressure on the ground (m), shape ``(k, 2, 2)``; NaN when the foot is unloaded.
        loaded: each foot's load state after the measurer's hysteresis, shape ``(k, 2)``.
        com_offset: the controller's COM correction (m), shape ``(k, 2)``; NaN during the start transition.
        cog_velocity_planned: the plan's COM velocity (m/s), shape ``(k, 2)``; NaN during the start transition.
        support_control: the support the controller acts on, codes :data:`~rtgait.sim.result.SUPPORT_CODES`,
            shape ``(k,)``; double during the start transition.
        level: the controller level, codes :data:`LEVEL_CODES`, shape ``(k,)``.
        omega: the planner's ``w = sqrt(g / z_c)`` (1/s), for the measured DCM ``c + c'/w``.
        contact_lag: how long before the tick the contact wrench was measured (s): one physics step.
    """

    joint_position: np.ndarray
    joint_velocity: np.ndarray
    joint_velocity_command: np.ndarray
    base_linear_velocity: np.ndarray
    base_angular_velocity: np.ndarray
    cog_velocity: np.ndarray
    sole_pose: np.ndarray
    foot_target: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    cop: np.ndarray
    loaded: np.ndarray
    com_offset: np.ndarray
    cog_velocity_planned: np.ndarray
    support_control: np.ndarray
    level: np.ndarray
    omega: float
    contact_lag: float


def _euler(rotation: np.ndarray) -> np.ndarray:
    """``(yaw, pitch, roll)`` (rad) of row-major rotation matrices ``(..., 9)``, ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    yaw = np.arctan2(rotation[..., 3], rotation[..., 0])
    pitch = np.arcsin(np.clip(-rotation[..., 6], -1.0, 1.0))
    roll = np.arctan2(rotation[..., 7], rotation[..., 8])
    return np.stack([yaw, pitch, roll], axis=-1)


class TickLog:
    """Preallocated per-tick record of a closed-loop run (module docstring).

    Args:
        sim: the simulated robot.
        data: the MuJoCo state the run steps (its fixed-size arrays are read through views kept here).
        servo: the joint servos' reference interpolator, read for the commanded joint velocities.
        n_ticks: rows to allocate.
        omega: the planner's pendulum frequency (1/s).
    """

    def __init__(
        self, sim: SimModel, data: mujoco.MjData, servo: ReferenceInterpolator, n_ticks: int, omega: float
    ) -> None:
        model = sim.model
        nu = model.nu
        self._model, self._data, self._servo = model, data, servo
        self._base = sim.base_body
        self._sites = (sim.left_sole_site, sim.right_sole_site)
        self._gear = model.actuator_gear[:, 0].copy()
        self.omega = float(omega)
        self.physics_dt = float(sim.timestep)
        self._joints = np.full((n_ticks, 3, nu), math.nan)  # position, velocity, velocity reference
        self._velocity = np.full((n_ticks, 6), math.nan)  # cvel of the base: angular, then linear at the COM
        self._points = np.full((n_ticks, 2, 3), math.nan)  # the base's origin and the robot's COM
        self._cog_velocity = np.full((n_ticks, 3), math.nan)
        self._sole_position = np.full((n_ticks, 2, 3), math.nan)
        self._sole_rotation = np.full((n_ticks, 2, 9), math.nan)
        self._targets = np.full((n_ticks, 2, 4), math.nan)
        self._scalars = np.full((n_ticks, _SCALARS), math.nan)
        # Views of MuJoCo's fixed-size arrays stay valid for the life of ``data``.
        self._length, self._actuator_velocity = data.actuator_length, data.actuator_velocity
        self._site_xpos, self._site_xmat, self._subtree_linvel = data.site_xpos, data.site_xmat, data.subtree_linvel
        self._cvel, self._xpos, self._subtree_com = data.cvel, data.xpos, data.subtree_com
        self._root = int(model.body_rootid[self._base])

    def record(
        self,
        k: int,
        left_foot: tuple[float, float, float, float] | list[float],
        right_foot: tuple[float, float, float, float] | list[float],
        targets: ControlTargets | None,
        measurement: Measurement | None,
        level: str,
    ) -> None:
        """Record tick ``k``, right after its first physics step: the IK's sole targets ``(x, y, z, yaw)`` (m, rad),
        the controller's output and measurement (``None`` during the start transition) and its level."""
        model, data = self._model, self._data
        rows = self._joints[k]
        rows[0] = self._length
        rows[1] = self._actuator_velocity
        rows[2] = self._servo.qd
        base = self._base
        self._velocity[k] = self._cvel[base]
        points = self._points[k]
        points[0], points[1] = self._xpos[base], self._subtree_com[self._root]
        mujoco.mj_subtreeVel(model, data)
        self._cog_velocity[k] = self._subtree_linvel[base]
        left, right = self._sites
        position, rotation = self._sole_position[k], self._sole_rotation[k]
        position[0], position[1] = self._site_xpos[left], self._site_xpos[right]
        rotation[0], rotation[1] = self._site_xmat[left], self._site_xmat[right]
        target = self._targets[k]
        target[0], target[1] = left_foot, right_foot
        if measurement is None:
            feet = _NAN_FEET
        else:
            lf, rf = measurement.left, measurement.right
            feet = (*lf.force, *lf.torque, *lf.cop, lf.loaded, *rf.force, *rf.torque, *rf.cop, rf.loaded)
        if targets is None:
            plan, support = _NAN_PLAN, 0
        else:
            (cx, cy, _), (dx, dy) = targets.com, targets.com_offset
            xi_x, xi_y = targets.dcm_planned
            w = self.omega
            plan, support = (dx, dy, w * (xi_x - (cx - dx)), w * (xi_y - (cy - dy))), SUPPORT_CODES[targets.support]
        self._scalars[k] = (*feet, *plan, support, LEVEL_CODES[level])

    def finish(self, ticks: int) -> TickRecord:
        """The record of the first ``ticks`` ticks, with the derived quantities (module docstring)."""
        joints = self._joints[:ticks]
        gear = self._gear
        scalars = self._scalars[:ticks]
        feet = scalars[:, :_PLAN].reshape(ticks, 2, _FOOT)
        rotation = self._sole_rotation[:ticks]
        sole_pose = np.concatenate([self._sole_position[:ticks], _euler(rotation)], axis=-1)
        velocity = self._velocity[:ticks]
        points = self._points[:ticks]
        angular = velocity[:, 0:3]
        linear = velocity[:, 3:6] + np.cross(angular, points[:, 0] - points[:, 1])
        return TickRecord(
            joint_position=joints[:, 0] / gear,
            joint_velocity=joints[:, 1] / gear,
            joint_velocity_command=joints[:, 2].copy(),
            base_linear_velocity=linear,
            base_angular_velocity=angular.copy(),
            cog_velocity=self._cog_velocity[:ticks].copy(),
            sole_pose=sole_pose,
            foot_target=self._targets[:ticks].copy(),
            force=feet[:, :, 0:3].copy(),
            torque=feet[:, :, 3:6].copy(),
            cop=feet[:, :, 6:8].copy(),
            loaded=feet[:, :, 8] == 1.0,
            com_offset=scalars[:, _PLAN : _PLAN + 2].copy(),
            cog_velocity_planned=scalars[:, _PLAN + 2 : _PLAN + 4].copy(),
            support_control=scalars[:, _PLAN + 4].astype(np.int8),
            level=scalars[:, _PLAN + 5].astype(np.int8),
            omega=self.omega,
            contact_lag=self.physics_dt,
        )
