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
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.robot.contact_wrenches import DEFAULT_FRICTION, WrenchDistribution, WrenchDistributor, force_transform
from rtgait.robot.drives import joint_drives
from rtgait.robot.model import RobotModel

__all__ = ["InverseDynamics", "RequiredWrench", "wrench_zmp"]

_LOCAL = pin.ReferenceFrame.LOCAL
_ROOT = 1  # the free flyer's joint id
_LAST_ROW = (0.0, 0.0, 0.0, 1.0)  # of a homogeneous matrix
_IDENTITY_ROWS = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
# The calls of a tick, bound once.
_rnea, _joint_jacobians, _frame_jacobian = pin.rnea, pin.computeJointJacobians, pin.getFrameJacobian
_concatenate = np.concatenate


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
        return wrench_zmp([*self.force.tolist(), *self.moment.tolist()], height)


def wrench_zmp(values: Sequence[float], height: float = 0.0) -> tuple[float, float]:
    """:meth:`RequiredWrench.zmp` of the wrench ``values`` (force then moment, world axes about the origin; N, N m)."""
    fx, fy, fz, nx, ny, _ = values
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
    feet's wrenches into :meth:`torques`. A caller that works on Python floats takes :meth:`compute` (the wrench as
    six floats) and :meth:`require_values` instead of :meth:`update` and :meth:`require`.
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
        # Views of what the kinematics rewrite in place in the data (its vectors of placements keep their size): the
        # base's placement, and each sole's translation and rotation (column-major, flattened without a copy), read
        # by one concatenation a tick into the rows the distributor takes.
        data = self.data
        self._base = data.oMi[_ROOT]
        self._placements: list[np.ndarray] = []
        for frame in self._soles:
            placement = data.oMf[frame]
            self._placements += [placement.translation, placement.rotation.T.reshape(9)]
        self._placement_values = np.empty(24)
        self._rows: tuple[list[list[float]], list[list[float]]] = (_IDENTITY_ROWS, _IDENTITY_ROWS)
        self._values: list[float] | None = None  # the wrench to distribute, force then moment (N, N m)
        self._required: RequiredWrench | None = None  # the same as arrays, made when asked for

    def update(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> RequiredWrench:
        """RNEA and the soles' Jacobians at ``q`` (m, quaternion, rad), ``v`` and ``a`` (Pinocchio's velocity
        coordinates, the base's in its own frame); the wrench the feet must give (module docstring)."""
        self.compute(q, v, a)
        return self.required  # type: ignore[return-value]

    def compute(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> list[float]:
        """:meth:`update`'s work, the wrench returned as six Python floats (force then moment; N, N m)."""
        model, data, jacobians = self.model, self.data, self._jacobians
        self._tau = tau = _rnea(model, data, q, v, a)
        _joint_jacobians(model, data, q)  # the placements too (RNEA keeps its own in the joints' frames)
        values = (self._base.toDualActionMatrix() @ tau[:6]).tolist()
        left, right = self._soles
        jacobians[0:6] = _frame_jacobian(model, data, left, _LOCAL)  # also places the frame
        jacobians[6:12] = _frame_jacobian(model, data, right, _LOCAL)
        # The soles' placements as the rows of their homogeneous matrices (the last, constant, left out).
        p = _concatenate(self._placements, out=self._placement_values).tolist()
        self._rows = (
            [[p[3], p[6], p[9], p[0]], [p[4], p[7], p[10], p[1]], [p[5], p[8], p[11], p[2]]],
            [[p[15], p[18], p[21], p[12]], [p[16], p[19], p[22], p[13]], [p[17], p[20], p[23], p[14]]],
        )
        self._values = values
        self._required = None
        return values

    def require(self, wrench: RequiredWrench) -> None:
        """Make ``wrench`` (world axes, about the origin) the one :meth:`distribute` shares out instead of the last
        :meth:`update`'s (e.g. the motion's moved to a commanded ZMP); the torques keep the update's RNEA."""
        self.require_values([*wrench.force.tolist(), *wrench.moment.tolist()])

    def require_values(self, values: list[float]) -> None:
        """:meth:`require` with the wrench as six Python floats (force then moment; N, N m)."""
        if self._values is None:
            raise ValueError("update() must run before require()")
        self._values = values
        self._required = None

    @property
    def required(self) -> RequiredWrench | None:
        """The wrench :meth:`distribute` shares out: the last :meth:`update`'s, or the one required since
        (``None`` before the first)."""
        values = self._values
        if self._required is None and values is not None:
            self._required = RequiredWrench(np.array(values[:3]), np.array(values[3:]))
        return self._required

    @property
    def sole_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """The left and right sole frames' placements at the last :meth:`update`, 4x4 homogeneous matrices (m)."""
        rows = self._rows
        return np.array([*rows[0], _LAST_ROW]), np.array([*rows[1], _LAST_ROW])

    @property
    def sole_rows(self) -> tuple[list[list[float]], list[list[float]]]:
        """:attr:`sole_frames`' first three rows as Python floats (the lists the next :meth:`update` replaces)."""
        return self._rows

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
        values = self._values
        if values is None:
            raise ValueError("update() must run before distribute()")
        return self.distributor.distribute_rows(
            values[:3], values[3:], self._rows, contact, left_ratio, (left_cop, right_cop)
        )

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
        frame = np.array([*self._rows[side], _LAST_ROW])  # that sole's placement alone
        return np.linalg.solve(force_transform(frame), np.asarray(world, dtype=float))
