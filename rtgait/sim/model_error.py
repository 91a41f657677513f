"""Model error: a simulated robot that differs from the controller's model of it, reproducibly from a seed.

The controller, its IK and its planner use the Pinocchio model of the robot description's URDF; the simulated robot
is built from the same URDF (:mod:`rtgait.sim.model`) and, with a model error, then made to differ from it the way a
real robot differs from its CAD model and its calibration (ranges in :data:`MODEL_ERROR_RANGES`, justified in
``docs/robots.md``). Each value is drawn uniformly within its range from a generator seeded by the run's seed:

* **masses**: each body's mass times a factor ``f`` in ``[1 - a, 1 + a]``; its rotational inertia times the same
  factor (the same shape, denser or lighter), its principal axes kept;
* **centres of mass**: each body's COM moved by ``d`` in its own frame, each axis in ``[-b, b]`` (a box, not a
  sphere: ``|d|`` reaches ``sqrt(3) b``);
* **joint zeros**: each moving joint's encoder reads ``q_read = q_true + o``, ``o`` in ``[-c, c]``. The controller
  commands ``q_ref`` in its model's convention; the drive servos its encoder reading to it, so the joint itself goes
  to ``q_ref - o`` and its encoder then reads ``q_ref`` (:class:`~rtgait.sim.drives.Drives`,
  :class:`~rtgait.sim.sensors.SensorModel`);
* **joint friction** (with the motor model only, :mod:`rtgait.sim.motors`): each moving joint's Coulomb and viscous
  friction times a factor in ``[1 - r, 1 + r]`` (one factor for both): a gear's friction differs from its bench
  identification with its temperature and load by some tens of per cent, and the controller knows only the
  identified values (its compensation, :mod:`rtgait.stack.friction_compensation`). Drawn from a stream of its own,
  so the other draws of a seed are those of a run without the motor model.

A *body* is a MuJoCo body with mass: the URDF's links on fixed and locked joints are fused into their moving parent
(:mod:`rtgait.sim.urdf_import`), so a body is one rigid group (Talos: the base, the two torso links, the arms and head
in ``torso_2_link``, six links a leg). One draw per rigid group is also what identification from motion can see: the
parts of a group never move relative to one another.

The masses and COMs are applied to the compiled ``MjModel`` (``body_mass``, ``body_inertia``, ``body_ipos``) and its
derived constants recomputed (``mj_setConst``: subtree masses, the solver's mean inertia, ...). The generator is the
seed's own stream (not the sensors' one): the same seed as the sensor noise draws unrelated values.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

__all__ = ["MODEL_ERROR_RANGES", "ModelError", "ModelErrorRanges", "apply_friction_error", "apply_model_error", "draw"]

_STREAM = 0x6D6F64656C  # mixed into the seed: the model error's stream differs from any other use of the same seed
_FRICTION_STREAM = 0x6672696374  # the joints' friction factors' own stream (module docstring)


@dataclass(frozen=True)
class ModelErrorRanges:
    """The half-widths of the uniform draws (module docstring).

    Attributes:
        mass: relative mass error of each body (0.05: factors in [0.95, 1.05]).
        com: COM shift of each body along each of its axes (m).
        joint_offset: encoder zero offset of each moving joint (rad).
        friction: relative error of each moving joint's friction (0.3: factors in [0.7, 1.3]), with the motor model.
    """

    mass: float = 0.05
    com: float = 0.010
    joint_offset: float = math.radians(0.5)
    friction: float = 0.3

    def __post_init__(self) -> None:
        for name in ("mass", "com", "joint_offset", "friction"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"ModelErrorRanges.{name} must be finite and >= 0, got {value}")
        if self.mass >= 1.0:
            raise ValueError(f"ModelErrorRanges.mass must be < 1 (a mass stays > 0), got {self.mass}")
        if self.friction > 1.0:
            raise ValueError(f"ModelErrorRanges.friction must be <= 1 (a friction stays >= 0), got {self.friction}")

    def summary(self) -> dict[str, float]:
        """The ranges in the units of ``summary.json``: percent, mm and degrees."""
        return {
            "mass_percent": 100.0 * self.mass,
            "com_mm": 1e3 * self.com,
            "joint_offset_deg": math.degrees(self.joint_offset),
        }


MODEL_ERROR_RANGES = ModelErrorRanges()
"""The default ranges: masses +-5 %, COMs +-10 mm per axis, joint zeros +-0.5 deg (``docs/robots.md``)."""


@dataclass(frozen=True, eq=False)
class ModelError:
    """The drawn differences between the simulated robot and the controller's model.

    Attributes:
        seed: the seed they were drawn from.
        ranges: the ranges they were drawn within.
        bodies: MuJoCo names of the bodies with mass, in body order.
        body_ids: their MuJoCo body ids.
        masses: their nominal masses (kg), the model's.
        coms: their nominal COMs in their own frames (m), shape ``(n, 3)``.
        mass_factors: simulated mass / nominal mass per body.
        com_shifts: simulated COM - nominal COM per body, in its frame (m), shape ``(n, 3)``.
        joints: the moving joints (the robot's joint order).
        joint_offsets: encoder reading - true joint angle per joint (rad).
        com_error: the whole robot's COM, simulated minus nominal, at the reference configuration ``draw`` was given
            (m, world frame; zeros without one).
        friction_factors: simulated friction / identified friction per joint (Coulomb and viscous alike).
        friction_applied: whether the simulated joints have the drawn friction (with the motor model:
            :func:`apply_friction_error`); the records report the factors only then.
    """

    seed: int
    ranges: ModelErrorRanges
    bodies: tuple[str, ...]
    body_ids: np.ndarray
    masses: np.ndarray
    coms: np.ndarray
    mass_factors: np.ndarray
    com_shifts: np.ndarray
    joints: tuple[str, ...]
    joint_offsets: np.ndarray
    com_error: np.ndarray
    friction_factors: np.ndarray
    friction_applied: bool = False

    @property
    def total_mass(self) -> tuple[float, float]:
        """The robot's mass (kg): the model's, the simulated robot's."""
        return float(self.masses.sum()), float((self.masses * self.mass_factors).sum())

    def summary(self) -> dict[str, Any]:
        """The compact record for ``summary.json``: seed, ranges, the whole robot's mass and COM error, the largest
        drawn values (the per-body and per-joint values are :meth:`values`)."""
        model, simulated = self.total_mass
        summary: dict[str, Any] = {
            "seed": self.seed,
            "ranges": self.ranges.summary(),
            "total_mass_kg": {"model": model, "simulated": simulated},
            "com_error_half_sitting_mm": (1e3 * self.com_error).tolist(),
            "largest": {
                "mass_percent": float(100.0 * np.max(np.abs(self.mass_factors - 1.0), initial=0.0)),
                "com_shift_mm": float(1e3 * np.max(np.abs(self.com_shifts), initial=0.0)),
                "joint_offset_deg": float(np.degrees(np.max(np.abs(self.joint_offsets), initial=0.0))),
            },
        }
        if self.friction_applied:
            summary["ranges"]["friction_percent"] = 100.0 * self.ranges.friction
            largest = float(100.0 * np.max(np.abs(self.friction_factors - 1.0), initial=0.0))
            summary["largest"]["friction_percent"] = largest
        return summary

    def values(self) -> dict[str, Any]:
        """Every drawn value, by body and joint name (``model_error.json``): mass factors, COM shifts (mm, body
        frame), joint offsets (deg, reading - true angle), with the seed and ranges."""
        values: dict[str, Any] = {
            "seed": self.seed,
            "ranges": self.ranges.summary(),
            "mass_factors": dict(zip(self.bodies, self.mass_factors.tolist(), strict=True)),
            "com_shifts_mm": dict(zip(self.bodies, (1e3 * self.com_shifts).tolist(), strict=True)),
            "joint_offsets_deg": dict(zip(self.joints, np.degrees(self.joint_offsets).tolist(), strict=True)),
        }
        if self.friction_applied:
            values["ranges"]["friction_percent"] = 100.0 * self.ranges.friction
            values["friction_factors"] = dict(zip(self.joints, self.friction_factors.tolist(), strict=True))
        return values


def _whole_com(masses: np.ndarray, coms: np.ndarray, ids: np.ndarray, data: mujoco.MjData) -> np.ndarray:
    """The COM (m, world) of bodies of ``masses`` with body-frame ``coms`` at the poses of ``data``'s kinematics."""
    rotations = data.xmat[ids].reshape(-1, 3, 3)
    points = data.xpos[ids] + np.einsum("bij,bj->bi", rotations, coms)
    return masses @ points / masses.sum()


def draw(
    seed: int,
    model: mujoco.MjModel,
    joints: tuple[str, ...],
    ranges: ModelErrorRanges = MODEL_ERROR_RANGES,
    reference: np.ndarray | None = None,
) -> ModelError:
    """The model error of ``seed`` for the nominal ``model`` (not changed here; :func:`apply_model_error` does).

    Args:
        seed: an integer >= 0; the same seed, model and ranges draw the same values.
        model: the compiled nominal model: its bodies with mass are perturbed.
        joints: the moving joints, one offset each.
        ranges: the half-widths of the draws.
        reference: a ``qpos`` at which to state the whole robot's COM error (e.g. half-sitting).
    """
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"the model error's seed must be an integer >= 0, got {seed!r}")
    ids = np.flatnonzero(model.body_mass > 0.0)
    n = len(ids)
    rng = np.random.default_rng([seed, _STREAM])
    mass_factors = 1.0 + ranges.mass * rng.uniform(-1.0, 1.0, n)
    com_shifts = ranges.com * rng.uniform(-1.0, 1.0, (n, 3))
    joint_offsets = ranges.joint_offset * rng.uniform(-1.0, 1.0, len(joints))
    friction = np.random.default_rng([seed, _FRICTION_STREAM]).uniform(-1.0, 1.0, len(joints))
    friction_factors = 1.0 + ranges.friction * friction
    masses, coms = model.body_mass[ids].copy(), model.body_ipos[ids].copy()
    com_error = np.zeros(3)
    if reference is not None:
        data = mujoco.MjData(model)
        data.qpos[:] = reference
        mujoco.mj_kinematics(model, data)
        com_error = _whole_com(masses * mass_factors, coms + com_shifts, ids, data) - _whole_com(
            masses, coms, ids, data
        )
    return ModelError(
        seed=seed,
        ranges=ranges,
        bodies=tuple(model.body(int(i)).name for i in ids),
        body_ids=ids,
        masses=masses,
        coms=coms,
        mass_factors=mass_factors,
        com_shifts=com_shifts,
        joints=tuple(joints),
        joint_offsets=joint_offsets,
        com_error=com_error,
        friction_factors=friction_factors,
    )


def apply_model_error(model: mujoco.MjModel, error: ModelError) -> None:
    """Give ``model`` (the nominal one ``error`` was drawn for) the drawn masses, inertias and COMs, and recompute
    its derived constants. The joint offsets act in the servos and encoders, not here."""
    ids = error.body_ids
    if not (np.array_equal(model.body_mass[ids], error.masses) and np.array_equal(model.body_ipos[ids], error.coms)):
        raise ValueError("the model error was drawn for another model (or this one was perturbed already)")
    model.body_mass[ids] = error.masses * error.mass_factors
    model.body_inertia[ids] *= error.mass_factors[:, None]
    model.body_ipos[ids] = error.coms + error.com_shifts
    mujoco.mj_setConst(model, mujoco.MjData(model))


def apply_friction_error(model: mujoco.MjModel, error: ModelError, dof_index: np.ndarray) -> ModelError:
    """Give ``model``'s moving joints (their dofs ``dof_index``, in ``error.joints`` order) the drawn friction: their
    ``frictionloss`` and ``damping`` (the motor model's, :func:`rtgait.sim.motors.add_friction`) times
    ``error.friction_factors``. Returns ``error`` marked as applied."""
    if len(dof_index) != len(error.friction_factors):
        raise ValueError(
            f"the model error drew {len(error.friction_factors)} joints' friction, got {len(dof_index)} dofs"
        )
    model.dof_frictionloss[dof_index] *= error.friction_factors
    model.dof_damping[dof_index] *= error.friction_factors
    return dataclasses.replace(error, friction_applied=True)
