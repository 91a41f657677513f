"""The rotation errors of the whole-body IK's orientation tasks (:mod:`rtgait.robot.ik`), in scalar arithmetic.

Each is the world-frame rotation vector ``log(R_target R^T)`` (rad) from a frame's rotation ``R`` (the first three
rows and columns of its homogeneous matrix ``h``) to its target: level with heading ``yaw``, ``Rz(yaw)``; leaned,
``Exp(lean) Rz(yaw)``; or a sole tilted by pitch and roll, ``Rz(yaw) Ry(pitch) Rx(roll)``. Written out on Python
numbers: on 3x3 matrices numpy's calls cost more than the arithmetic, and the IK computes four of them a tick.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

__all__: list[str] = []  # the IK's own helpers


def _floats(values: np.ndarray | Sequence[float]) -> Sequence[float]:
    """A short vector as Python numbers: scalar arithmetic on numpy scalars is several times slower."""
    return values.tolist() if isinstance(values, np.ndarray) else values


def _leaned_yaw_error(
    h: list[list[float]], c: float, s: float, lean: Sequence[float] | None
) -> tuple[float, float, float]:
    """World-frame rotation vector from rotation ``h`` to ``Exp(lean) Rz(yaw)`` (rad), ``c, s = cos(yaw), sin(yaw)``:
    :func:`_yaw_error` when upright. With ``L = Exp(lean)``, ``L Rz R^T`` is ``Rz (L^T R)^T`` conjugated by ``L``, so
    its log is ``L`` times the yaw error of ``L^T R``."""
    if lean is None:
        return _yaw_error(h, c, s)
    lx, ly, lz = _floats(lean)
    angle = math.sqrt(lx * lx + ly * ly + lz * lz)
    if angle < 1e-12:
        return _yaw_error(h, c, s)
    L = _rotation(lx / angle, ly / angle, lz / angle, angle)
    rows = [row[:3] for row in h[:3]]
    # L^T R: entry (i, j) = sum_k L[k][i] R[k][j].
    tilted = [[L[0][i] * rows[0][j] + L[1][i] * rows[1][j] + L[2][i] * rows[2][j] for j in range(3)] for i in range(3)]
    ex, ey, ez = _yaw_error(tilted, c, s)
    return (L[0][0] * ex + L[0][1] * ey + L[0][2] * ez, L[1][0] * ex + L[1][1] * ey + L[1][2] * ez,
            L[2][0] * ex + L[2][1] * ey + L[2][2] * ez)  # fmt: skip


def _foot_error(h: list[list[float]], foot: Sequence[float], yaw: float) -> tuple[float, float, float]:
    """World-frame rotation vector from the sole rotation ``h`` to the target of ``foot``: ``Rz(yaw)`` (level), or
    ``Rz(yaw) Ry(pitch) Rx(roll)`` when ``foot`` has a pitch and roll (its 5th and 6th values, rad). That target is
    ``Exp(w) Rz(yaw)`` with ``w = Rz(yaw) log(Ry(pitch) Rx(roll))``, the lean form of :func:`_leaned_yaw_error`."""
    c, s = math.cos(yaw), math.sin(yaw)
    if len(foot) < 6 or not (foot[4] or foot[5]):
        return _yaw_error(h, c, s)
    cp, sp, cr, sr = math.cos(foot[4]), math.sin(foot[4]), math.cos(foot[5]), math.sin(foot[5])
    # Ry(p) Rx(r) = [[cp, sp sr, sp cr], [0, cr, -sr], [-sp, cp sr, cp cr]]; its log from the skew part and trace.
    cos_angle = 0.5 * (cp + cr + cp * cr - 1.0)
    ax, ay, az = 0.5 * (cp * sr + sr), 0.5 * (sp * cr + sp), 0.5 * (-sp * sr)
    sin_angle = math.sqrt(ax * ax + ay * ay + az * az)
    scale = math.atan2(sin_angle, cos_angle) / sin_angle
    wx, wy, wz = scale * ax, scale * ay, scale * az
    return _leaned_yaw_error(h, c, s, (c * wx - s * wy, s * wx + c * wy, wz))


def _rotation(ux: float, uy: float, uz: float, angle: float) -> list[list[float]]:
    """Rotation matrix of ``angle`` (rad) about the unit axis ``u`` (Rodrigues' formula)."""
    c, s = math.cos(angle), math.sin(angle)
    k = 1.0 - c
    return [[c + k * ux * ux, k * ux * uy - s * uz, k * ux * uz + s * uy],
            [k * uy * ux + s * uz, c + k * uy * uy, k * uy * uz - s * ux],
            [k * uz * ux - s * uy, k * uz * uy + s * ux, c + k * uz * uz]]  # fmt: skip


def _yaw_error(h: list[list[float]], c: float, s: float) -> tuple[float, float, float]:
    """World-frame rotation vector from rotation ``h[:3][:3]`` to the level rotation of heading ``yaw`` (rad), given
    as ``c, s = cos(yaw), sin(yaw)``.

    That is log(Rz(yaw) R^T), from the skew part and the trace of ``E = Rz(yaw) R^T`` written out in scalars.
    """
    h0, h1, h2 = h[0], h[1], h[2]
    r00, r01, r02 = h0[0], h0[1], h0[2]
    r10, r11, r12 = h1[0], h1[1], h1[2]
    r20, r21, r22 = h2[0], h2[1], h2[2]
    vx = 0.5 * (r12 - (s * r20 + c * r21))
    vy = 0.5 * ((c * r20 - s * r21) - r02)
    vz = 0.5 * ((s * r00 + c * r01) - (c * r10 - s * r11))
    cos_angle = 0.5 * ((c * r00 - s * r01) + (s * r10 + c * r11) + r22 - 1.0)
    sin_angle = math.sqrt(vx * vx + vy * vy + vz * vz)
    if cos_angle < -0.9:
        # Near a half turn the skew part vanishes and loses the axis; Pinocchio's log recovers it.
        rz = np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))
        rotation = np.array([row[:3] for row in h[:3]])
        wx, wy, wz = pin.log3(rz @ rotation.T).tolist()
        return wx, wy, wz
    if sin_angle < 1e-12:
        return vx, vy, vz
    scale = math.atan2(sin_angle, cos_angle) / sin_angle
    return scale * vx, scale * vy, scale * vz
