"""Each foot's wrench, centre of pressure, pose and load, and the ZMP of both feet, from the contact force and moment
summed over the foot and its sole frame's pose.

With ``F`` the force on a foot and ``M`` its moment about the world origin (N, N m), ``o`` the sole frame's origin
and ``R`` its rotation (x forward, y left, z out of the sole), the moment about the sole origin is
``tau_o = M - o x F``. In the sole frame, with ``f = R^T F`` and ``t = R^T tau_o``, the centre of pressure (the point
of the sole plane about which the moment has no tangential part) is

    cop_local = (-t_y / f_z, t_x / f_z),        cop = o + R (cop_local, 0)               (m)

NaN when the foot carries less than ``min_force``. The ZMP of both feet is the point of the plane ``z = h`` about
which the net moment of all foot forces is vertical: with ``tau_O = sum_feet (o - O) x F + tau_o`` about
``O = (0, 0, h)``,

    zmp = (-tau_O,y / F_z, tau_O,x / F_z)                                                 (m)

which for feet flat on the ground is the force-weighted mean of their CoPs; NaN when no foot carries ``min_force``.
The plane is the soles' by default, ``h = sum_i max(f_z,i, 0) o_z,i / sum_i max(f_z,i, 0)``: the stance sole's in
single support, where the planner puts its ZMP (the support height of ``docs/method.md``). On a plane ``d`` below
it the ZMP moves by ``d F_xy / F_z``, about ``d (c - p) / z_c``: on top of a 0.9 m staircase the ZMP on the floor's
plane is twice as far from the COM as the pendulum's.
A foot's wrench may also be given in its sole frame (``f``, ``t`` about the sole origin, as a force sensor's turned
there): then ``F = R f``, ``tau_o = R t``.
The sole's orientation is read as ``R = Rz(yaw) Ry(pitch) Rx(roll)``; its tilt is the angle between the sole normal
and the vertical. All on Python floats: a tick's few numbers cost less so than as numpy arrays.
"""

from __future__ import annotations

import math

from rtgait.core.geometry.footsteps import Side
from rtgait.estimation.load import LoadHysteresis
from rtgait.estimation.state import FootState, Landing

__all__ = ["FeetFromWrenches", "soles_plane"]

_NAN2 = (math.nan, math.nan)
_new_tuple = tuple.__new__  # a NamedTuple made from a tuple at once, without its generated __new__'s argument parsing


def soles_plane(left_force: float, left_height: float, right_force: float, right_height: float) -> float:
    """The height (m) of the ZMP's plane for the soles' vertical forces (N) and heights (m): the heights weighted
    by the loads (a pull counts as none); 0 without load."""
    lf = left_force if left_force > 0.0 else 0.0
    rf = right_force if right_force > 0.0 else 0.0
    total = lf + rf
    return (lf * left_height + rf * right_height) / total if total > 0.0 else 0.0


class FeetFromWrenches:
    """The feet's states and the ZMP (module docstring), with the feet's load states kept by ``load``.

    Args:
        load: the feet's load and landing detection.
        min_force: least load (N) for which a CoP or a ZMP is given.
        ground_height: height of the ZMP's plane (m); ``None``: the soles' (module docstring).
    """

    def __init__(self, load: LoadHysteresis, min_force: float, ground_height: float | None = None) -> None:
        self.load = load
        self.min_force = float(min_force)
        self.ground_height = None if ground_height is None else float(ground_height)

    def foot(
        self, index: int, t: float, fx: float, fy: float, fz: float, mx: float, my: float, mz: float, count: int,
        position: list[float], m: list[float],
    ) -> tuple[FootState, Landing | None]:  # fmt: skip
        """One foot's state from its summed force ``(fx, fy, fz)`` (N) and moment about the world origin (N m), and
        its sole frame's position and row-major rotation; and its landing at this tick, if it landed."""
        ox, oy, oz = position
        # Moment about the sole origin: tau_o = M - o x F.
        tx = mx - (oy * fz - oz * fy)
        ty = my - (oz * fx - ox * fz)
        tz = mz - (ox * fy - oy * fx)
        # The sole frame's components: R^T v, R row-major (m[3 r + c] = R[r][c]).
        m0, m1, m2, m3, m4, m5, m6, m7, m8 = m
        lfz = m2 * fx + m5 * fy + m8 * fz
        ltx = m0 * tx + m3 * ty + m6 * tz
        lty = m1 * tx + m4 * ty + m7 * tz
        return self._state(index, t, fx, fy, fz, tx, ty, tz, lfz, ltx, lty, count, position, m)

    def sole_foot(
        self, index: int, t: float, wrench: tuple[float, float, float, float, float, float], count: int,
        position: tuple[float, float, float], m: tuple[float, ...], load_force: float | None = None,
        near_ground: bool = True,
    ) -> tuple[FootState, Landing | None]:  # fmt: skip
        """One foot's state from the ground's wrench on it in its sole frame, ``(fx, fy, fz, tx, ty, tz)`` (N, N m,
        about the sole origin), and its sole frame's world position and row-major rotation (as :meth:`foot`);
        ``load_force``: the vertical force (N) the load detection reads, default the wrench's; ``near_ground``: whether
        the foot, if unloaded, may become loaded (:meth:`~rtgait.estimation.load.LoadHysteresis.update`)."""
        lfx, lfy, lfz, ltx, lty, ltz = wrench
        m0, m1, m2, m3, m4, m5, m6, m7, m8 = m
        # The world components: R v.
        return self._state(
            index, t, m0 * lfx + m1 * lfy + m2 * lfz, m3 * lfx + m4 * lfy + m5 * lfz, m6 * lfx + m7 * lfy + m8 * lfz,
            m0 * ltx + m1 * lty + m2 * ltz, m3 * ltx + m4 * lty + m5 * ltz, m6 * ltx + m7 * lty + m8 * ltz,
            lfz, ltx, lty, count, position, m, load_force, near_ground,
        )  # fmt: skip

    def _state(
        self, index: int, t: float, fx: float, fy: float, fz: float, tx: float, ty: float, tz: float, lfz: float,
        ltx: float, lty: float, count: int, position: list[float] | tuple[float, float, float], m: list[float] |
        tuple[float, ...], load_force: float | None = None, near_ground: bool = True,
    ) -> tuple[FootState, Landing | None]:  # fmt: skip
        """The foot's state from its force and moment about the sole origin in the world (N, N m), their sole-frame
        normal force and tangential moment, and its sole frame's pose; the load detection reads ``load_force`` (N),
        default ``fz``, and lets the foot become loaded only if ``near_ground``."""
        ox, oy, oz = position
        m0, m1, _, m3, m4, _, m6, m7, m8 = m
        if lfz > self.min_force:
            cx, cy = -lty / lfz, ltx / lfz
            cop_local = (cx, cy)
            cop = (ox + m0 * cx + m1 * cy, oy + m3 * cx + m4 * cy)
        else:
            cop_local = cop = _NAN2
        # R = Rz(yaw) Ry(pitch) Rx(roll); the tilt is the angle between the sole normal and the vertical.
        yaw = math.atan2(m3, m0)
        # max(-1, min(1, v)) written as the builtins decide it (`b if b < a else a` for min(a, b), `b if b > a
        # else a` for max: the same result, NaN included), a call each costing more than the trigonometry.
        sine = -m6 if -m6 < 1.0 else 1.0
        pitch = math.asin(sine if sine > -1.0 else -1.0)
        roll = math.atan2(m7, m8)
        cosine = m8 if m8 < 1.0 else 1.0
        tilt = math.acos(cosine if cosine > -1.0 else -1.0)
        loaded = self.load.update(index, fz if load_force is None else load_force, t, near_ground)
        landing = None
        if loaded is None:
            loaded = True
            side: Side = "left" if index == 0 else "right"
            landing = _new_tuple(Landing, (t, side, ox, oy, oz, yaw, roll, pitch, fz))
        foot = _new_tuple(
            FootState,
            ((fx, fy, fz), (tx, ty, tz), fz, cop, cop_local, (ox, oy, oz, yaw), roll, pitch, tilt, loaded, count),
        )
        return foot, landing

    def zmp(self, left: FootState, right: FootState) -> tuple[tuple[float, float], float]:
        """The ZMP of both feet on its plane (m; NaN below ``min_force``) and their total vertical force (N)."""
        h = self.ground_height
        if h is None:
            h = soles_plane(left.force[2], left.pose[2], right.force[2], right.pose[2])
        # ZMP moments about (0, 0, h): (o - O) x F + tau_o per foot, in the order the feet are summed.
        zmp_mx = zmp_my = total = 0.0
        for foot in (left, right):
            ox, oy, oz, _ = foot.pose
            fx, fy, fz = foot.force
            tx, ty, _ = foot.torque
            zmp_mx += (oy * fz - (oz - h) * fy) + tx
            zmp_my += ((oz - h) * fx - ox * fz) + ty
            total += fz
        zmp = (-zmp_my / total, zmp_mx / total) if total > self.min_force else _NAN2
        return zmp, total
