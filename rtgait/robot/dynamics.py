"""Multibody check of a joint trajectory: centroidal momentum and the ZMP of the whole body.

The planner models the robot as a point mass at constant height (the linear inverted pendulum). The real body
also changes its angular momentum about the COG (legs swinging, pelvis turning), which moves the ZMP away from
the pendulum's. This module measures that on the trajectory the IK produced:

* velocities and accelerations by central finite differences on the configuration manifold (``pin.difference``,
  so the free-flyer's orientation is differentiated correctly), never across the ticks where a caller says the
  trajectory jumps (``breaks``: a jump has no acceleration, its second difference ``J / dt^2`` is the sampling's);
* centroidal momentum ``h_G = (M c', L)`` and its rate ``(M c'', L')`` at the COG, by Pinocchio's
  ``computeCentroidalMomentumTimeVariation``;
* the ZMP on the ground plane z = 0 from the total contact wrench. With the ground reaction force
  ``f = M (c'' + g e_z)`` and its moment about the origin ``tau = c x f + L'``, the point of zero horizontal moment
  is ``p_x = -tau_y / f_z``, ``p_y = tau_x / f_z``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

if TYPE_CHECKING:  # annotations only: the check itself needs nothing but arrays and a model
    from rtgait.core.analysis.rollout import Rollout
    from rtgait.robot.motion import JointTrajectory

__all__ = ["MultibodyCheck", "check_motion", "finite_differences", "multibody_check"]


@dataclass(frozen=True)
class MultibodyCheck:
    """Centroidal quantities and the multibody ZMP of a trajectory, per tick.

    Attributes:
        times: tick times (s), shape ``(k,)``.
        zmp: multibody ZMP on the ground (m), shape ``(k, 2)``.
        cog: COG position (m), shape ``(k, 3)``.
        cog_acc: COG acceleration (m/s^2), shape ``(k, 3)``.
        angular_momentum: angular momentum about the COG (kg m^2/s), world axes, shape ``(k, 3)``.
        angular_momentum_rate: its time derivative (N m), shape ``(k, 3)``.
        vertical_force: vertical ground reaction force ``M (c''_z + g)`` (N), shape ``(k,)``.
        planned_zmp: the ZMP the planner intended (m), shape ``(k, 2)``, if given.
    """

    times: np.ndarray
    zmp: np.ndarray
    cog: np.ndarray
    cog_acc: np.ndarray
    angular_momentum: np.ndarray
    angular_momentum_rate: np.ndarray
    vertical_force: np.ndarray
    planned_zmp: np.ndarray | None = None

    @property
    def zmp_error(self) -> np.ndarray:
        """Multibody ZMP minus planned ZMP per axis (m), shape ``(k, 2)``."""
        if self.planned_zmp is None:
            raise ValueError("no planned ZMP was given to compare with")
        return self.zmp - self.planned_zmp

    @property
    def zmp_error_max(self) -> tuple[float, float]:
        """Largest absolute ZMP error along x and along y (m)."""
        worst = np.abs(self.zmp_error).max(axis=0)
        return float(worst[0]), float(worst[1])

    @property
    def angular_zmp_offset(self) -> np.ndarray:
        """The part of the ZMP due to the rate of angular momentum, ``(-L'_y, L'_x) / f_z`` (m), shape ``(k, 2)``:
        what an angular-momentum compensation has to cancel."""
        rate = self.angular_momentum_rate
        return np.column_stack([-rate[:, 1], rate[:, 0]]) / self.vertical_force[:, None]


def finite_differences(
    model: pin.Model, q: np.ndarray, dt: float, breaks: Sequence[int] = ()
) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations of a configuration trajectory sampled every ``dt`` (s).

    Central differences on the configuration manifold: ``v_k = (q_{k+1} - q_{k-1}) / (2 dt)`` and
    ``a_k = ((q_{k+1} - q_k) - (q_k - q_{k-1})) / dt^2``, where ``-`` is ``pin.difference`` (the free-flyer's
    velocity is in its local frame, as Pinocchio expects). The first and last velocities are one-sided; the
    first and last accelerations repeat their neighbours'.

    A trajectory that jumps (a reference moved at once) has no acceleration at the jump: the second difference
    across a jump ``J`` is ``J / dt^2``, a value of the sampling, not of a motion. ``breaks`` are the ticks ``k`` at
    which the trajectory may jump between ``q_{k-1}`` and ``q_k``: no difference spans them, and each piece between
    two breaks is differentiated as a trajectory of its own (its ends as above). A piece of two ticks has one-sided
    velocities and no acceleration (NaN), one of a single tick neither.

    Args:
        model: the model ``q`` belongs to.
        q: configurations, shape ``(k, nq)``, ``k >= 3``.
        dt: sampling period (s).
        breaks: ticks where a piece starts, each within ``[1, k - 1]``; ``()`` for one smooth trajectory.

    Returns:
        ``v`` and ``a``, each of shape ``(k, nv)`` (m/s and rad/s; m/s^2 and rad/s^2).
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != model.nq or q.shape[0] < 3:
        raise ValueError(f"q must have shape (k >= 3, {model.nq}), got {q.shape}")
    if not (np.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a period > 0 s, got {dt}")
    starts = sorted({int(k) for k in breaks})
    if starts and not 1 <= starts[0] <= starts[-1] <= len(q) - 1:
        raise ValueError(f"breaks must be ticks within [1, {len(q) - 1}], got {starts[0]} to {starts[-1]}")
    # Steps between consecutive samples; everything else is arithmetic on them.
    steps = np.array([pin.difference(model, q[k], q[k + 1]) for k in range(len(q) - 1)])
    v = np.full((len(q), model.nv), np.nan)
    a = np.full_like(v, np.nan)
    for begin, end in zip([0, *starts], [*starts, len(q)], strict=True):
        _differentiate(steps[begin : end - 1], dt, v[begin:end], a[begin:end])
    return v, a


def _differentiate(steps: np.ndarray, dt: float, v: np.ndarray, a: np.ndarray) -> None:
    """Fill the velocities ``v`` and accelerations ``a`` of one smooth piece from its ``len(v) - 1`` steps
    (:func:`finite_differences`); a piece too short for them leaves NaN."""
    if len(steps) == 0:
        return
    v[0] = steps[0] / dt
    v[-1] = steps[-1] / dt
    if len(steps) < 2:
        return
    v[1:-1] = (steps[:-1] + steps[1:]) / (2.0 * dt)
    a[1:-1] = (steps[1:] - steps[:-1]) / (dt * dt)
    a[0] = a[1]
    a[-1] = a[-2]


def multibody_check(
    model: pin.Model,
    times: np.ndarray,
    q: np.ndarray,
    planned_zmp: np.ndarray | None = None,
    breaks: Sequence[int] = (),
) -> MultibodyCheck:
    """Centroidal momentum, its rate and the multibody ZMP of a joint trajectory.

    Args:
        model: the Pinocchio model of ``q`` (e.g. :attr:`RobotModel.model`); its gravity is used.
        times: uniformly spaced tick times (s), shape ``(k,)``.
        q: configurations, shape ``(k, nq)``.
        planned_zmp: optional planned ZMP (m), shape ``(k, 2)``, to compare with.
        breaks: ticks where ``q`` may jump (:func:`finite_differences`); the momentum of a tick without a
            velocity, and its rate, the force and the ZMP of one without an acceleration, are NaN.
    """
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or len(times) < 3:
        raise ValueError("times must be a 1-D array of at least 3 ticks")
    dt = float(times[1] - times[0])
    if not np.allclose(np.diff(times), dt, rtol=1e-6, atol=1e-12):
        raise ValueError("times must be uniformly spaced")
    if planned_zmp is not None:
        planned_zmp = np.asarray(planned_zmp, dtype=float)
        if planned_zmp.shape != (len(times), 2):
            raise ValueError(f"planned_zmp must have shape ({len(times)}, 2), got {planned_zmp.shape}")
    v, a = finite_differences(model, q, dt, breaks)
    moving = np.isfinite(v[:, 0])
    accelerating = np.isfinite(a[:, 0])
    v[~moving] = 0.0  # computed as if at rest, for the COG, then NaN
    a[~accelerating] = 0.0
    data = model.createData()
    mass = pin.computeTotalMass(model)
    gravity = -float(model.gravity.linear[2])
    n = len(times)
    cog = np.empty((n, 3))
    momentum = np.empty((n, 3))
    rate = np.empty((n, 3))
    force = np.empty((n, 3))
    for k in range(n):
        pin.computeCentroidalMomentumTimeVariation(model, data, q[k], v[k], a[k])
        cog[k] = data.com[0]
        # hg and dhg are expressed at the COG with world axes: linear M c', M c''; angular L, L'.
        momentum[k] = data.hg.angular
        rate[k] = data.dhg.angular
        force[k] = data.dhg.linear
    momentum[~moving] = np.nan
    rate[~accelerating] = np.nan
    force[~accelerating] = np.nan
    cog_acc = force / mass
    force[:, 2] += mass * gravity
    # Moment of the contact wrench about the origin: tau = c x f + L'.
    tau = np.cross(cog, force) + rate
    zmp = np.column_stack([-tau[:, 1], tau[:, 0]]) / force[:, 2:3]
    return MultibodyCheck(
        times=times,
        zmp=zmp,
        cog=cog,
        cog_acc=cog_acc,
        angular_momentum=momentum,
        angular_momentum_rate=rate,
        vertical_force=force[:, 2].copy(),
        planned_zmp=planned_zmp,
    )


def check_motion(motion: JointTrajectory, rollout: Rollout | None = None) -> MultibodyCheck:
    """:func:`multibody_check` of a whole-body motion, against the planned ZMP of ``rollout`` if given."""
    planned = None
    if rollout is not None:
        planned = np.column_stack([rollout.column("zmp_x"), rollout.column("zmp_y")])
    return multibody_check(motion.robot.model, motion.times, motion.q, planned)
