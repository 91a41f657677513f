"""The complete per-tick record of a walk in physics, beyond what :class:`~rtgait.sim.result.SimResult` keeps.

:class:`TickLog` preallocates every array once and fills one row per control tick with :meth:`TickLog.record`
(no allocation per tick beyond a few Python floats: five row copies, one ``struct`` packing into a preallocated
table, one MuJoCo call, ``mj_subtreeVel``);
:meth:`TickLog.finish` trims them to the ticks simulated and derives the rest with numpy, into a :class:`CompleteLog`.

**Which instant.** :meth:`TickLog.record` is called right after the first physics step of tick ``k``: MuJoCo's
kinematics, velocities and actuator state then describe the state at the tick's time ``t`` (``mj_step`` computes them
for the state it starts from before integrating it), the same instant as the ZMP, COG, base pose and contacts that
:class:`~rtgait.sim.contact.ContactMonitor` records there. Measured at ``t``:

* joint positions and velocities: ``actuator_length / gear`` and ``actuator_velocity / gear`` (each actuator drives
  one joint through a joint transmission, so these are the joint's ``qpos`` and ``qvel``);
* the base's spatial velocity, MuJoCo's ``cvel`` of the base body: its angular velocity ``w`` and the velocity ``v_c``
  of its point at the robot's COM ``c`` (world frame); the base origin ``p`` moves at ``v_p = v_c + w x (p - c)``
  (:meth:`CompleteLog.base_velocity`; ``mj_objectVelocity`` would give the base link's centre of mass instead);
* the COM velocity, ``subtree_linvel`` of the base (``mj_subtreeVel``, the robot being the base's subtree);
* each sole frame's position and orientation (``site_xpos``, ``site_xmat``), turned into ``(x, y, z, yaw, pitch,
  roll)`` with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` as :mod:`rtgait.sim.measure` does.

The per-foot **contact wrench** and centre of pressure are the controller's own measurement of the tick
(:class:`~rtgait.estimation.state.Measurement`), which reads the contact forces of the last physics step, i.e. of the
state one physics step *before* ``t``: recording them costs nothing (measuring the contacts again at ``t`` would
cost as much as the controller's whole measurement, a tenth of a tick). They are NaN during the start transition,
when the controller does not measure yet.

Commanded at the tick: the joint velocity reference the servos were given (``Drives.qd``), the IK's
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

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.core.geometry.support import SUPPORT_CODES
from rtgait.core.planner.levels import CONTROLLER_LEVELS
from rtgait.estimation.feet import soles_plane
from rtgait.sim.estimation_errors import StateTrack
from rtgait.sim.row_packing import row_packer

if TYPE_CHECKING:
    from rtgait.control.settings import ControlTargets
    from rtgait.estimation.state import Measurement
    from rtgait.interface.truth import GroundTruth
    from rtgait.sim.drives import Drives
    from rtgait.sim.model import SimModel

__all__ = ["LEVEL_CODES", "CompleteLog", "TickLog"]

LEVEL_CODES = {level: code for code, level in enumerate(CONTROLLER_LEVELS)}
"""Controller level per tick in :attr:`CompleteLog.level`: its index in
:data:`rtgait.core.planner.levels.CONTROLLER_LEVELS`."""

# The per-tick scalars, packed into one row of a float64 table with one ``struct`` call (a numpy assignment from a
# tuple of Python floats costs several times more): COM velocity (3), base spatial velocity (6), IK sole targets
# (2 x 4), per foot force (3), torque (3), CoP (2) and load (1), then COM correction (2), planned COM velocity (2),
# the planner's phase, support code, level code; then the estimate's COM (3), COM velocity (3), DCM (2), sole
# positions (2 x 3) and ZMP (2), and the truth's COM, COM velocity and sole positions of the same instant with the
# feet's true vertical forces (2) and their moment about the world's origin, x and y (2).
_COG_VELOCITY = 0
_BASE_VELOCITY = 3
_TARGETS = 9
_FEET = 17
_FOOT = 9
_PLAN = _FEET + 2 * _FOOT
_ESTIMATE = _PLAN + 7
_TRUTH = _ESTIMATE + 16
_SCALARS = _TRUTH + 16
_NAN_FEET = (math.nan,) * (2 * _FOOT)
_NAN_PLAN = (math.nan,) * 4
_NAN_ESTIMATE = (math.nan,) * 16
_NAN_TRUTH = (math.nan,) * 16


@dataclass(frozen=True, eq=False)
class CompleteLog:
    """What :class:`TickLog` recorded, one row per simulated tick (``k`` rows; world frame, SI units).

    Attributes:
        joint_position: measured joint positions at the tick (rad), shape ``(k, n)``, in the simulation's
            ``joint_names`` order (the torques' order).
        joint_velocity: measured joint velocities (rad/s), shape ``(k, n)``.
        joint_velocity_command: the joint velocity references the servos were given (rad/s), shape ``(k, n)``.
        base_spatial_velocity: MuJoCo's ``cvel`` of the base, ``(w, v_c)``: its angular velocity (rad/s) and the
            velocity of the point fixed to it at the robot's COM (m/s), world frame, shape ``(k, 6)``;
            :meth:`base_velocity` moves it to the base's origin.
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
        phase: the planner's phase index (0: the standing start, odd: single supports), -1 during the start
            transition, shape ``(k,)``.
        support_control: the support the controller acts on, codes
            :data:`~rtgait.core.geometry.support.SUPPORT_CODES`,
            shape ``(k,)``; double during the start transition.
        level: the controller level, codes :data:`LEVEL_CODES`, shape ``(k,)``.
        estimate: the controller's measurement of the COM, its velocity, the DCM, the soles' positions, the feet's
            vertical forces and load states (:class:`~rtgait.sim.estimation_errors.StateTrack`), one physics step
            before the tick like the wrench; NaN during the start transition. The estimator's, or with
            ``state="truth"`` the simulator's.
        truth: the simulator's truth of that same instant (its load states are not recorded: the comparison
            derives them from its forces); NaN during the start transition.
        sole: the robot's sole rectangle around the sole frame (m).
        omega: the planner's ``w = sqrt(g / z_c)`` (1/s), for the measured DCM ``c + c'/w``.
        contact_lag: how long before the tick the contact wrench was measured (s): one physics step.
    """

    joint_position: np.ndarray
    joint_velocity: np.ndarray
    joint_velocity_command: np.ndarray
    base_spatial_velocity: np.ndarray
    cog_velocity: np.ndarray
    sole_pose: np.ndarray
    foot_target: np.ndarray
    force: np.ndarray
    torque: np.ndarray
    cop: np.ndarray
    loaded: np.ndarray
    com_offset: np.ndarray
    cog_velocity_planned: np.ndarray
    phase: np.ndarray
    support_control: np.ndarray
    level: np.ndarray
    estimate: StateTrack
    truth: StateTrack
    sole: SoleRect
    omega: float
    contact_lag: float

    def base_velocity(self, base_position: np.ndarray, cog: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The base's linear velocity at its origin ``v_p = v_c + w x (p - c)`` (m/s) and its angular velocity ``w``
        (rad/s), world frame, each ``(k, 3)``, from the base origin ``p`` and the COM ``c`` at the ticks (m,
        ``(k, 3)``: :attr:`SimResult.base_position` and :attr:`SimResult.cog`)."""
        angular = self.base_spatial_velocity[:, 0:3]
        linear = self.base_spatial_velocity[:, 3:6] + np.cross(angular, base_position - cog)
        return linear, angular.copy()


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
        servo: the joints' drives, read for the velocity reference they apply.
        n_ticks: rows to allocate.
        omega: the planner's pendulum frequency (1/s).
    """

    def __init__(self, sim: SimModel, data: mujoco.MjData, servo: Drives, n_ticks: int, omega: float) -> None:
        model = sim.model
        nu = model.nu
        self._model, self._data, self._servo = model, data, servo
        self._sites = (sim.left_sole_site, sim.right_sole_site)
        self._gear = model.actuator_gear[:, 0].copy()
        self.omega = float(omega)
        self.sole = sim.robot.description.sole
        self.physics_dt = float(sim.timestep)
        # The ground-truth estimator's least force for a ZMP: 0.1 % of the weight.
        self._min_force = 1e-3 * float(sim.robot.mass * -model.opt.gravity[2])
        self._joints = np.full((n_ticks, 3, nu), math.nan)  # position, velocity, velocity reference
        # Every site (the model has the two sole sites only, so one assignment copies both).
        self._sites_position = np.full((n_ticks, model.nsite, 3), math.nan)
        self._sites_rotation = np.full((n_ticks, model.nsite, 9), math.nan)
        self._scalars = np.full((n_ticks, _SCALARS), math.nan)
        self._pack, self._buffer, self._row_bytes = row_packer(self._scalars)
        # Views of MuJoCo's fixed-size arrays stay valid for the life of ``data``.
        self._length, self._actuator_velocity = data.actuator_length, data.actuator_velocity
        self._site_xpos, self._site_xmat = data.site_xpos, data.site_xmat
        # The base's rows, kept as views too (indexing costs as much as reading them).
        self._base_linvel, self._base_cvel = data.subtree_linvel[sim.base_body], data.cvel[sim.base_body]

    def record(
        self,
        k: int,
        left_foot: tuple[float, float, float, float] | list[float],
        right_foot: tuple[float, float, float, float] | list[float],
        targets: ControlTargets | None,
        measurement: Measurement | None,
        level: str,
        truth: GroundTruth | None = None,
    ) -> None:
        """Record tick ``k``, right after its first physics step: the IK's sole targets ``(x, y, z, yaw)`` (m, rad),
        the controller's output and measurement (``None`` during the start transition), its level and the
        simulator's truth of the measurement's instant (``None``: not known, NaN)."""
        rows = self._joints[k]
        rows[0] = self._length
        rows[1] = self._actuator_velocity
        rows[2] = self._servo.qd
        self._sites_position[k] = self._site_xpos
        self._sites_rotation[k] = self._site_xmat
        mujoco.mj_subtreeVel(self._model, self._data)
        if measurement is None:
            feet, estimate = _NAN_FEET, _NAN_ESTIMATE
        else:
            lf, rf = measurement.left, measurement.right
            feet = (*lf.force, *lf.torque, *lf.cop, lf.loaded, *rf.force, *rf.torque, *rf.cop, rf.loaded)
            (lx, ly, lz, _), (rx, ry, rz, _) = lf.pose, rf.pose
            estimate = (*measurement.com, *measurement.com_vel, *measurement.dcm, lx, ly, lz, rx, ry, rz,
                        *measurement.zmp)  # fmt: skip
        if truth is None:
            true: tuple[float, ...] = _NAN_TRUTH
        else:
            left, right = truth.left, truth.right
            (lfx, lfy, lfz), (rfx, rfy, rfz) = left.force, right.force
            # The moment about the soles' plane's (0, 0, h): M - (0, 0, h) x F, its ZMP read off in finish().
            h = soles_plane(lfz, left.sole_position[2], rfz, right.sole_position[2])
            true = (*truth.com, *truth.com_vel, *left.sole_position, *right.sole_position, lfz, rfz,
                    left.moment[0] + right.moment[0] + h * (lfy + rfy),
                    left.moment[1] + right.moment[1] - h * (lfx + rfx))  # fmt: skip
        if targets is None:
            plan: tuple[float, ...] = _NAN_PLAN
            phase, support = -1, 0
        else:
            (cx, cy, _), (dx, dy) = targets.com, targets.com_offset
            xi_x, xi_y = targets.dcm_planned
            w = self.omega
            plan = (dx, dy, w * (xi_x - (cx - dx)), w * (xi_y - (cy - dy)))
            phase, support = targets.phase, SUPPORT_CODES[targets.support]
        self._pack(
            self._buffer, k * self._row_bytes, *self._base_linvel.tolist(), *self._base_cvel.tolist(),
            *left_foot, *right_foot, *feet, *plan, phase, support, LEVEL_CODES[level], *estimate, *true,
        )  # fmt: skip

    def finish(self, ticks: int) -> CompleteLog:
        """The record of the first ``ticks`` ticks, with the derived quantities (module docstring)."""
        joints = self._joints[:ticks]
        gear = self._gear
        scalars = self._scalars[:ticks]
        feet = scalars[:, _FEET:_PLAN].reshape(ticks, 2, _FOOT)
        sites = list(self._sites)
        position, rotation = self._sites_position[:ticks, sites], self._sites_rotation[:ticks, sites]
        plan = scalars[:, _PLAN:_ESTIMATE]
        return CompleteLog(
            joint_position=joints[:, 0] / gear,
            joint_velocity=joints[:, 1] / gear,
            joint_velocity_command=joints[:, 2].copy(),
            base_spatial_velocity=scalars[:, _BASE_VELOCITY:_TARGETS].copy(),
            cog_velocity=scalars[:, _COG_VELOCITY:_BASE_VELOCITY].copy(),
            sole_pose=np.concatenate([position, _euler(rotation)], axis=-1),
            foot_target=scalars[:, _TARGETS:_FEET].reshape(ticks, 2, 4).copy(),
            force=feet[:, :, 0:3].copy(),
            torque=feet[:, :, 3:6].copy(),
            cop=feet[:, :, 6:8].copy(),
            loaded=feet[:, :, 8] == 1.0,
            com_offset=plan[:, 0:2].copy(),
            cog_velocity_planned=plan[:, 2:4].copy(),
            phase=plan[:, 4].astype(np.int32),
            support_control=plan[:, 5].astype(np.int8),
            level=plan[:, 6].astype(np.int8),
            estimate=self._estimate(scalars[:, _ESTIMATE:_TRUTH], feet),
            truth=self._truth(scalars[:, _TRUTH:]),
            sole=self.sole,
            omega=self.omega,
            contact_lag=self.physics_dt,
        )

    def _estimate(self, columns: np.ndarray, feet: np.ndarray) -> StateTrack:
        """The controller's measurement's track from its columns and the feet's wrench columns."""
        return StateTrack(
            com=columns[:, 0:3].copy(),
            com_velocity=columns[:, 3:6].copy(),
            dcm=columns[:, 6:8].copy(),
            soles=columns[:, 8:14].reshape(-1, 2, 3).copy(),
            normal_force=feet[:, :, 2].copy(),
            loaded=feet[:, :, 8] == 1.0,
            zmp=columns[:, 14:16].copy(),
        )

    def _truth(self, columns: np.ndarray) -> StateTrack:
        """The truth's track; its load states are left to the comparison, which starts the hysteresis where it
        starts comparing (:func:`~rtgait.sim.estimation_errors.estimation_errors`)."""
        com, velocity = columns[:, 0:3].copy(), columns[:, 3:6].copy()
        force = columns[:, 12:14].copy()
        total = force.sum(axis=1)
        # The ZMP on the soles' plane of the feet's wrenches, as the ground-truth estimator makes it
        # (rtgait.estimation.feet): (-M_y, M_x) / F_z of their moment about (0, 0, h), NaN below its least force.
        with np.errstate(invalid="ignore", divide="ignore"):
            zmp = np.column_stack([-columns[:, 15], columns[:, 14]]) / total[:, None]
        zmp[~(total > self._min_force)] = math.nan
        return StateTrack(
            com=com,
            com_velocity=velocity,
            dcm=com[:, 0:2] + velocity[:, 0:2] / self.omega,
            soles=columns[:, 6:12].reshape(-1, 2, 3).copy(),
            normal_force=force,
            loaded=None,
            zmp=zmp,
        )
