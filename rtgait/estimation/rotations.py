"""Rotations as Python floats for the estimator's tick: row-major 3x3 matrices as tuples of nine floats
(``R[r][c] = m[3 r + c]``), unit quaternions ``(w, x, y, z)``, and the yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

A tick needs a handful of 3x3 products; written out on floats they cost a fraction of numpy's per-call overhead.
"""

from __future__ import annotations

import math

__all__ = [
    "IDENTITY", "mat_mul", "mat_mul_t", "mat_t_vec", "mat_vec", "quat_matrix", "turned", "yaw_of", "yawed",
]  # fmt: skip

Matrix = tuple[float, float, float, float, float, float, float, float, float]
Vector = tuple[float, float, float]

IDENTITY: Matrix = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def quat_matrix(w: float, x: float, y: float, z: float) -> Matrix:
    """The rotation of a quaternion ``(w, x, y, z)``, normalised first (a filter's output may drift off unit norm).

    Raises:
        ValueError: a zero or non-finite quaternion.
    """
    n = w * w + x * x + y * y + z * z
    if not (n > 0.0 and math.isfinite(n)):
        raise ValueError(f"an orientation quaternion must be finite and non-zero, got {(w, x, y, z)}")
    s = 2.0 / n
    xx, yy, zz = s * x * x, s * y * y, s * z * z
    xy, xz, yz = s * x * y, s * x * z, s * y * z
    wx, wy, wz = s * w * x, s * w * y, s * w * z
    return (1.0 - yy - zz, xy - wz, xz + wy, xy + wz, 1.0 - xx - zz, yz - wx, xz - wy, yz + wx, 1.0 - xx - yy)


def mat_mul(a: tuple[float, ...], b: tuple[float, ...]) -> Matrix:
    """``A B``."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (
        a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
        a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
        a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8,
    )  # fmt: skip


def mat_mul_t(a: tuple[float, ...], b: tuple[float, ...]) -> Matrix:
    """``A B^T``."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (
        a0 * b0 + a1 * b1 + a2 * b2, a0 * b3 + a1 * b4 + a2 * b5, a0 * b6 + a1 * b7 + a2 * b8,
        a3 * b0 + a4 * b1 + a5 * b2, a3 * b3 + a4 * b4 + a5 * b5, a3 * b6 + a4 * b7 + a5 * b8,
        a6 * b0 + a7 * b1 + a8 * b2, a6 * b3 + a7 * b4 + a8 * b5, a6 * b6 + a7 * b7 + a8 * b8,
    )  # fmt: skip


def mat_vec(m: tuple[float, ...], v: tuple[float, ...]) -> Vector:
    """``R v``."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z, m[6] * x + m[7] * y + m[8] * z)


def mat_t_vec(m: tuple[float, ...], v: tuple[float, ...]) -> Vector:
    """``R^T v``."""
    x, y, z = v
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z, m[2] * x + m[5] * y + m[8] * z)


def yaw_of(m: tuple[float, ...]) -> float:
    """The yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)``: the heading of the frame's x axis on the ground (rad)."""
    return math.atan2(m[3], m[0])


def yawed(angle: float, m: tuple[float, ...]) -> Matrix:
    """``Rz(angle) R``: the same roll and pitch, the yaw turned by ``angle`` (rad)."""
    return turned(math.cos(angle), math.sin(angle), m)


def turned(c: float, s: float, m: tuple[float, ...]) -> Matrix:
    """``Rz R`` for ``Rz``'s cosine ``c`` and sine ``s``: :func:`yawed` with the angle's trigonometry done once."""
    m0, m1, m2, m3, m4, m5, m6, m7, m8 = m
    return (c * m0 - s * m3, c * m1 - s * m4, c * m2 - s * m5, s * m0 + c * m3, s * m1 + c * m4, s * m2 + c * m5,
            m6, m7, m8)  # fmt: skip
