"""The contact wrenches the feet are asked for: the desired per-foot split made to sum to the motion's wrench, within
each sole's contact wrench cone.

A foot's wrench ``w = (f, tau)`` (N, N m) is the ground's force on the sole and its moment about the sole point, in the
sole frame's axes (x forward, y left, z out of the floor). Its centre of pressure is ``(-tau_y / f_z, tau_x / f_z)``.

**The contact wrench cone** of a rectangular sole of half-sizes ``X`` (along x) and ``Y`` (along y) centred at
``s`` in the sole frame, with a friction pyramid ``|f_x|, |f_y| <= mu f_z`` at every point, is the set of the wrenches
of the four corners' pyramid forces. About the centre (``tau_c = tau - s x f``) its faces are (Caron, Pham and Nakamura,
"Stability of surface contacts for humanoid robots", ICRA 2015)

    |f_x| <= mu f_z,   |f_y| <= mu f_z,   |tau_c,x| <= Y f_z,   |tau_c,y| <= X f_z,
    tau_min <= tau_c,z <= tau_max,
    tau_min = -mu (X + Y) f_z + |Y f_x - mu tau_c,x| + |X f_y - mu tau_c,y|,
    tau_max =  mu (X + Y) f_z - |Y f_x + mu tau_c,x| - |X f_y + mu tau_c,y|

(16 half-spaces ``H w <= 0``) and its generators the 16 corner forces ``(+-mu, +-mu, 1)`` at the corners. ``mu`` is the
pyramid's, inscribed in the floor's Coulomb cone: ``mu = friction / sqrt(2)``.

**Distribution.** The feet in contact must sum to the required wrench ``W = (F, N)`` (world axes, about the origin). In
single support the stance foot takes it all. In double support the wrenches nearest the desired ones ``w_i^d`` (the
controller's split, :mod:`rtgait.control.foot_control`: a share ``s_i`` of ``F`` at a CoP ``c_i`` per foot),

    min sum |S (w_i - w_i^d)|^2   s.t.   sum X_i w_i = W,      S = diag(1, 1, 1, 1/L, 1/L, 1/L)

(``X_i`` the sole's force transform to the world, ``L`` the sole's half-length so that a moment ``f L`` weighs as a
force ``f``), are ``w = w^d + Q^-1 A^T (A Q^-1 A^T)^-1 (W - A w^d)`` with ``A = [X_1 X_2]``, ``Q = S^2``. The weights
are the same in every frame, so the sum can be taken about the sole points' midpoint ``m``, the soles at ``m +- d``:
``A Q^-1 A^T`` is then ``2 diag(I, B)``, ``B = (L^2 + |d|^2) I - d d^T``, whose inverse is
``(I + d d^T / L^2) / (L^2 + |d|^2)``. In world axes about each sole point, with the moment still missing about ``m``,
``r = N - m x F - (c - m) x F`` (``c = s_1 c_1 + s_2 c_2``; the desired forces already sum to ``F``):

    y = B^-1 r / 2,     f_1 = s_1 F + y x d,    f_2 = s_2 F - y x d,    tau_i = (c_i - p_i) x s_i F + L^2 y

(no solver). When that leaves a cone (a CoP beyond its sole, friction beyond ``mu``, a pulling foot) and the split asks
everything of one foot whose cone holds ``W`` (the commanded ZMP at the end of the segment between the feet), that foot
takes it all. Otherwise, and in single support when the stance foot's cone does not hold ``W``, a small QP runs, on the
corner forces ``lambda >= 0`` of the generators ``G_i`` (``w_i = G_i lambda_i``, so every wrench it gives is in its
cone), the sum as rows of weight :data:`SUM_WEIGHT`:

    min  SUM_WEIGHT^2 |S (sum X_i G_i lambda_i - W)|^2 + sum |S (G_i lambda_i - w_i^d)|^2,   lambda >= 0

(non-negative least squares, ``scipy.optimize.nnls``: some 60 us a tick with the matrix; in single support ``w^d`` is
the exact wrench). A required wrench no cone can give (the motion's ZMP outside the support polygon) gets the nearest
one they can; its :attr:`WrenchDistribution.residual` says how far.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from operator import le as _le
from typing import NamedTuple

import numpy as np
from scipy.optimize import nnls

from rtgait.core.geometry.footsteps import SoleRect

__all__ = [
    "DEFAULT_FRICTION",
    "SUM_WEIGHT",
    "SoleCone",
    "WrenchDistribution",
    "WrenchDistributor",
    "force_transform",
]

DEFAULT_FRICTION = 1.0
"""The floor's Coulomb friction coefficient: rubber on a dry floor, the simulated floor's
(:class:`rtgait.sim.config.SimConfig` ``friction``). The pyramid inside its cone has ``mu = 0.71``."""

SUM_WEIGHT = 1e3
"""Weight of the sum's rows in the QP against the deviation's (module docstring): a feasible sum is met to about
``1e-6`` of the deviation from the desired wrenches."""

_CONE_TOLERANCE = 1e-9  # N (times the sole's half-length for moments): a wrench this far outside is inside
_NO_WRENCH = (0.0,) * 6  # a foot's wrench out of contact
_array = np.array
_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing


class SoleCone:
    """The contact wrench cone of one sole (module docstring), in its sole frame about the sole point.

    Args:
        sole: the sole rectangle around the sole point (m).
        side: ``"left"`` or ``"right"`` (the rectangle's inner side faces the other foot).
        mu: the friction pyramid's coefficient, ``> 0``.

    Attributes:
        faces: ``H``, shape ``(16, 6)``: a wrench ``w`` is in the cone when ``H w <= 0``.
        generators: ``G``, shape ``(6, 16)``: the corner forces' wrenches; the cone is ``{G lambda, lambda >= 0}``.
    """

    def __init__(self, sole: SoleRect, side: str, mu: float) -> None:
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        if not (math.isfinite(mu) and mu > 0.0):
            raise ValueError(f"the friction pyramid's mu must be > 0, got {mu}")
        y_low, y_high = (-sole.inner, sole.outer) if side == "left" else (-sole.outer, sole.inner)
        half_x, half_y = 0.5 * (sole.front + sole.back), 0.5 * (y_high - y_low)
        centre = np.array([0.5 * (sole.front - sole.back), 0.5 * (y_high + y_low), 0.0])
        X, Y = half_x, half_y
        rows = [
            [1, 0, -mu, 0, 0, 0], [-1, 0, -mu, 0, 0, 0], [0, 1, -mu, 0, 0, 0], [0, -1, -mu, 0, 0, 0],
            [0, 0, -Y, 1, 0, 0], [0, 0, -Y, -1, 0, 0], [0, 0, -X, 0, 1, 0], [0, 0, -X, 0, -1, 0],
        ]  # fmt: skip
        for sx in (1.0, -1.0):
            for sy in (1.0, -1.0):
                # tau_z >= tau_min and tau_z <= tau_max, each absolute value opened by its signs.
                rows.append([sx * Y, sy * X, -mu * (X + Y), -sx * mu, -sy * mu, -1.0])
                rows.append([sx * Y, sy * X, -mu * (X + Y), sx * mu, sy * mu, 1.0])
        # About the centre: tau_c = tau - s x f = tau + [s]x^T f, folded into the faces.
        shift = np.eye(6)
        shift[3:6, 0:3] = -_skew(centre)
        self.faces = np.array(rows, dtype=float) @ shift
        generators = []
        for cx in (sole.front, -sole.back):
            for cy in (y_high, y_low):
                corner = np.array([cx, cy, 0.0])
                for ex, ey in ((1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)):
                    force = np.array([ex * mu, ey * mu, 1.0])
                    generators.append(np.concatenate([force, np.cross(corner, force)]))
        self.generators = np.array(generators).T
        self.length = max(half_x, 1e-3)  # L of the module docstring

    def contains(self, wrench: np.ndarray) -> bool:
        """Whether ``wrench`` (sole frame, about the sole point) is in the cone, to :data:`_CONE_TOLERANCE`."""
        return float((self.faces @ wrench).max()) <= _CONE_TOLERANCE * self.length

    def cop(self, wrench: np.ndarray) -> tuple[float, float]:
        """The centre of pressure of ``wrench`` in the sole frame (m); NaN without a normal force."""
        fz = float(wrench[2])
        if fz <= 0.0:
            return math.nan, math.nan
        return -float(wrench[4]) / fz, float(wrench[3]) / fz


class WrenchDistribution(NamedTuple):
    """The feet's wrenches for one tick.

    Attributes:
        wrenches: shape ``(2, 6)``, left then right, each ``(f, tau)`` in its sole frame about the sole point (N,
            N m); zeros for a foot not in contact.
        method: ``"single"`` (one foot carries it all), ``"closed-form"`` (the double-support projection) or
            ``"qp"`` (the closed form left a cone).
        residual: the weighted norm of what the wrenches miss of the required one, ``|S (W - sum X_i w_i)|`` (N); 0
            to rounding unless no distribution in the cones gives it.
    """

    wrenches: np.ndarray
    method: str
    residual: float


class WrenchDistributor:
    """Distributes a required wrench over the feet in contact (module docstring).

    Args:
        sole: the sole rectangle (m).
        friction: the floor's Coulomb friction coefficient, ``> 0``; the pyramid's ``mu`` is ``friction / sqrt(2)``.

    Attributes:
        cones: the left and right soles' cones.
        qp_count: ticks on which the QP ran.
    """

    def __init__(self, sole: SoleRect, friction: float = DEFAULT_FRICTION) -> None:
        if not (math.isfinite(friction) and friction > 0.0):
            raise ValueError(f"friction must be a coefficient > 0, got {friction}")
        mu = friction / math.sqrt(2.0)
        self.sole, self.friction, self.mu = sole, float(friction), mu
        self.cones = (SoleCone(sole, "left", mu), SoleCone(sole, "right", mu))
        length = self.cones[0].length
        self._length2 = length * length
        self._scale = np.array([1.0, 1.0, 1.0, 1.0 / length, 1.0 / length, 1.0 / length])
        self._sum_scale = SUM_WEIGHT * self._scale
        self._scaled_generators = tuple(self._scale[:, None] * cone.generators for cone in self.cones)
        # Both cones' faces in one block matrix: one product checks both feet.
        self._faces = np.zeros((32, 12))
        self._faces[:16, :6] = self.cones[0].faces
        self._faces[16:, 6:] = self.cones[1].faces
        self._tolerance = _CONE_TOLERANCE * length
        self._tolerances = [self._tolerance] * 32  # one per face, for _within
        self.qp_count = 0

    def distribute(
        self,
        force: Sequence[float],
        moment: Sequence[float],
        frames: Sequence[np.ndarray],
        contact: tuple[bool, bool],
        left_ratio: float = 0.5,
        cops: Sequence[Sequence[float] | None] = (None, None),
    ) -> WrenchDistribution:
        """The feet's wrenches for the required wrench ``W = (force, moment)``.

        Args:
            force, moment: ``W``, world axes, about the world origin (N, N m).
            frames: each sole frame's placement in the world, a 4x4 homogeneous matrix (m), left then right.
            contact: whether the left and the right foot are in contact (at least one).
            left_ratio: in double support, the left foot's share of the force, in [0, 1].
            cops: in double support, each foot's desired CoP, world ``(x, y)`` on its sole's plane (m); ``None``: the
                sole point.
        """
        rows = (frames[0].tolist(), frames[1].tolist())
        return self.distribute_rows(force, moment, rows, contact, left_ratio, cops)

    def distribute_rows(
        self,
        force: Sequence[float],
        moment: Sequence[float],
        rows: Sequence[list[list[float]]],
        contact: tuple[bool, bool],
        left_ratio: float = 0.5,
        cops: Sequence[Sequence[float] | None] = (None, None),
    ) -> WrenchDistribution:
        """:meth:`distribute` with each sole frame's placement as the rows of its homogeneous matrix in Python floats
        (the first three at least: ``[R | p]``)."""
        fx, fy, fz = force
        nx, ny, nz = moment
        left, right = rows
        if contact[0] and contact[1]:
            if not (math.isfinite(left_ratio) and 0.0 <= left_ratio <= 1.0):
                raise ValueError(f"left_ratio must be within [0, 1], got {left_ratio}")
            pl = (left[0][3], left[1][3], left[2][3])
            pr = (right[0][3], right[1][3], right[2][3])
            cl = pl if cops[0] is None else (cops[0][0], cops[0][1], pl[2])
            cr = pr if cops[1] is None else (cops[1][0], cops[1][1], pr[2])
            sl, sr = left_ratio, 1.0 - left_ratio
            mx, my, mz = 0.5 * (pl[0] + pr[0]), 0.5 * (pl[1] + pr[1]), 0.5 * (pl[2] + pr[2])
            dx, dy, dz = pl[0] - mx, pl[1] - my, pl[2] - mz
            # The moment the desired wrenches miss about m: N - m x F - (c - m) x F = N - c x F.
            cx, cy, cz = sl * cl[0] + sr * cr[0], sl * cl[1] + sr * cr[1], sl * cl[2] + sr * cr[2]
            rx, ry, rz = nx - (cy * fz - cz * fy), ny - (cz * fx - cx * fz), nz - (cx * fy - cy * fx)
            length2 = self._length2
            along = (dx * rx + dy * ry + dz * rz) / length2
            k = 0.5 / (length2 + dx * dx + dy * dy + dz * dz)
            yx, yy, yz = k * (rx + dx * along), k * (ry + dy * along), k * (rz + dz * along)
            ex, ey, ez = yy * dz - yz * dy, yz * dx - yx * dz, yx * dy - yy * dx  # y x d
            wl = _local(left, sl * fx + ex, sl * fy + ey, sl * fz + ez, cl, pl, sl, force, length2, (yx, yy, yz))
            wr = _local(right, sr * fx - ex, sr * fy - ey, sr * fz - ez, cr, pr, sr, force, length2, (yx, yy, yz))
            wrenches = _array((wl, wr))
            if _within(self._faces @ wrenches.reshape(12), self._tolerances):
                return _new_tuple(WrenchDistribution, (wrenches, "closed-form", 0.0))
            if sl == 1.0 or sr == 1.0:  # all asked of one foot (the split at the segment's end): that foot alone?
                alone = self._single(0 if sl == 1.0 else 1, rows, force, moment)
                if alone.method == "single":
                    return alone
            # The desired wrenches, for the QP (the closed form with y = 0).
            desired = np.array((
                _local(left, sl * fx, sl * fy, sl * fz, cl, pl, sl, force, 0.0, (0.0, 0.0, 0.0)),
                _local(right, sr * fx, sr * fy, sr * fz, cr, pr, sr, force, 0.0, (0.0, 0.0, 0.0)),
            ))  # fmt: skip
            return self._qp(force, moment, rows, desired, (0, 1))
        if not (contact[0] or contact[1]):
            raise ValueError("at least one foot must be in contact to carry the robot")
        single = self._single(0 if contact[0] else 1, rows, force, moment)
        if single.method == "single":
            return single
        return self._qp(force, moment, rows, single.wrenches, (0 if contact[0] else 1,))

    def _single(
        self, i: int, rows: Sequence[list[list[float]]], force: Sequence[float], moment: Sequence[float]
    ) -> WrenchDistribution:
        """The whole wrench on foot ``i`` (0 left, 1 right): method ``"single"`` when its cone holds it, else
        ``"outside"`` (the wrench as it is)."""
        fx, fy, fz = force
        nx, ny, nz = moment
        h = rows[i]
        px, py, pz = h[0][3], h[1][3], h[2][3]
        # The whole wrench about the sole point: N - p x F.
        tx, ty, tz = nx - (py * fz - pz * fy), ny - (pz * fx - px * fz), nz - (px * fy - py * fx)
        wrench = _rotate_back(h, fx, fy, fz) + _rotate_back(h, tx, ty, tz)
        wrenches = _array((wrench, _NO_WRENCH) if i == 0 else (_NO_WRENCH, wrench))
        inside = _within(self.cones[i].faces @ wrenches[i], self._tolerances)
        return _new_tuple(WrenchDistribution, (wrenches, "single" if inside else "outside", 0.0))

    def _qp(
        self,
        force: Sequence[float],
        moment: Sequence[float],
        frames: Sequence[list[list[float]]],
        desired: np.ndarray,
        feet: tuple[int, ...],
    ) -> WrenchDistribution:
        """The corner-force QP of the module docstring for the feet ``feet``, ``desired`` of shape ``(2, 6)``, the sole
        frames as :meth:`WrenchDistributor.distribute_rows` takes them."""
        self.qp_count += 1
        n = 16
        rows = 6 * (1 + len(feet))
        matrix = np.zeros((rows, n * len(feet)))
        rhs = np.empty(rows)
        sum_scale = self._sum_scale
        rhs[0:6] = sum_scale * np.array([*force, *moment])
        for k, i in enumerate(feet):
            columns = slice(n * k, n * (k + 1))
            transform = force_transform(np.array(frames[i]))
            matrix[0:6, columns] = (sum_scale[:, None] * transform) @ self.cones[i].generators
            matrix[6 * (k + 1) : 6 * (k + 2), columns] = self._scaled_generators[i]
            rhs[6 * (k + 1) : 6 * (k + 2)] = self._scale * desired[i]
        forces, _ = nnls(matrix, rhs)
        wrenches = np.zeros((2, 6))
        for k, i in enumerate(feet):
            wrenches[i] = self.cones[i].generators @ forces[n * k : n * (k + 1)]
        residual = float(np.linalg.norm(rhs[0:6] - matrix[0:6] @ forces)) / SUM_WEIGHT
        return WrenchDistribution(wrenches, "qp", residual)


def _within(values: np.ndarray, tolerances: list[float]) -> bool:
    """Whether every value of a cone's faces times a wrench is at most its tolerance: ``values.max() <= tolerance``,
    compared as Python floats (a NaN fails both), without numpy's reduction calls."""
    return all(map(_le, values.tolist(), tolerances))


def _local(
    h: list[list[float]],
    fx: float,
    fy: float,
    fz: float,
    cop: tuple[float, float, float],
    point: tuple[float, float, float],
    share: float,
    force: Sequence[float],
    length2: float,
    y: tuple[float, float, float],
) -> tuple[float, ...]:
    """A foot's wrench in its sole frame from its world-axes force ``f`` and the moment ``(c - p) x s F + L^2 y``
    about its sole point ``p`` (module docstring)."""
    ax, ay, az = cop[0] - point[0], cop[1] - point[1], cop[2] - point[2]
    gx, gy, gz = share * force[0], share * force[1], share * force[2]
    tx = ay * gz - az * gy + length2 * y[0]
    ty = az * gx - ax * gz + length2 * y[1]
    tz = ax * gy - ay * gx + length2 * y[2]
    return _rotate_back(h, fx, fy, fz) + _rotate_back(h, tx, ty, tz)


def _rotate_back(h: list[list[float]], x: float, y: float, z: float) -> tuple[float, float, float]:
    """``R^T v`` for the rotation of the homogeneous matrix ``h``: a world vector in the frame's axes."""
    h0, h1, h2 = h[0], h[1], h[2]
    return (
        h0[0] * x + h1[0] * y + h2[0] * z,
        h0[1] * x + h1[1] * y + h2[1] * z,
        h0[2] * x + h1[2] * y + h2[2] * z,
    )


def force_transform(h: np.ndarray) -> np.ndarray:
    """The 6x6 matrix taking a wrench in the frame ``h`` (about its origin) to world axes about the world origin:
    ``[[R, 0], [p x R, R]]``."""
    rotation, position = h[:3, :3], h[:3, 3]
    transform = np.zeros((6, 6))
    transform[:3, :3] = rotation
    transform[3:, 3:] = rotation
    transform[3:, :3] = _skew(position) @ rotation
    return transform


def _skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix of ``v``: ``_skew(v) @ u = v x u``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
