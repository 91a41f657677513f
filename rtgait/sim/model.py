"""The MuJoCo model of a robot, built at run time from its robot description.

What the importer gets from the URDF and what is changed (:mod:`rtgait.sim.urdf_import`):

* ``package://`` mesh URIs are resolved under the description's ``package_dirs``, and MuJoCo's URDF extension keeps
  the paths and the visual meshes and takes the inertia from the ``<inertial>`` elements only (as Pinocchio does),
  so both see the same mass distribution.
* Meshes are visual only: the URDF's collision meshes overlap at the joints, and a walking foot must touch the floor
  through its sole. What touches what is built by :mod:`rtgait.sim.contact_model`: one box per sole (the described
  sole rectangle), the only thing that touches the floor, and convex shapes of the leg links, which collide with
  the other leg's.
* The root link gets a free joint (the URDF has a fixed base).
* Visual meshes MuJoCo cannot decode (:data:`MESH_FORMATS`) are left out with one :class:`MeshSkippedWarning`;
  ``<mimic>`` couplings are dropped (every joint is locked or has its own servo).
* Every joint outside ``walking.moving_joints`` is locked at its half-sitting angle, as the whole-body IK treats it:
  fewer degrees of freedom, cheaper physics steps.
* Each moving joint gets a drive with its gains (``config.gains``), torque limit and armature
  (:mod:`rtgait.sim.actuation`, :mod:`rtgait.sim.drives`); with ``config.motor_model``, its motor's torque-speed
  envelope and the gears' friction, replacing the URDF's ``<dynamics>`` (:mod:`rtgait.sim.motors`).
* The sensors of the description's ``[sensors]``: sites at their frames and MuJoCo's sensors on them
  (:mod:`rtgait.sim.sensor_sites`); massless, they change nothing in the physics.
* With ``config.model_error``, the robot differs from the model the controller has of it: masses, centres of mass
  and joint zeros drawn from that seed, and with the motor model its joints' friction (:mod:`rtgait.sim.model_error`).
* The ``implicitfast`` integrator: the servo damping is integrated implicitly, which keeps stiff, heavily damped
  servos on light links stable at a millisecond step.

Configurations: Pinocchio's free flyer is ``(x, y, z, qx, qy, qz, qw)``, MuJoCo's free joint ``(x, y, z, qw, qx,
qy, qz)``; joints are matched by URDF name, never by order.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from rtgait.core.geometry.terrain import TerrainKind
from rtgait.core.obstacle.box import Obstacle
from rtgait.robot.description import RobotError
from rtgait.robot.model import RobotModel
from rtgait.sim.actuation import Actuation, add_actuators, own_gains, resolve_actuation
from rtgait.sim.config import SimConfig
from rtgait.sim.contact_model import add_floor, add_leg_shapes, add_sole, exclude_pairs, touching_pairs
from rtgait.sim.model_error import ModelError, apply_friction_error, apply_model_error, draw
from rtgait.sim.motors import MotorModel, add_friction, resolve_motors
from rtgait.sim.obstacles import add_obstacles
from rtgait.sim.sensor_sites import SensorLayout, add_sensors
from rtgait.sim.terrain import add_terrain
from rtgait.sim.urdf_import import MESH_FORMATS, MeshSkippedWarning, compile_spec, lock_joint, urdf_for_mujoco

__all__ = ["MESH_FORMATS", "SETTLE_TIME", "MeshSkippedWarning", "SimConfig", "SimModel", "build_sim_model"]

SETTLE_TIME = 0.2
"""Physics time (s) a fresh state stands still before its clock starts (see :meth:`SimModel.reset`)."""


@dataclass(frozen=True, eq=False)
class SimModel:
    """A compiled MuJoCo model of a robot and the indices the closed loop needs.

    Attributes:
        robot: the Pinocchio robot it was built from (the IK works on ``robot.model``).
        config: the physics parameters.
        model: the compiled MuJoCo model.
        joint_names: the moving joints, in the order of ``robot.joint_names`` (Pinocchio's reduced model).
        qpos_index: MuJoCo ``qpos`` address of each joint of ``joint_names``.
        dof_index: MuJoCo ``qvel`` address of each joint of ``joint_names``.
        actuation: the joint servos (gains, armature, torque limits, control period and physics step); actuator
            ``i`` drives joint ``i`` of ``joint_names``.
        base_body: MuJoCo body id of the floating base (the URDF's root link).
        left_sole_geom, right_sole_geom: geom ids of the sole contact boxes.
        left_sole_site, right_sole_site: site ids at the sole points (the description's sole frames).
        floor_geom: geom id of the floor plane.
        leg_geoms: geom ids of the leg shapes, left leg's then right leg's (empty without leg collisions).
        excluded_leg_pairs: MuJoCo body names of the left and right leg links whose shapes touch at half-sitting and
            are therefore excluded from colliding.
        qpos_half_sitting: MuJoCo configuration at half-sitting, soles on the floor (m, unit quaternion, rad).
        sensors: where the robot's sensors are in ``data.sensordata`` (:mod:`rtgait.sim.sensor_sites`).
        model_error: how the simulated robot differs from ``robot`` (:mod:`rtgait.sim.model_error`; ``model`` has
            its masses and COMs, :attr:`encoder_offsets` its joint zeros), or ``None``: it does not.
        motors: the drives' motors (:mod:`rtgait.sim.motors`), or ``None``: ideal drives (``config.motor_model``
            false).
        terrain: the terrain built into the scene (:mod:`rtgait.sim.terrain`), or ``None``: the flat floor.
    """

    robot: RobotModel
    config: SimConfig
    model: mujoco.MjModel
    joint_names: tuple[str, ...]
    qpos_index: np.ndarray
    dof_index: np.ndarray
    actuation: Actuation
    base_body: int
    left_sole_geom: int
    right_sole_geom: int
    left_sole_site: int
    right_sole_site: int
    floor_geom: int
    qpos_half_sitting: np.ndarray
    leg_geoms: tuple[int, ...] = ()
    excluded_leg_pairs: tuple[tuple[str, str], ...] = ()
    sensors: SensorLayout | None = None
    model_error: ModelError | None = None
    motors: MotorModel | None = None
    terrain: TerrainKind | None = None

    @property
    def timestep(self) -> float:
        """Physics step (s)."""
        return float(self.model.opt.timestep)

    @property
    def control_dt(self) -> float:
        """Control period (s): the closed loop's tick."""
        return self.actuation.control_dt

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        return self.actuation.substeps

    @property
    def command_delay(self) -> int:
        """Control periods between writing a joint command and the drives' applying it (``config.command_delay``)."""
        return int(self.config.command_delay or 0)

    @property
    def kp(self) -> np.ndarray:
        """Position gains per joint of ``joint_names`` (N m/rad)."""
        return self.actuation.kp

    @property
    def kd(self) -> np.ndarray:
        """Damping gains per joint of ``joint_names`` (N m s/rad)."""
        return self.actuation.kd

    @property
    def encoder_offsets(self) -> np.ndarray | None:
        """Encoder reading - true angle of each joint of ``joint_names`` (rad; the model error's joint zeros), or
        ``None`` without a model error. A drive holding ``q_ref`` holds the joint at ``q_ref - offset``."""
        return None if self.model_error is None else self.model_error.joint_offsets

    def qpos_from_pinocchio(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """MuJoCo ``qpos`` from a configuration of the robot's reduced Pinocchio model.

        Args:
            q: ``(x, y, z, qx, qy, qz, qw, joints...)`` in ``robot.joint_names`` order (m, rad).
            out: array of shape ``(model.nq,)`` to fill (e.g. ``data.qpos``); a new one when ``None``.
        """
        if out is None:
            out = np.empty(self.model.nq)
        out[0:3] = q[0:3]
        out[3] = q[6]
        out[4:7] = q[3:6]
        out[self.qpos_index] = q[7:]
        return out

    def pinocchio_from_qpos(self, qpos: np.ndarray) -> np.ndarray:
        """Reduced Pinocchio configuration from a MuJoCo ``qpos`` (the inverse of :meth:`qpos_from_pinocchio`)."""
        q = np.empty(self.robot.model.nq)
        q[0:3] = qpos[0:3]
        q[3:6] = qpos[4:7]
        q[6] = qpos[3]
        q[7:] = qpos[self.qpos_index]
        return q

    def full_configurations(self, qpos: np.ndarray) -> np.ndarray:
        """Configurations of the robot's FULL Pinocchio model from MuJoCo ``qpos`` rows (for the 3D replay).

        The free joint's quaternion is reordered from ``(qw, qx, qy, qz)`` to ``(qx, qy, qz, qw)``, the moving
        joints are taken by name (:attr:`qpos_index`), and the joints locked in MuJoCo get their half-sitting
        angle, at which the model builder locked them.

        Args:
            qpos: shape ``(model.nq,)`` or ``(k, model.nq)`` (m, unit quaternion, rad).

        Returns:
            shape ``(full nq,)`` or ``(k, full nq)`` in ``robot.full_model``'s order (m, unit quaternion, rad).
        """
        qpos = np.asarray(qpos, dtype=float)
        if qpos.shape[-1] != self.model.nq:
            raise ValueError(f"qpos must have {self.model.nq} coordinates per row, got shape {qpos.shape}")
        q = np.empty((*qpos.shape[:-1], self.robot.model.nq))
        q[..., 0:3] = qpos[..., 0:3]
        q[..., 3:6] = qpos[..., 4:7]
        q[..., 6] = qpos[..., 3]
        q[..., 7:] = qpos[..., self.qpos_index]
        return self.robot.full_configuration(q)

    def new_data(self, settle: float = SETTLE_TIME, q: np.ndarray | None = None) -> mujoco.MjData:
        """Fresh simulation state at rest with the soles on the floor and the servos holding the posture.

        Args:
            settle: physics time (s) to let the robot sink into the soft contact before time 0 (see :meth:`reset`).
            q: configuration of the robot's reduced Pinocchio model to start from; default half-sitting.
        """
        data = mujoco.MjData(self.model)
        self.reset(data, settle, q)
        return data

    def reset(self, data: mujoco.MjData, settle: float = SETTLE_TIME, q: np.ndarray | None = None) -> None:
        """Put ``data`` back to a standing start (time 0, at rest, no external forces, servo targets at the posture).

        Args:
            data: the state to reset.
            settle: physics time (s) simulated with the posture held before the clock is set to 0, so that the
                soles have sunk into the soft contact and the servos carry the weight: a run then starts from
                rest instead of from a small drop onto the floor. 0 starts with the soles exactly on the floor.
            q: configuration of the robot's reduced Pinocchio model to start from (soles on the floor); default
                half-sitting. With a model error the drives hold its joint angles in the model's convention, so the
                joints move by the encoder offsets while the robot settles on its soles, as a miscalibrated robot
                set down on the floor would.

        The settle holds the posture with the stiff gains (``SimConfig.gains = "stiff"``'s) whatever the drives' own:
        under the robot's gains, with no feed-forward torque yet, the legs would sag under the weight (G1's knees by
        a quarter radian, Talos's by 50 mrad) before the controller's first command, a start no robot lowered onto
        the floor has. The drives' own gains are put back before time 0.
        """
        if not (math.isfinite(settle) and settle >= 0.0):
            raise ValueError(f"settle must be a duration >= 0 s, got {settle}")
        model = self.model
        # The posture is held by the drives' own gains and at standstill, whatever a damping command left.
        own_gains(model, self.actuation)
        if self.motors is not None:
            self.motors.standstill(model.actuator_forcerange)
        mujoco.mj_resetData(model, data)
        if q is None:
            data.qpos[:] = self.qpos_half_sitting
        else:
            self.qpos_from_pinocchio(np.asarray(q, dtype=float), out=data.qpos)
        data.ctrl[:] = data.qpos[self.qpos_index]
        if self.model_error is not None:  # the drives servo their encoders, which read the joints + the offsets
            data.ctrl -= self.model_error.joint_offsets
        settling = round(settle / model.opt.timestep)
        if settling and self.config.gains != "stiff":
            stiff = resolve_actuation(self.robot, self.actuation.control_dt, self.actuation.physics_dt, "stiff")
            own_gains(model, stiff)
        for _ in range(settling):
            mujoco.mj_step(model, data)
        own_gains(model, self.actuation)
        data.qvel[:] = 0.0
        data.qacc_warmstart[:] = 0.0
        data.time = 0.0
        mujoco.mj_forward(model, data)


def _half_sitting_qpos(model: mujoco.MjModel, robot: RobotModel) -> np.ndarray:
    """MuJoCo ``qpos`` of the half-sitting configuration, joints by name (before a :class:`SimModel` exists)."""
    qpos = np.zeros(model.nq)
    q = robot.q_half_sitting
    qpos[0:3], qpos[3], qpos[4:7] = q[0:3], q[6], q[3:6]
    for i, name in enumerate(robot.joint_names):
        qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]] = q[7 + i]
    return qpos


def build_sim_model(
    robot: RobotModel | str,
    config: SimConfig | None = None,
    obstacles: Sequence[Obstacle] = (),
    terrain: TerrainKind | None = None,
) -> SimModel:
    """Build the MuJoCo model of ``robot`` (a loaded robot, or a built-in robot name / description file path), with
    a box geom for each of ``obstacles`` (:mod:`rtgait.sim.obstacles`) and the boxes of ``terrain`` on a floor
    lowered to its lowest level (:mod:`rtgait.sim.terrain`; ``None``: the flat floor).

    Raises:
        RobotError: the URDF cannot be read or MuJoCo cannot compile the edited model (message names the cause).
        ValueError: the control period (``config.control_dt`` or the description's) and the physics step do not
            fit (:func:`rtgait.sim.actuation.substeps`), a joint's resolved kp is not > 0, ``config.gains`` is
            ``"robot"`` and a joint has no robot gains, or ``config.motor_model`` and a joint has no motor type.
    """
    if not isinstance(robot, RobotModel):
        robot = RobotModel.load(robot)
    config = (config or SimConfig()).resolved(robot)
    description = robot.description
    try:
        spec = mujoco.MjSpec.from_string(urdf_for_mujoco(description, config.meshes))
    except ValueError as error:
        raise RobotError(f"model.urdf {description.urdf}: MuJoCo cannot read it: {error}") from None
    spec.modelname = description.name

    moving = set(robot.joint_names)
    for joint in list(spec.joints):
        if joint.name not in moving:
            lock_joint(spec, joint, description.posture_angle(joint.name))
    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 0, 0

    root = spec.worldbody.first_body()
    root.add_freejoint(name="root")
    for side in ("left", "right"):
        add_sole(spec, robot, side, root, config)
    add_floor(spec, config)
    if terrain is not None:
        add_terrain(spec, terrain, config)
    add_obstacles(spec, obstacles)
    shapes = add_leg_shapes(spec, robot) if config.leg_collisions else []
    actuation = resolve_actuation(robot, config.control_dt, config.physics_dt, config.gains)
    actuation = actuation.scaled(config.gain_scale, config.armature_scale)
    add_actuators(spec, actuation)
    motors = resolve_motors(robot, actuation) if config.motor_model else None
    if motors is not None:
        add_friction(spec, motors)
    add_sensors(spec, robot, root)

    spec.option.timestep = config.physics_dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.noslip_iterations = config.noslip_iterations
    model = compile_spec(spec, description)
    excluded: list[tuple[str, str]] = []
    if shapes:
        excluded = touching_pairs(model, _half_sitting_qpos(model, robot), shapes)
        if excluded:
            exclude_pairs(spec, excluded)
            model = compile_spec(spec, description)
    error = None
    if config.model_error is not None:
        reference = _half_sitting_qpos(model, robot)
        error = draw(config.model_error, model, robot.joint_names, reference=reference)
        apply_model_error(model, error)

    def ident(kind: mujoco.mjtObj, name: str) -> int:
        index = mujoco.mj_name2id(model, kind, name)
        if index < 0:  # pragma: no cover - every name looked up was added above
            raise RobotError(f"the MuJoCo model of {description.name} has no {kind.name} {name!r}")
        return int(index)

    joint_ids = [ident(mujoco.mjtObj.mjOBJ_JOINT, name) for name in robot.joint_names]
    qpos_index = np.array([model.jnt_qposadr[j] for j in joint_ids])
    dof_index = np.array([model.jnt_dofadr[j] for j in joint_ids])
    if error is not None and motors is not None:  # the joints' friction differs from the identified one too
        error = apply_friction_error(model, error, dof_index)
    base_body = int(model.jnt_bodyid[ident(mujoco.mjtObj.mjOBJ_JOINT, "root")])
    sim = SimModel(
        robot=robot,
        config=config,
        model=model,
        joint_names=robot.joint_names,
        qpos_index=qpos_index,
        dof_index=dof_index,
        actuation=actuation,
        base_body=base_body,
        left_sole_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "left_sole_contact"),
        right_sole_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "right_sole_contact"),
        left_sole_site=ident(mujoco.mjtObj.mjOBJ_SITE, "left_sole"),
        right_sole_site=ident(mujoco.mjtObj.mjOBJ_SITE, "right_sole"),
        floor_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "floor"),
        qpos_half_sitting=np.empty(0),
        leg_geoms=tuple(ident(mujoco.mjtObj.mjOBJ_GEOM, shape.geom_name) for shape in shapes),
        excluded_leg_pairs=tuple(excluded),
        sensors=SensorLayout.of(model, robot),
        model_error=error,
        motors=motors,
        terrain=terrain,
    )
    qpos = sim.qpos_from_pinocchio(robot.q_half_sitting)
    object.__setattr__(sim, "qpos_half_sitting", qpos)
    return sim
