"""Feed-forward joint torques from whole-body inverse dynamics with the contact wrenches the controller asks for.

The floating-base model (free flyer first) at configuration ``q``, velocity ``v`` and acceleration ``a`` obeys

    M(q) a + h(q, v) = S^T tau + sum_i J_i(q)^T w_i                                                  (N m, N)

with ``J_i`` the sole frames' Jacobians (frame axes) and ``w_i`` the feet's wrenches (sole frame, about the sole point;
:mod:`rtgait.robot.contact_wrenches`), ``S`` the joints' rows. The base's six rows carry no torque, so the wrenches
must balance them: carried to the world origin, the base's part of RNEA is the wrench

    W = X_base [RNEA(q, v, a)]_base = (M (c'' - g), L' + c x M (c'' - g))                            (N, N m)

(the rate of centroidal momentum less gravity's wrench, ``g = (0, 0, -9.81)``), and ``sum X_i w_i = W``. The joints'
rows then give the feed-forward

    tau = [RNEA(q, v, a)]_joints - sum_i [J_i]_joints^T w_i.                                          (N m)

Pinocchio's RNEA adds each joint's armature times its acceleration: the drives' reflected rotor inertia, set here from
the robot description as the simulated drives take it (:func:`~rtgait.robot.drives.joint_drives`).

One tick costs one RNEA, one ``computeJointJacobians`` and two frame Jacobians (some 10 us of Pinocchio for Talos),
the distribution (a 6x6 solve; the QP of :mod:`rtgait.robot.contact_wrenches` only when a cone binds) and the
products.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.robot.contact_wrenches import DEFAULT_FRICTION, WrenchDistribution, WrenchDistributor, force_transform
from rtgait.robot.drives import joint_drives
from rtgait.robot.model import RobotModel

__all__ = ["InverseDynamics", "RequiredWrench"]

_LOCAL = pin.ReferenceFrame.LOCAL
_ROOT = 1  # the free flyer's joint id


class RequiredWrench(NamedTuple):
    """The wrench the feet must give the robot for its motion (world axes, about the world origin).

    Attributes:
        force: ``M (c'' - g)`` (N).
        moment: ``L' + c x M (c'' - g)`` (N m).
    """

    force: np.ndarray
    moment: np.ndarray

    def zmp(self, height: float = 0.0) -> tuple[float, float]:
        """The point of the plane ``z = height`` (m) about which the wrench has no horizontal moment (m); NaN
        without an upward force."""
        (fx, fy, fz), (nx, ny, _) = self.force.tolist(), self.moment.tolist()
        if not fz > 0.0:
            return math.nan, math.nan
        return (height * fx - ny) / fz, (nx + height * fy) / fz


class InverseDynamics:
    """Whole-body inverse dynamics of a robot standing or walking on its soles (module docstring).

    Args:
        robot: the loaded robot (its reduced model: the IK's configurations).
        sole: the sole rectangle around the sole points (m).
        friction: the floor's Coulomb friction coefficient (:mod:`rtgait.robot.contact_wrenches`).
        armature: the joints' reflected rotor inertias (kg m^2), one per joint; ``None``: the description's
            (:func:`~rtgait.robot.drives.joint_drives`).

    Use: :meth:`update` at the tick's ``(q, v, a)``, then :meth:`distribute` the wrench it returns and turn the
    feet's wrenches into :meth:`torques`.
    """

    def __init__(
        self,
        robot: RobotModel,
        sole: SoleRect,
        friction: float = DEFAULT_FRICTION,
        armature: np.ndarray | None = None,
    ) -> None:
        model = pin.Model(robot.model)  # its own copy: the armature is set on it
        armature = joint_drives(robot)[1] if armature is None else np.asarray(armature, dtype=float)
        if armature.shape != (model.nv - 6,) or not (np.isfinite(armature).all() and (armature >= 0.0).all()):
            raise ValueError(f"armature must be {model.nv - 6} finite inertias >= 0 kg m^2, got {armature!r}")
        model.armature[:6] = 0.0
        model.armature[6:] = armature
        self.robot, self.model, self.data = robot, model, model.createData()
        self.distributor = WrenchDistributor(sole, friction)
        self._soles = (robot.left_sole_id, robot.right_sole_id)
        self._tau = np.zeros(model.nv)
        # Both soles' Jacobians stacked, rewritten in place each tick; their joints' columns transposed, a view.
        self._jacobians = np.zeros((12, model.nv))
        self._joints_t = self._jacobians[:, 6:].T
        self._base_t = self._jacobians[:, :6].T
        self._frames: tuple[np.ndarray, np.ndarray] = (np.eye(4), np.eye(4))
        self._required: RequiredWrench | None = None

    def update(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> RequiredWrench:
        """RNEA and the soles' Jacobians at ``q`` (m, quaternion, rad), ``v`` and ``a`` (Pinocchio's velocity
        coordinates, the base's in its own frame); the wrench the feet must give (module docstring)."""
        model, data, jacobians = self.model, self.data, self._jacobians
        self._tau = tau = pin.rnea(model, data, q, v, a)
        pin.computeJointJacobians(model, data, q)  # the placements too (RNEA keeps its own in the joints' frames)
        wrench = data.oMi[_ROOT].toDualActionMatrix() @ tau[:6]
        left, right = self._soles
        jacobians[0:6] = pin.getFrameJacobian(model, data, left, _LOCAL)  # also places the frame
        jacobians[6:12] = pin.getFrameJacobian(model, data, right, _LOCAL)
        placements = data.oMf
        self._frames = (placements[left].homogeneous, placements[right].homogeneous)
        self._required = required = RequiredWrench(wrench[:3], wrench[3:])
        return required

    def require(self, wrench: RequiredWrench) -> None:
        """Make ``wrench`` (world axes, about the origin) the one :meth:`distribute` shares out instead of the last
        :meth:`update`'s (e.g. the motion's moved to a commanded ZMP); the torques keep the update's RNEA."""
        if self._required is None:
            raise ValueError("update() must run before require()")
        self._required = wrench

    @property
    def required(self) -> RequiredWrench | None:
        """The last :meth:`update`'s required wrench (``None`` before the first)."""
        return self._required

    @property
    def sole_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """The left and right sole frames' placements at the last :meth:`update`, 4x4 homogeneous matrices (m)."""
        return self._frames

    def distribute(
        self,
        contact: tuple[bool, bool],
        left_ratio: float = 0.5,
        left_cop: tuple[float, float] | None = None,
        right_cop: tuple[float, float] | None = None,
    ) -> WrenchDistribution:
        """The feet's wrenches for the last :meth:`update`'s required wrench
        (:class:`~rtgait.robot.contact_wrenches.WrenchDistributor`).

        Args:
            contact: whether the left and the right foot carry load (at least one).
            left_ratio: in double support, the left foot's desired share of the force, in [0, 1].
            left_cop, right_cop: the desired centres of pressure, world ``(x, y)`` (m); ``None``: the sole point.
        """
        required = self._required
        if required is None:
            raise ValueError("update() must run before distribute()")
        force, moment = required.force.tolist(), required.moment.tolist()
        return self.distributor.distribute(force, moment, self._frames, contact, left_ratio, (left_cop, right_cop))

    def torques(self, wrenches: np.ndarray) -> np.ndarray:
        """The joints' feed-forward torques (N m) of the last :meth:`update` with the feet's ``wrenches`` (shape ``(2,
        6)``, left then right, sole frame about the sole point): ``RNEA - sum J^T w`` on the joints' rows."""
        return self._tau[6:] - self._joints_t @ wrenches.reshape(12)

    def base_residual(self, wrenches: np.ndarray) -> np.ndarray:
        """What the ``wrenches`` leave of the base's rows, ``[RNEA]_base - sum [J_i]_base^T w_i`` (N, N m; the base's
        frame): zero when they balance the motion."""
        return self._tau[:6] - self._base_t @ np.asarray(wrenches, dtype=float).reshape(12)

    def sole_wrench(self, side: int, world: np.ndarray) -> np.ndarray:
        """A wrench given in world axes about the world origin (force then moment) as the sole ``side`` (0 left, 1
        right) takes it, sole frame about the sole point (at the last :meth:`update`)."""
        return np.linalg.solve(force_transform(self._frames[side]), np.asarray(world, dtype=float))
