"""Leg odometry about the centre of pressure: the point of a stance foot that stays still when the foot rocks.

The kinematic velocity of the base (:mod:`rtgait.estimation.kinematic_inertial`, step 4) holds each loaded sole's
frame origin still: ``v_B = -(w x p_i) - p_i'`` with ``p_i`` the sole origin relative to the base (base frame) and
``w`` the base's angular velocity. That is right for a foot flat on the ground. A foot that rocks on an edge or a
corner (a landing on the toe after a push, a foot rolling on its outer edge) turns in the world at
``w_i = w + w_rel,i`` (the gyro plus the leg's joints) about its contact, and its origin moves at
``w_i x (p_i - q_i)``, ``q_i`` the contact point: the velocity held-still-origin odometry reports is off by that
much. The point that does not move is the contact itself, which the foot's wrench locates: the centre of pressure
``c_i = (-t_y, t_x, 0) / f_z`` in the sole frame (the wrench about the sole origin). Holding ``q_i = p_i + R_i c_i``
still instead of ``p_i`` gives

    v_B = -(w x q_i) - q_i' = -(w x p_i) - p_i' - w_i x (R_i c_i),        q_i' = p_i' + w_rel,i x (R_i c_i)

(``R_i`` the sole's rotation in the base frame, ``c_i`` fixed on the sole while the foot rocks about it). For a foot
flat and still, ``w_i = 0`` and the correction vanishes: it changes nothing where the flat-foot odometry was right.
Force-weighted over the loaded feet like the odometry itself (weights ``s_i``), the correction is
``-sum_i s_i w_i x (R_i c_i)``. The centre of pressure is clamped to the sole's rectangle: a wrench estimated from
joint torques (G1) errs by newton metres, which puts the centre of pressure of a foot carrying a few tens of newtons
(a landing that bounces) tens of centimetres off the foot, and the contact cannot be outside the sole.

Pronto's leg odometry (Camurri 2017) and contact-aided filters (Bloesch 2013, Hartley 2020) likewise put the
no-slip constraint on the contact point rather than on a frame of the foot.
"""

from __future__ import annotations

__all__ = ["rocking_correction"]

Vec3 = tuple[float, float, float]
Extents = tuple[float, float, float, float]
"""A sole's rectangle in its frame: ``(x_min, x_max, y_min, y_max)`` (m)."""


def rocking_correction(
    angular_velocity: Vec3,
    rotation: tuple[float, ...],
    relative_angular_velocity: Vec3,
    wrench: tuple[float, ...],
    share: float,
    extents: Extents | None,
) -> Vec3:
    """One loaded foot's term of the correction (m/s, base frame) to add to the flat-foot kinematic velocity of the
    base, ``-s_i w_i x (R_i c_i)`` (module docstring); sum it over the loaded feet.

    Args:
        angular_velocity: the base's angular velocity ``w`` (rad/s, base frame).
        rotation: the sole's rotation in the base frame (row-major 3x3).
        relative_angular_velocity: its angular velocity relative to the base from the joints (rad/s, base frame).
        wrench: the ground's wrench on it in the sole frame about its origin ``(fx, fy, fz, tx, ty, tz)`` (N, N m).
        share: its share ``s_i`` of the odometry.
        extents: the sole's rectangle that bounds the centre of pressure (``None``: unbounded).

    A foot without a positive normal force is held at its origin (no correction).
    """
    fz = wrench[2]
    if not fz > 0.0:
        return (0.0, 0.0, 0.0)
    px, py = -wrench[4] / fz, wrench[3] / fz  # the centre of pressure in the sole frame
    if extents is not None:
        x_min, x_max, y_min, y_max = extents
        px = x_min if px < x_min else x_max if px > x_max else px
        py = y_min if py < y_min else y_max if py > y_max else py
    px, py = share * px, share * py
    r = rotation
    dx = r[0] * px + r[1] * py  # s_i R_i c_i, base frame
    dy = r[3] * px + r[4] * py
    dz = r[6] * px + r[7] * py
    ux, uy, uz = relative_angular_velocity
    fx, fy, fz = (
        angular_velocity[0] + ux,
        angular_velocity[1] + uy,
        angular_velocity[2] + uz,
    )  # the foot's, in the world
    return (fz * dy - fy * dz, fx * dz - fz * dx, fy * dx - fx * dy)
