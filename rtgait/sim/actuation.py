"""Joint actuation in physics: each joint's drive gains, torque limit and armature, from the robot description.

The model of one joint's drive, as humanoids' joint loops run (Unitree's motors, a ros_control joint; and as
mc_mujoco simulates them):

* the controller sends a command ``(q_ref, qd_ref, tau_ff, kp, kd)`` every **control period** (``control_dt``: 1 ms
  for Talos, whose ros_control loop runs at 1 kHz; 2 ms for G1, whose low-level SDK loop runs at 500 Hz); gains it
  leaves out are the drive's own (this module's ``kp``, ``kd``);
* the drive applies ``tau = tau_ff + kp (q_ref - q) + kd (qd_ref - qd)`` (N m), clipped to the joint's torque limit
  (or the motor's envelope, :mod:`rtgait.sim.motors`), at every **physics step** (``physics_dt``, which divides the
  control period): :mod:`rtgait.sim.drives`;
* the motor's rotor, seen through the gear of ratio ``N``, adds ``J_rotor N^2`` to the joint's inertia (the
  **armature**).

In MuJoCo: one *general* actuator per joint with ``gain = kp`` and bias ``-kp q - kd qd`` (:func:`add_actuators`),
``forcerange = +-effort limit``: MuJoCo evaluates the PD at the state of each substep, and the ``implicitfast``
integrator integrates its ``-kd qd`` implicitly (dropping it, correctly, while the actuator saturates); a torque
computed in Python would make the damping explicit, unstable once ``kd / inertia`` exceeds ``2 / dt`` (a
stance-sized servo on a light swing foot).

Two sets of the drive's own gains (``SimConfig.gains``): ``"stiff"``, the description's ``kp``/``kd`` else the
defaults below, derived from the URDF; ``"robot"``, the gains the real robot's low-level controller runs
(``robot_kp``/``robot_kd``, cited in each description).

Defaults derived from the URDF when the description does not give a value (``[actuation]``,
:mod:`rtgait.robot.description`):

* **torque limit** = the URDF's ``<limit effort>`` (none when it is missing, 0 or infinite);
* **armature** = ``armature_per_torque`` x the torque limit
  (:data:`rtgait.robot.actuation_table.DEFAULT_ARMATURE_PER_TORQUE`);
* **kp** = ``(2 pi f)^2 (armature + I_carried)`` for the natural frequency ``f`` (``actuation.natural_frequency``,
  10 Hz by default), ``I_carried`` the inertia about the joint axis at half-sitting of what the joint carries: for a
  leg joint the larger of the part beyond it (swing) and the rest of the robot pivoting about it with the foot on
  the ground (stance); for any other joint the part beyond it. Every joint has the bandwidth where an open-loop
  walking pattern needs it: carrying the robot.
* **kd** = ``2 zeta sqrt(kp (armature + I_distal))``, ``I_distal`` the inertia beyond the joint: a swinging limb is
  critically damped (at ``zeta = 1``), the loaded stance modes lightly, as in the gain tables of position-controlled
  humanoids (mc_mujoco's JVRC1: kd 20-50 N m s/rad on kp 3000-6000 N m/rad). Damping the stance inertia critically
  would make the ankle torque, which sets the ZMP, answer every velocity error (``docs/design/simulation.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from rtgait.interface.command import GAIN_SETS
from rtgait.robot.drives import joint_drives
from rtgait.robot.joint_inertia import carried_inertia
from rtgait.robot.model import RobotModel

__all__ = ["Actuation", "add_actuators", "carried_inertia", "own_gains", "resolve_actuation", "substeps"]

_TIME_TOLERANCE = 1e-9  # relative: 0.002 / 0.0005 must count as exactly 4


def substeps(control_dt: float, physics_dt: float) -> int:
    """Physics steps per control period.

    Raises:
        ValueError: a period that is not a positive finite duration, a physics step longer than the control
            period, or one that does not divide it.
    """
    for name, value in (("control_dt", control_dt), ("physics_dt", physics_dt)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be a duration > 0 s, got {value}")
    if physics_dt > control_dt * (1.0 + _TIME_TOLERANCE):
        raise ValueError(
            f"physics_dt {physics_dt:g} s is longer than the control period control_dt {control_dt:g} s: the physics "
            "must take at least one step per control period"
        )
    ratio = control_dt / physics_dt
    n = round(ratio)
    if abs(ratio - n) > _TIME_TOLERANCE * ratio:
        raise ValueError(
            f"physics_dt {physics_dt:g} s must divide the control period control_dt {control_dt:g} s "
            f"(a whole number of physics steps per control period), got {ratio:.6g} steps"
        )
    return n


@dataclass(frozen=True, eq=False)
class Actuation:
    """The resolved actuation of every moving joint, in ``joint_names`` order.

    Attributes:
        joint_names: the moving joints (the IK's order).
        kp: position gains (N m/rad).
        kd: damping gains (N m s/rad).
        armature: reflected rotor inertias (kg m^2).
        effort_limit: torque limits (N m); ``inf``: none.
        carried_inertia: the inertia each joint carries at half-sitting, armature excluded (kg m^2), from which the
            default gains are derived (:func:`carried_inertia`).
        control_dt: control period (s): a new joint reference every period.
        physics_dt: physics step (s), a divisor of ``control_dt``.
        gains: which of the description's gain sets ``kp`` and ``kd`` are (``"stiff"`` or ``"robot"``).
    """

    joint_names: tuple[str, ...]
    kp: np.ndarray
    kd: np.ndarray
    armature: np.ndarray
    effort_limit: np.ndarray
    carried_inertia: np.ndarray
    control_dt: float
    physics_dt: float
    gains: str = "stiff"

    def __post_init__(self) -> None:
        substeps(self.control_dt, self.physics_dt)
        for name in ("kp", "kd", "armature", "effort_limit", "carried_inertia"):
            values = getattr(self, name)
            if values.shape != (len(self.joint_names),):
                raise ValueError(f"Actuation.{name} must have one value per joint, got shape {values.shape}")
        if not (np.isfinite(self.kp).all() and (self.kp > 0.0).all()):
            bad = self.joint_names[int(np.argmin(np.where(np.isfinite(self.kp), self.kp, -1.0)))]
            raise ValueError(f"kp of joint {bad} must be finite and > 0 N m/rad (a position servo needs a stiffness)")
        for name in ("kd", "armature"):
            values = getattr(self, name)
            if not (np.isfinite(values).all() and (values >= 0.0).all()):
                raise ValueError(f"Actuation.{name} must be finite and >= 0 for every joint")
        if not (self.effort_limit > 0.0).all():
            raise ValueError("Actuation.effort_limit must be > 0 N m for every joint (inf: no limit)")

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        return substeps(self.control_dt, self.physics_dt)

    @property
    def natural_frequency(self) -> np.ndarray:
        """Natural frequency of each joint's servo on the inertia it carries plus the armature (Hz)."""
        return np.sqrt(self.kp / (self.carried_inertia + self.armature)) / (2.0 * math.pi)

    @property
    def damping_ratio(self) -> np.ndarray:
        """Damping ratio of each joint's servo on the inertia it carries plus the armature."""
        inertia = self.carried_inertia + self.armature
        return self.kd / (2.0 * np.sqrt(self.kp * inertia))

    def scaled(self, gains: float = 1.0, armature: float = 1.0) -> Actuation:
        """The same actuation with ``kp`` and ``kd`` times ``gains`` and the armature times ``armature`` (for
        ensembles of physics settings: the servo's gains and the rotor's inertia are uncertain by tens of %)."""
        for name, value in (("gains", gains), ("armature", armature)):
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"the {name} scale must be finite and > 0, got {value}")
        return replace(self, kp=self.kp * gains, kd=self.kd * gains, armature=self.armature * armature)

    def rows(self) -> list[dict[str, float | str]]:
        """One row per joint (for tables and documentation): name, kp, kd, armature, effort limit, carried
        inertia, natural frequency and damping ratio."""
        frequency, ratio = self.natural_frequency, self.damping_ratio
        return [
            {
                "joint": name,
                "kp": float(self.kp[i]),
                "kd": float(self.kd[i]),
                "armature": float(self.armature[i]),
                "effort_limit": float(self.effort_limit[i]),
                "carried_inertia": float(self.carried_inertia[i]),
                "natural_frequency": float(frequency[i]),
                "damping_ratio": float(ratio[i]),
            }
            for i, name in enumerate(self.joint_names)
        ]


def resolve_actuation(
    robot: RobotModel, control_dt: float | None = None, physics_dt: float = 0.001, gains: str = "stiff"
) -> Actuation:
    """Every moving joint's actuation: the description's values, else defaults derived from the URDF (see the
    module docstring).

    Args:
        robot: the loaded robot.
        control_dt: control period (s); ``None``: the description's ``actuation.control_dt``.
        physics_dt: physics step (s); must divide the control period.
        gains: ``"stiff"`` (the description's ``kp``/``kd``, else derived) or ``"robot"`` (its ``robot_kp``/
            ``robot_kd``, which every moving joint must have).

    Raises:
        ValueError: bad periods (:func:`substeps`), an unknown gain set, a joint without the robot's gains, or a
            joint whose resolved kp is not > 0.
    """
    if gains not in GAIN_SETS:
        raise ValueError(f"gains must be {' or '.join(map(repr, GAIN_SETS))}, got {gains!r}")
    description = robot.description
    if control_dt is None:
        control_dt = description.actuation.control_dt
    substeps(control_dt, physics_dt)
    distal, carried = carried_inertia(robot)
    limits, armature = joint_drives(robot)
    kp, kd = [], []
    for i, name in enumerate(robot.joint_names):
        spec = description.joint_actuation(name)
        rotor = float(armature[i])
        if gains == "robot":
            if spec.robot_kp is None or spec.robot_kd is None:
                raise ValueError(
                    f"gains 'robot': the description of {description.name} gives no robot_kp and robot_kd for joint "
                    f"{name} ([[actuation.joints]])"
                )
            kp.append(spec.robot_kp)
            kd.append(spec.robot_kd)
        else:
            omega = 2.0 * math.pi * spec.natural_frequency
            joint_kp = spec.kp if spec.kp is not None else omega * omega * (rotor + float(carried[i]))
            kp.append(joint_kp)
            kd.append(
                spec.kd
                if spec.kd is not None
                else 2.0 * spec.damping_ratio * math.sqrt(joint_kp * (rotor + float(distal[i])))
            )
    return Actuation(
        joint_names=robot.joint_names,
        kp=np.array(kp),
        kd=np.array(kd),
        armature=armature,
        effort_limit=limits,
        carried_inertia=carried,
        control_dt=float(control_dt),
        physics_dt=float(physics_dt),
        gains=gains,
    )


def add_actuators(spec: mujoco.MjSpec, actuation: Actuation) -> None:
    """Give each moving joint of ``spec`` its armature and a general actuator that is the clipped PD servo (actuator
    ``i`` drives ``actuation.joint_names[i]``; see the module docstring)."""
    for i, name in enumerate(actuation.joint_names):
        joint = spec.joint(name)
        joint.armature = float(actuation.armature[i])
        kp, kd, limit = float(actuation.kp[i]), float(actuation.kd[i]), float(actuation.effort_limit[i])
        # force = kp * ctrl - kp * q - kd * qdot, what <position kp kv> compiles to, spelt out for every MuJoCo
        # version; implicitfast integrates the -kd * qdot part implicitly.
        actuator = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.gainprm = [kp] + [0.0] * 9
        actuator.biasprm = [0.0, -kp, -kd] + [0.0] * 7
        if math.isfinite(limit):
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [-limit, limit]
        else:
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE


def own_gains(model: mujoco.MjModel, actuation: Actuation) -> None:
    """Put the drives' own gains (:func:`add_actuators`'s) back into ``model``'s actuators, whatever a command with
    other gains left there (:mod:`rtgait.sim.drives`)."""
    model.actuator_gainprm[:, 0] = actuation.kp
    model.actuator_biasprm[:, 1] = -actuation.kp
    model.actuator_biasprm[:, 2] = -actuation.kd
