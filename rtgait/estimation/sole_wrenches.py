"""The ground's wrench on each sole, in the sole frame about its origin, from a foot force/torque sensor or, on a
robot without one, from the leg's joint torques.

**From a force/torque sensor** mounted at ``p`` with rotation ``R_s`` in the sole frame
(:class:`~rtgait.interface.body_kinematics.ForceSensorMount`), reading ``(f, t)`` in its own frame: the wrench the
sensor passes to the leg, moved to the sole origin, is ``f_s = R_s f``, ``t_s = R_s t + p x f_s``. Between sensor
and ground hangs a mass ``m`` centred at ``c`` (the foot below an ankle sensor), whose weight the sensor also
carries. At rest (a foot in contact is), the ground's wrench is the sensor's minus that weight, ``g_S`` the gravity
vector in the sole frame (m/s^2):

    f_ground = f_s - m g_S,        t_ground = t_s - c x (m g_S)                             (N, N m)

The foot's acceleration times its mass is left out here, for the wrench the estimator reports (a foot in contact
is still); the load detection takes it out of the vertical force (:mod:`rtgait.estimation.foot_inertia`).

**From joint torques** (a leg without a force sensor, the G1's). The dynamics of a leg's joints,
``M_l q'' + h_l = tau_l + J^T F``, with ``J`` the sole frame's 6 x n Jacobian with respect to the leg's joints
(rows linear then angular, sole frame) and ``F = (f, t)`` the ground's wrench on the sole in that frame, give with
``tau_id = M_l q'' + h_l`` the torques the leg's motion needs with the sole free (its inverse dynamics)

    J^T F = tau_id - tau_l        =>        F = J^-T (tau_id - tau_l)                          (N, N m)

for a six-joint leg (least squares otherwise); at rest ``tau_id`` is the leg's gravity torques. Where the motion
comes from and what filters it: :mod:`rtgait.estimation.torque_wrenches`. The Jacobian is singular for a straight
knee, where ``F`` is not observable along the leg's axis (then the least-squares wrench).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.linalg.lapack import dgesv as _gesv

from rtgait.interface.body_kinematics import ForceSensorMount
from rtgait.interface.readings import Wrench

__all__ = ["SoleWrench", "leg_wrench", "sensor_wrench", "torque_wrenches"]

SoleWrench = tuple[float, float, float, float, float, float]
"""``(fx, fy, fz, tx, ty, tz)``: the ground's force on a sole (N) and its moment about the sole origin (N m), in the
sole frame."""


def sensor_wrench(
    reading: Wrench, mount: ForceSensorMount, gravity: tuple[float, float, float], zero: SoleWrench | None = None
) -> SoleWrench:
    """The ground's wrench on a sole from its force sensor's ``reading`` (module docstring); ``gravity`` is the gravity
    vector in the sole frame (m/s^2); ``zero``: the sensor's zero in the sole frame, taken off too
    (:mod:`rtgait.estimation.sensor_zero`)."""
    (fx, fy, fz), (tx, ty, tz) = reading
    (px, py, pz), r, m, (cx, cy, cz) = mount
    # In the sole frame: f_s = R_s f, t_s = R_s t + p x f_s.
    ax = r[0] * fx + r[1] * fy + r[2] * fz
    ay = r[3] * fx + r[4] * fy + r[5] * fz
    az = r[6] * fx + r[7] * fy + r[8] * fz
    bx = r[0] * tx + r[1] * ty + r[2] * tz + (py * az - pz * ay)
    by = r[3] * tx + r[4] * ty + r[5] * tz + (pz * ax - px * az)
    bz = r[6] * tx + r[7] * ty + r[8] * tz + (px * ay - py * ax)
    if zero is not None:
        z0, z1, z2, z3, z4, z5 = zero
        ax, ay, az, bx, by, bz = ax - z0, ay - z1, az - z2, bx - z3, by - z4, bz - z5
    if m == 0.0:
        return ax, ay, az, bx, by, bz
    wx, wy, wz = m * gravity[0], m * gravity[1], m * gravity[2]  # the weight below the sensor
    return (ax - wx, ay - wy, az - wz, bx - (cy * wz - cz * wy), by - (cz * wx - cx * wz), bz - (cx * wy - cy * wx))


def torque_wrenches(
    jacobians: Sequence[np.ndarray], needed: np.ndarray, torques: np.ndarray
) -> tuple[SoleWrench, SoleWrench]:
    """The ground's wrench on each sole from its leg's joint torques (module docstring).

    Args:
        jacobians: the left and right soles' Jacobians with respect to their legs' joints, shape ``(6, n)`` each, rows
            linear then angular, sole frame.
        needed: the torques each leg's motion needs with the sole free, ``tau_id`` (N m), shape ``(2, n)``.
        torques: the legs' measured joint torques (N m), shape ``(2, n)``.

    Returns:
        The left and right soles' wrenches.
    """
    left, right = needed - torques
    return leg_wrench(jacobians[0], left), leg_wrench(jacobians[1], right)


def leg_wrench(jacobian: np.ndarray, residual: np.ndarray) -> SoleWrench:
    """The wrench ``F`` with ``J^T F = residual``: a sole's Jacobian ``J`` with respect to its leg's joints, shape
    ``(6, n)``, and the leg's residual torques ``tau_id - tau_l`` (N m), shape ``(n,)`` (module docstring)."""
    jt = jacobian.T
    if jt.shape[0] == 6:
        # LAPACK's solver called directly: numpy's solve costs four times as much on a 6 x 6.
        _, _, wrench, info = _gesv(jt, residual)
        if info == 0:
            return tuple(wrench.tolist())  # type: ignore[return-value]
    # A leg of other than six joints, or a singular Jacobian: the least-squares (or least-norm) wrench.
    return tuple(np.linalg.lstsq(jt, residual, rcond=None)[0].tolist())  # type: ignore[return-value]
