"""The MuJoCo model of a robot, built at run time from its robot description.

What the importer gets from the URDF and what is changed, and why:

* The URDF's ``package://`` mesh URIs are rewritten to files under the description's ``package_dirs`` (MuJoCo
  does not know ROS packages), and MuJoCo's URDF extension ``<mujoco><compiler .../></mujoco>`` keeps the paths
  and the visual meshes, and takes the inertia from the URDF's ``<inertial>`` elements only (as Pinocchio does),
  so both see the same mass distribution.
* Mesh geoms are visual only (no collision): the URDF's collision meshes overlap at the joints (dozens of
  self-contacts at the start) and a walking foot must touch the floor through its sole, not a mesh. The collision
  meshes are dropped; one thin box per sole, the described sole rectangle with its bottom face on the sole point,
  is the only thing that touches the floor.
* The root link gets a free joint (the URDF has a fixed base).
* Every joint outside ``walking.moving_joints`` is locked at its half-sitting angle (its body is turned by the
  angle and the joint removed): the whole-body IK treats them the same way, and the model gets fewer degrees of
  freedom, which makes every physics step cheaper.
* Each moving joint gets a position servo ``tau = kp (q_target - q) - kd qdot``, limited to the URDF's effort
  limit, and the rotor inertia :attr:`SimConfig.armature`. The gains are the description's ``[gains]`` when
  given, else a default proportional to the robot's mass (the torques a leg joint must resist grow with the
  weight it carries: in single support, the whole robot's).
* 1 ms steps with the ``implicitfast`` integrator: the servo damping is integrated implicitly, which keeps stiff
  servos stable at that step.

Configurations: Pinocchio's free flyer is ``(x, y, z, qx, qy, qz, qw)``, MuJoCo's free joint ``(x, y, z, qw, qx,
qy, qz)``; joints are matched by URDF name, never by order.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from rtgait.robot.description import RobotDescription, RobotError
from rtgait.robot.model import RobotModel

__all__ = ["SETTLE_TIME", "SimConfig", "SimModel", "build_sim_model"]

SETTLE_TIME = 0.2
"""Physics time (s) a fresh state stands still before its clock starts (see :meth:`SimModel.reset`)."""

_PACKAGE = "package://"
# Collision bits: the floor (type 1) collides with the soles (affinity 1), and nothing else collides with
# anything: not sole with sole, not a visual mesh with either.
_FLOOR_CONTYPE, _FLOOR_CONAFFINITY = 1, 0
_SOLE_CONTYPE, _SOLE_CONAFFINITY = 0, 1


@dataclass(frozen=True)
class SimConfig:
    """Physics parameters of the simulated robot and its floor.

    Why the defaults (checked on Talos, 90 kg, with the built-in scenarios; the closed loop is the planner alone,
    with no stabiliser, so the servos and the soles decide how faithfully the robot follows the plan):

    * Stiff servos, ``kp = 1000 N m/rad`` per kg (90 kN m/rad on Talos), ``kd = kp / 100 s``: position-controlled
      humanoids run their joints stiff; the largest walking torque (the knee, about 180 N m of its 300 N m
      limit) then deflects a joint by 2 mrad. At half these gains the robot rocks more on its soles: the measured
      ZMP strays up to twice as far from the plan.
    * A soft, well-damped sole: contact time constant 10 ms, damping ratio 2, which sinks about 1 mm under the
      robot's weight, like a rubber sole. On a stiffer or less damped contact (MuJoCo's default damping ratio
      is 1) the stiff robot rocks more from one sole edge to the other after landings; rubber soles absorb that.
    * ``armature = 0.1 kg m^2`` per joint: geared motors add their rotor's inertia times the squared gear ratio
      (tenths of a kg m^2 for a humanoid's leg joints); it also keeps the stiff servos of light links (the feet)
      stable at a 1 ms step.

    Attributes:
        timestep: physics step (s); also the control period of the closed loop.
        friction: sliding friction coefficient between soles and floor.
        contact_timeconst: time constant of the soft contact (s); MuJoCo's ``solref[0]``, at least two steps.
        contact_dampratio: damping ratio of the soft contact; MuJoCo's ``solref[1]``.
        contact_impedance: MuJoCo's ``solimp[0:2]``, the contact's impedance at zero and at 1 mm penetration.
        sole_thickness: height of the sole contact boxes (m); their bottom face is on the sole point.
        kp_per_kg: default position gain per kg of robot mass (N m/rad/kg), for joints without ``[gains]``.
        kd_per_kg: default damping gain per kg of robot mass (N m s/rad/kg).
        armature: rotor inertia reflected to each moving joint (kg m^2): a geared motor's rotor, seen through a
            gear ratio r, adds r^2 times its inertia to the joint; the URDF has none.
        meshes: keep the visual meshes (for viewing); without them the model builds faster and simulates the same.
    """

    timestep: float = 0.001
    friction: float = 1.0
    contact_timeconst: float = 0.01
    contact_dampratio: float = 2.0
    contact_impedance: tuple[float, float] = (0.9, 0.95)
    sole_thickness: float = 0.01
    kp_per_kg: float = 1000.0
    kd_per_kg: float = 10.0
    armature: float = 0.1
    meshes: bool = True

    def __post_init__(self) -> None:
        rules = {
            "timestep": (self.timestep > 0.0, "> 0 s"),
            "friction": (self.friction > 0.0, "> 0"),
            "contact_timeconst": (self.contact_timeconst >= 2.0 * self.timestep, ">= 2 timesteps (s)"),
            "contact_dampratio": (self.contact_dampratio > 0.0, "> 0"),
            "sole_thickness": (self.sole_thickness > 0.0, "> 0 m"),
            "kp_per_kg": (self.kp_per_kg > 0.0, "> 0 N m/rad/kg"),
            "kd_per_kg": (self.kd_per_kg >= 0.0, ">= 0 N m s/rad/kg"),
            "armature": (self.armature >= 0.0, ">= 0 kg m^2"),
        }
        for name, (ok, rule) in rules.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and ok):
                raise ValueError(f"SimConfig.{name} must be finite and {rule}, got {value}")
        low, high = self.contact_impedance
        if not 0.0 < low <= high < 1.0:
            raise ValueError(
                f"SimConfig.contact_impedance must be (low, high) with 0 < low <= high < 1, got {(low, high)}"
            )


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
        kp, kd: servo gains per joint of ``joint_names`` (N m/rad, N m s/rad); actuator ``i`` drives joint ``i``.
        base_body: MuJoCo body id of the floating base (the URDF's root link).
        left_sole_geom, right_sole_geom: geom ids of the sole contact boxes.
        left_sole_site, right_sole_site: site ids at the sole points (the description's sole frames).
        floor_geom: geom id of the floor plane.
        qpos_half_sitting: MuJoCo configuration at half-sitting, soles on the floor (m, unit quaternion, rad).
    """

    robot: RobotModel
    config: SimConfig
    model: mujoco.MjModel
    joint_names: tuple[str, ...]
    qpos_index: np.ndarray
    dof_index: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    base_body: int
    left_sole_geom: int
    right_sole_geom: int
    left_sole_site: int
    right_sole_site: int
    floor_geom: int
    qpos_half_sitting: np.ndarray

    @property
    def timestep(self) -> float:
        """Physics step (s)."""
        return float(self.model.opt.timestep)

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
                half-sitting.
        """
        if not (math.isfinite(settle) and settle >= 0.0):
            raise ValueError(f"settle must be a duration >= 0 s, got {settle}")
        model = self.model
        mujoco.mj_resetData(model, data)
        if q is None:
            data.qpos[:] = self.qpos_half_sitting
        else:
            self.qpos_from_pinocchio(np.asarray(q, dtype=float), out=data.qpos)
        data.ctrl[:] = data.qpos[self.qpos_index]
        for _ in range(round(settle / model.opt.timestep)):
            mujoco.mj_step(model, data)
        data.qvel[:] = 0.0
        data.qacc_warmstart[:] = 0.0
        data.time = 0.0
        mujoco.mj_forward(model, data)


# ----- URDF text -------------------------------------------------------------------------------------------------


def _resolve_mesh(uri: str, description: RobotDescription) -> str | None:
    """Absolute path of a URDF mesh URI, or ``None`` when no file is found."""
    if uri.startswith(_PACKAGE):
        relative = uri[len(_PACKAGE) :]
        for folder in description.package_dirs:
            candidate = folder / relative
            if candidate.is_file():
                return str(candidate)
        return None
    path = Path(uri.removeprefix("file://"))
    if not path.is_absolute():
        path = description.urdf.parent / path
    return str(path) if path.is_file() else None


def _urdf_for_mujoco(description: RobotDescription, meshes: bool) -> str:
    """The URDF's text, ready for MuJoCo's importer (see the module docstring)."""
    try:
        root = ElementTree.parse(description.urdf).getroot()
    except (OSError, ElementTree.ParseError) as error:
        raise RobotError(f"model.urdf {description.urdf} is not a readable URDF: {error}") from None
    for old in root.findall("mujoco"):
        root.remove(old)
    for link in root.findall("link"):
        for collision in link.findall("collision"):
            link.remove(collision)
        for visual in link.findall("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            path = _resolve_mesh(mesh.get("filename", ""), description) if meshes else None
            if path is None:
                # A missing mesh file is only a missing picture; the physics does not depend on it.
                link.remove(visual)
            else:
                mesh.set("filename", path)
    extension = ElementTree.Element("mujoco")
    ElementTree.SubElement(
        extension,
        "compiler",
        {
            "strippath": "false",  # keep the absolute mesh paths written above
            "discardvisual": "false",  # the visual meshes are the only picture of the robot left
            "inertiafromgeom": "false",  # the URDF's <inertial> only, as Pinocchio reads it
            "balanceinertia": "true",  # a few URDF inertias violate the triangle inequality slightly
            "fusestatic": "true",  # links on fixed joints (and locked ones) become part of their parent
            "angle": "radian",
        },
    )
    root.insert(0, extension)
    return ElementTree.tostring(root, encoding="unicode")


# ----- spec edits ------------------------------------------------------------------------------------------------


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


def _rotate(quat: np.ndarray, vector: np.ndarray) -> np.ndarray:
    out = np.empty(3)
    mujoco.mju_rotVecQuat(out, vector, quat)
    return out


def _lock_joint(spec: mujoco.MjSpec, joint: mujoco.MjsJoint, angle: float) -> None:
    """Turn (or slide) the joint's body by ``angle`` about the joint axis and remove the joint."""
    body = joint.parent
    axis = np.array(joint.axis, dtype=float)
    axis /= np.linalg.norm(axis)
    anchor = np.array(joint.pos, dtype=float)
    quat = np.array(body.quat, dtype=float)
    quat /= np.linalg.norm(quat)
    if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
        turn = np.empty(4)
        mujoco.mju_axisAngle2Quat(turn, axis, angle)
        # A rotation about an axis through `anchor` (body coordinates): the body origin moves unless anchor = 0.
        body.pos = np.array(body.pos) + _rotate(quat, anchor - _rotate(turn, anchor))
        body.quat = _quat_mul(quat, turn)
    elif joint.type == mujoco.mjtJoint.mjJNT_SLIDE:
        body.pos = np.array(body.pos) + _rotate(quat, angle * axis)
    else:  # pragma: no cover - descriptions only name one-coordinate joints, and URDFs have no others
        raise RobotError(f"cannot lock joint {joint.name!r} of type {joint.type}")
    if hasattr(spec, "delete"):
        spec.delete(joint)
    else:  # MuJoCo before 3.4 removes an element through the element itself
        joint.delete()


def _sole_placement(robot: RobotModel, frame_id: int) -> tuple[str | None, pin.SE3]:
    """The URDF joint a sole frame hangs from (``None``: the root link) and the frame's placement in it."""
    full = robot.full_model
    frame = full.frames[frame_id]
    # Pinocchio's joint frame is the child link's frame, which is MuJoCo's body frame for that link.
    joint = full.names[frame.parentJoint]
    return (None if frame.parentJoint == 1 else joint), frame.placement


def _add_sole(
    spec: mujoco.MjSpec, robot: RobotModel, side: str, root: mujoco.MjsBody, config: SimConfig
) -> tuple[str, str]:
    """Add a sole contact box and a site at the sole point; returns their names."""
    frame_id = robot.full_left_sole_id if side == "left" else robot.full_right_sole_id
    joint, placement = _sole_placement(robot, frame_id)
    body = root if joint is None else spec.joint(joint).parent
    sole = robot.description.sole
    # `inner` is toward the other foot: -y for the left foot, +y for the right one.
    toward_other = -1.0 if side == "left" else 1.0
    half = np.array([0.5 * (sole.front + sole.back), 0.5 * (sole.inner + sole.outer), 0.5 * config.sole_thickness])
    centre = np.array(
        [0.5 * (sole.front - sole.back), toward_other * 0.5 * (sole.inner - sole.outer), half[2]]
    )  # in the sole frame: the box stands on the sole point's plane
    rotation = placement.rotation
    quat = pin.Quaternion(rotation).coeffs()  # (x, y, z, w)
    wxyz = np.array([quat[3], quat[0], quat[1], quat[2]])
    geom_name, site_name = f"{side}_sole_contact", f"{side}_sole"
    body.add_geom(
        name=geom_name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=half,
        pos=placement.translation + rotation @ centre,
        quat=wxyz,
        contype=_SOLE_CONTYPE,
        conaffinity=_SOLE_CONAFFINITY,
        condim=3,
        friction=[config.friction, 0.005, 0.0001],
        solref=[config.contact_timeconst, config.contact_dampratio],
        solimp=[*config.contact_impedance, 0.001, 0.5, 2.0],
        mass=0.0,
        group=3,
        rgba=[0.9, 0.5, 0.1, 0.6],
    )
    body.add_site(name=site_name, pos=placement.translation, quat=wxyz, size=[0.01, 0.01, 0.01])
    return geom_name, site_name


def _default_gains(robot: RobotModel, config: SimConfig) -> tuple[float, float]:
    return config.kp_per_kg * robot.mass, config.kd_per_kg * robot.mass


def build_sim_model(robot: RobotModel | str, config: SimConfig | None = None) -> SimModel:
    """Build the MuJoCo model of ``robot`` (a loaded robot, or a built-in robot name / description file path).

    Raises:
        RobotError: the URDF cannot be read or MuJoCo cannot compile the edited model (message names the cause).
    """
    if not isinstance(robot, RobotModel):
        robot = RobotModel.load(robot)
    config = config or SimConfig()
    description = robot.description
    try:
        spec = mujoco.MjSpec.from_string(_urdf_for_mujoco(description, config.meshes))
    except ValueError as error:
        raise RobotError(f"model.urdf {description.urdf}: MuJoCo cannot read it: {error}") from None
    spec.modelname = description.name

    moving = set(robot.joint_names)
    for joint in list(spec.joints):
        if joint.name not in moving:
            _lock_joint(spec, joint, description.posture_angle(joint.name))
    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 0, 0

    root = spec.worldbody.first_body()
    root.add_freejoint(name="root")
    for side in ("left", "right"):
        _add_sole(spec, robot, side, root, config)
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],  # infinite plane (size 0); the 0.05 is the grid spacing for viewers
        contype=_FLOOR_CONTYPE,
        conaffinity=_FLOOR_CONAFFINITY,
        friction=[config.friction, 0.005, 0.0001],
        solref=[config.contact_timeconst, config.contact_dampratio],
        solimp=[*config.contact_impedance, 0.001, 0.5, 2.0],
        rgba=[0.8, 0.8, 0.8, 1.0],
    )

    default_kp, default_kd = _default_gains(robot, config)
    kp, kd = [], []
    for name in robot.joint_names:
        joint = spec.joint(name)
        joint.armature = config.armature
        gains = description.gains(name)
        joint_kp, joint_kd = gains if gains is not None else (default_kp, default_kd)
        kp.append(joint_kp)
        kd.append(joint_kd)
        # MuJoCo's position servo spelt out (what <position kp kv> compiles to, in every MuJoCo version):
        # force = kp * ctrl - kp * q - kd * qdot; implicitfast integrates the -kd * qdot part implicitly.
        actuator = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.gainprm = [joint_kp] + [0.0] * 9
        actuator.biasprm = [0.0, -joint_kp, -joint_kd] + [0.0] * 7

    spec.option.timestep = config.timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    try:
        model = spec.compile()
    except ValueError as error:
        raise RobotError(f"model.urdf {description.urdf}: MuJoCo cannot compile the robot: {error}") from None

    def ident(kind: mujoco.mjtObj, name: str) -> int:
        index = mujoco.mj_name2id(model, kind, name)
        if index < 0:  # pragma: no cover - every name looked up was added above
            raise RobotError(f"the MuJoCo model of {description.name} has no {kind.name} {name!r}")
        return int(index)

    joint_ids = [ident(mujoco.mjtObj.mjOBJ_JOINT, name) for name in robot.joint_names]
    qpos_index = np.array([model.jnt_qposadr[j] for j in joint_ids])
    dof_index = np.array([model.jnt_dofadr[j] for j in joint_ids])
    base_body = int(model.jnt_bodyid[ident(mujoco.mjtObj.mjOBJ_JOINT, "root")])
    sim = SimModel(
        robot=robot,
        config=config,
        model=model,
        joint_names=robot.joint_names,
        qpos_index=qpos_index,
        dof_index=dof_index,
        kp=np.array(kp),
        kd=np.array(kd),
        base_body=base_body,
        left_sole_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "left_sole_contact"),
        right_sole_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "right_sole_contact"),
        left_sole_site=ident(mujoco.mjtObj.mjOBJ_SITE, "left_sole"),
        right_sole_site=ident(mujoco.mjtObj.mjOBJ_SITE, "right_sole"),
        floor_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "floor"),
        qpos_half_sitting=np.empty(0),
    )
    qpos = sim.qpos_from_pinocchio(robot.q_half_sitting)
    object.__setattr__(sim, "qpos_half_sitting", qpos)
    return sim
