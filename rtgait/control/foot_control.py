"""Foot force control for a position-controlled humanoid: the feet realise the commanded ZMP.

After Kajita et al., "Biped walking stabilization based on linear inverted pendulum tracking" (IROS 2010), as
hrpsys-base's Stabilizer (EEFM) and lipm_walking_controller implement it: a stiff position servo cannot command a
torque, but tilting a loaded sole moves its centre of pressure (CoP), and raising one foot against the other moves
load between them. Three parts, per control tick (world frame, SI units):

**1. Wrench distribution** (:func:`split_zmp`). In single support the stance foot takes the commanded ZMP ``p``
(clamped to its sole). In double support, with the sole points ``r_L, r_R`` and ``u = r_L - r_R``,

    a = clamp(((p - r_R) . u) / |u|^2, 0, 1),        f_L = a f,  f_R = (1 - a) f

and what the segment cannot reach, ``o = p - (r_R + a u)``, is produced by both CoPs alike: ``c_L = r_L + o``,
``c_R = r_R + o``, each clamped to its sole, so ``a c_L + (1 - a) c_R = p`` unless a clamp acted (``saturated``).
A projection in place of lipm_walking_controller's force distribution QP: no solver, exact whenever the ZMP is
feasible, the QP's force ratio.

**2. Ankle damping of each sole's CoP** (hrpsys ``calcDampingControl``, Kajita 2010 eqs. 14-17). With the measured
normal force ``f_z`` and the measured and desired CoPs in the sole frame, the moment error is
``dtau_x = f_z (c_y - c_y,d)``, ``dtau_y = -f_z (c_x - c_x,d)`` (N m), and the roll and pitch offsets obey

    theta' = K dtau - theta / T,        |theta'| <= theta'_max,  |theta| <= theta_max              (3)

This is hrpsys' ``theta' = K (tau_d - tau) - theta / T`` with ``tau`` the moment the foot applies to the ground (the
negative of the reaction measured here). Signs: a CoP in front of the desired one gives ``dtau_y < 0``, the toe rises
and the heel presses, the CoP moves back; a CoP left of the desired one gives a positive roll, which presses the
right edge. The leak ``T`` returns the ankle to the plan; a foot in the air leaks with ``swing_time_constant`` so
that it lands level.

**3. Foot force-difference control** (Kajita 2010 eq. 18). In double support, both feet loaded, the feet's heights
move apart by ``dz = h_R - h_L`` (m):

    dz' = K_f ((f_L - f_R)_d - (f_L - f_R)) - dz / T_f,        h_L = m - dz/2,  h_R = m + dz/2       (4)

with the desired difference ``(2 a - 1)`` times the measured total and the mean ``m`` leaking to zero. Outside double
support each height leaks (``T_f`` loaded, ``swing_time_constant`` in the air); each is clamped to ``max_height``.

Defaults (:class:`FootControlGains`) and sources: ``cop_admittance`` K = 0.01 rad/(N m s), lipm_walking_controller's
``admittance.cop`` for HRP-4 and HRP-2 (hrpsys' ``1 / eefm_rot_damping_gain``); ``cop_time_constant`` T = 1.5 s and
``max_tilt`` = 10 degrees, hrpsys ``eefm_rot_time_const`` and ``eefm_rot_compensation_limit``; ``max_tilt_rate`` =
0.2 rad/s, lipm_walking_controller ``MAX_FDC_RX_VEL``; ``force_difference_admittance`` K_f = 1e-4 m/(N s),
lipm_walking_controller ``admittance.dfz`` (HRP-4; its clamps, 0.1 and 5e-4, bound the accepted values);
``force_difference_time_constant`` T_f = 1.5 s, ``max_height`` = 0.025 m and ``swing_time_constant`` = 0.08 s, hrpsys
``eefm_pos_time_const_support``, ``eefm_pos_compensation_limit`` and ``eefm_pos_time_const_swing``. These are gains
of 40-60 kg robots with rubber bushes in their feet: tune ``K`` on the robot
(:data:`rtgait.control.settings.SIM_COP_ADMITTANCE`).

Output (:class:`~rtgait.interface.task_targets.FootOffsets`): roll and pitch per foot (rad) and height per foot (m).
The IK of :mod:`rtgait.robot.ik` keeps soles level, so the tilts go to the ankle joints after it
(:func:`rtgait.robot.ankles.find_ankle_joints`, :func:`rtgait.robot.ankles.add_ankle_offsets`); the heights go to
the feet targets' z.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, NamedTuple

from rtgait.core.geometry.footsteps import SoleRect
from rtgait.interface.task_targets import FootOffsets

if TYPE_CHECKING:
    from rtgait.estimation.state import FootState

__all__ = [
    "FootControlGains",
    "FootForceControl",
    "FootOffsets",
    "ZmpSplit",
    "split_zmp",
]

_new_tuple = tuple.__new__  # a NamedTuple from a tuple at once, without its generated __new__'s argument parsing

Pose = tuple[float, float, float]
"""A sole frame on the ground ``(x, y, yaw)`` (m, rad); a longer tuple (e.g. ``(x, y, z, yaw)``) is read as its
first two and last values."""


@dataclass(frozen=True)
class FootControlGains:
    """Gains and limits of the foot force control (SI units; defaults and sources in the module docstring).

    Attributes:
        cop_admittance: K of eq. (3), rad/(N m s), in [0, 0.1]; 0 turns ankle damping off.
        cop_time_constant: T of eq. (3), s.
        max_tilt: largest roll or pitch offset, rad.
        max_tilt_rate: largest rate of a roll or pitch offset, rad/s.
        force_difference_admittance: K_f of eq. (4), m/(N s), in [0, 5e-4]; 0 turns it off.
        force_difference_time_constant: T_f of eq. (4), s.
        max_height: largest height offset of a foot, m.
        swing_time_constant: leak of the offsets of a foot in the air, s.
    """

    cop_admittance: float = 0.01
    cop_time_constant: float = 1.5
    max_tilt: float = math.radians(10.0)
    max_tilt_rate: float = 0.2
    force_difference_admittance: float = 1e-4
    force_difference_time_constant: float = 1.5
    max_height: float = 0.025
    swing_time_constant: float = 0.08

    def __post_init__(self) -> None:
        ranges = {
            "cop_admittance": (0.0, 0.1),
            "cop_time_constant": (1e-3, 1e4),
            "max_tilt": (0.0, 0.5),
            "max_tilt_rate": (0.0, 10.0),
            "force_difference_admittance": (0.0, 5e-4),
            "force_difference_time_constant": (1e-3, 1e4),
            "max_height": (0.0, 0.1),
            "swing_time_constant": (1e-3, 1e4),
        }
        for field in fields(self):
            low, high = ranges[field.name]
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
            if not (number and low <= value <= high):
                raise ValueError(f"FootControlGains.{field.name} must be within [{low:g}, {high:g}], got {value!r}")


class ZmpSplit(NamedTuple):
    """The commanded ZMP shared between the feet (:func:`split_zmp`).

    Attributes:
        left_ratio: the left foot's share of the normal force, in [0, 1].
        left_cop, right_cop: desired CoP of each foot, world ``(x, y)`` (m); a foot with no share gets its sole
            point.
        saturated: a CoP was clamped to its sole: the feet cannot produce this ZMP.
    """

    left_ratio: float
    left_cop: tuple[float, float]
    right_cop: tuple[float, float]
    saturated: bool


def _clamp_to_sole(px: float, py: float, pose: Pose, sole: SoleRect, left: bool) -> tuple[float, float, bool]:
    """Nearest point of the sole rectangle of the foot at ``pose`` to ``(px, py)`` (m), and whether it moved."""
    x, y, yaw = pose[0], pose[1], pose[-1]
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = px - x, py - y
    lx, ly = c * dx + s * dy, -s * dx + c * dy
    # `inner` is toward the other foot: -y for the left foot, +y for the right one.
    y_low, y_high = (-sole.inner, sole.outer) if left else (-sole.outer, sole.inner)
    # min(max(v, low), high) as conditionals with the builtins' exact choices (cheaper than two calls each).
    # (max(a, b) is `b if b > a else a`, min(a, b) `b if b < a else a`: a NaN stays, a tie gives the first.)
    low, high = -sole.back, sole.front
    qx = low if low > lx else lx
    qx = high if high < qx else qx
    qy = y_low if y_low > ly else ly
    qy = y_high if y_high < qy else qy
    if qx == lx and qy == ly:
        return px, py, False
    return x + c * qx - s * qy, y + s * qx + c * qy, True


def split_zmp(zmp: tuple[float, float], left: Pose, right: Pose, sole: SoleRect, support: str) -> ZmpSplit:
    """Share the ZMP ``zmp`` (m) between the feet at ``left`` and ``right`` (module docstring, part 1).

    Args:
        zmp: the commanded ZMP, world ``(x, y)`` (m).
        left, right: the sole frames ``(x, y, yaw)`` (or ``(x, y, z, yaw)``) of the feet (m, rad).
        sole: the sole rectangle around the sole frame (m).
        support: ``"double"``, ``"left"`` or ``"right"``: the feet that may carry load.
    """
    px, py = zmp
    if support == "left":
        cx, cy, clamped = _clamp_to_sole(px, py, left, sole, True)
        return _new_tuple(ZmpSplit, (1.0, (cx, cy), (right[0], right[1]), clamped))
    if support == "right":
        cx, cy, clamped = _clamp_to_sole(px, py, right, sole, False)
        return _new_tuple(ZmpSplit, (0.0, (left[0], left[1]), (cx, cy), clamped))
    if support != "double":
        raise ValueError(f"support must be 'double', 'left' or 'right', got {support!r}")
    lx, ly, rx, ry = left[0], left[1], right[0], right[1]
    ux, uy = lx - rx, ly - ry
    length2 = ux * ux + uy * uy
    ratio = ((px - rx) * ux + (py - ry) * uy) / length2 if length2 > 0.0 else 0.5
    ratio = 0.0 if ratio < 0.0 else (1.0 if ratio > 1.0 else ratio)
    ox, oy = px - (rx + ratio * ux), py - (ry + ratio * uy)
    saturated = False
    if ratio > 0.0:
        lcx, lcy, clamped = _clamp_to_sole(lx + ox, ly + oy, left, sole, True)
        saturated = clamped
    else:
        lcx, lcy = lx, ly
    if ratio < 1.0:
        rcx, rcy, clamped = _clamp_to_sole(rx + ox, ry + oy, right, sole, False)
        saturated = saturated or clamped
    else:
        rcx, rcy = rx, ry
    return _new_tuple(ZmpSplit, (ratio, (lcx, lcy), (rcx, rcy), saturated))


class FootForceControl:
    """Ankle damping control of both soles and foot force-difference control (module docstring, parts 2-3).

    Args:
        gains: :class:`FootControlGains` (default: its defaults).
        dt: default control period (s) of :meth:`update`.

    The state is the six offsets; :meth:`reset` zeroes them.
    """

    def __init__(self, gains: FootControlGains | None = None, dt: float | None = None) -> None:
        if gains is not None and not isinstance(gains, FootControlGains):
            raise ValueError(f"gains must be a FootControlGains, got {type(gains).__name__}")
        self.gains = gains or FootControlGains()
        if dt is not None and not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        self.dt = dt
        self._tick_dt = math.nan
        self.reset()

    def reset(self) -> None:
        """Zero the offsets."""
        self._tilt = [0.0, 0.0, 0.0, 0.0]  # left roll, left pitch, right roll, right pitch (rad)
        self._height = [0.0, 0.0]  # left, right (m)

    @property
    def offsets(self) -> FootOffsets:
        """The offsets after the last :meth:`update`."""
        lr, lp, rr, rp = self._tilt
        return _new_tuple(FootOffsets, (lr, lp, self._height[0], rr, rp, self._height[1]))

    def _set_dt(self, dt: float) -> None:
        """Exact discretisation of ``y' = u - y / T`` with ``u`` held over the tick: ``y+ = a y + T (1 - a) u``."""
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a period > 0 s, got {dt}")
        g = self.gains
        self._cop_leak = math.exp(-dt / g.cop_time_constant)
        self._cop_input = -g.cop_time_constant * math.expm1(-dt / g.cop_time_constant) * g.cop_admittance
        self._force_leak = math.exp(-dt / g.force_difference_time_constant)
        self._force_input = (
            -g.force_difference_time_constant * math.expm1(-dt / g.force_difference_time_constant)
        ) * g.force_difference_admittance
        self._swing_leak = math.exp(-dt / g.swing_time_constant)
        self._max_step = g.max_tilt_rate * dt
        self._tick_dt = dt

    def update(
        self,
        split: ZmpSplit,
        left: FootState,
        right: FootState,
        support: str,
        dt: float | None = None,
    ) -> FootOffsets:
        """One tick: the offsets for the desired split and the measured feet.

        Args:
            split: the desired distribution (:func:`split_zmp`).
            left, right: the measured feet (:class:`~rtgait.estimation.state.FootState`: ``normal_force``,
                ``cop_local``, ``pose``, ``loaded``).
            support: the feet meant to carry load now, ``"double"``, ``"left"`` or ``"right"``: ankle damping acts
                on those that are also measured loaded, force-difference control only in ``"double"`` with both
                loaded.
            dt: the tick's period (s); default the constructor's.
        """
        if dt is None:
            if self.dt is None:
                raise ValueError("dt must be given to update() or to the constructor (s)")
            dt = self.dt
        if dt != self._tick_dt:
            self._set_dt(dt)
        # A foot is under damping control when it is loaded and meant to carry load; otherwise it is in the air, or
        # on the ground when the plan has it swinging, and returns to the plan.
        double_support = support == "double"
        left_active = left.loaded and support != "right"
        right_active = right.loaded and support != "left"
        ratio = split.left_ratio
        self._ankle(0, left, split.left_cop, left_active)
        self._ankle(2, right, split.right_cop, right_active)

        h = self._height
        max_h = self.gains.max_height
        if double_support and left.loaded and right.loaded:
            total = left.normal_force + right.normal_force
            error = (2.0 * ratio - 1.0) * total - (left.normal_force - right.normal_force)
            dz = h[1] - h[0]
            mean = 0.5 * (h[0] + h[1])
            dz = self._force_leak * dz + self._force_input * error
            mean *= self._force_leak
            h[0], h[1] = mean - 0.5 * dz, mean + 0.5 * dz
        else:
            h[0] *= self._force_leak if left.loaded else self._swing_leak
            h[1] *= self._force_leak if right.loaded else self._swing_leak
        h[0] = -max_h if h[0] < -max_h else (max_h if h[0] > max_h else h[0])
        h[1] = -max_h if h[1] < -max_h else (max_h if h[1] > max_h else h[1])
        return self.offsets

    def _ankle(self, index: int, foot: FootState, desired: tuple[float, float], active: bool) -> None:
        """Eq. (3) for one foot's roll and pitch (``index`` 0 left, 2 right)."""
        tilt = self._tilt
        roll, pitch = tilt[index], tilt[index + 1]
        cx, cy = foot.cop_local
        if active and cx == cx and cy == cy:  # NaN-safe: no CoP, no torque input
            # The desired CoP in the measured sole frame (the sole's own tilt is a few mrad: its yaw suffices).
            x, y, yaw = foot.pose[0], foot.pose[1], foot.pose[-1]
            c, s = math.cos(yaw), math.sin(yaw)
            dx, dy = desired[0] - x, desired[1] - y
            fz = foot.normal_force
            torque_x = fz * (cy - (-s * dx + c * dy))
            torque_y = -fz * (cx - (c * dx + s * dy))
            new_roll = self._cop_leak * roll + self._cop_input * torque_x
            new_pitch = self._cop_leak * pitch + self._cop_input * torque_y
        else:
            new_roll = self._swing_leak * roll
            new_pitch = self._swing_leak * pitch
        step = self._max_step
        limit = self.gains.max_tilt
        # max(low, min(high, v)) as conditionals with the builtins' exact choices (a NaN gives `high`, a tie the
        # first argument): two builtin calls per clamp cost more than the rest of the line.
        d = new_roll - roll
        d = d if d < step else step
        new_roll = roll + (d if d > -step else -step)
        d = new_pitch - pitch
        d = d if d < step else step
        new_pitch = pitch + (d if d > -step else -step)
        new_roll = new_roll if new_roll < limit else limit
        tilt[index] = new_roll if new_roll > -limit else -limit
        new_pitch = new_pitch if new_pitch < limit else limit
        tilt[index + 1] = new_pitch if new_pitch > -limit else -limit
