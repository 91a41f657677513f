"""DCM feedback: the commanded ZMP that steers the measured divergent component of motion back onto its reference.

A robot-agnostic stabiliser for any control loop, in the style of Englsberger's capture-point control and of the
LIPM stabiliser of lipm_walking_controller / mc_rtc: reference in, measurement in, commanded ZMP and COM correction
out. Pure float arithmetic per tick (no numpy on the hot path), so it costs a few microseconds in CPython.

Model, per horizontal axis (x and y are independent). The linear inverted pendulum at constant height ``z_c``
with ``w = sqrt(g / z_c)`` (1/s), COM ``c`` (m) and ZMP ``p`` (m): ``p = c - c'' / w^2``. Its divergent component of
motion (DCM, instantaneous capture point) ``xi = c + c' / w`` (m) obeys

    xi' = w (xi - p)                                                          (1)

and so does the reference the planner gives, ``xi_ref' = w (xi_ref - p_ref)``.

Law. With the DCM error ``e = xi - xi_ref`` (m) and its leaky integral ``I`` (m s), ``I' = e - I / T_i``,

    p_cmd = p_ref + (1 + k_p / w) e + (k_i / w) I                             (2)

Substituting (2) into (1) (the robot realising ``p = p_cmd``) gives the error dynamics

    e' = -k_p e - k_i I,        I' = e - I / T_i                              (3)

Stability condition. The characteristic polynomial of (3) is ``s^2 + (k_p + 1/T_i) s + (k_i + k_p / T_i)``, which
is Hurwitz (both roots in the open left half-plane) for every ``k_p > 0, k_i >= 0, T_i > 0``. Without the leak
(``T_i = None``, i.e. ``1/T_i = 0``) it is ``s^2 + k_p s + k_i``: asymptotically stable iff ``k_p > 0`` and
``k_i > 0``; with ``k_i = 0`` the error still decays as ``e^{-k_p t}`` (the integrator's pole at 0 is not fed
back). ``k_p = 0`` is accepted but *not* stable: ``p_cmd = p_ref + e`` merely holds the error (``e' = 0``), and
``p_cmd = p_ref`` (no feedback at all) lets it grow as ``e^{w t}``. Sampled at period ``dt`` with the command held
over the tick, the proportional loop multiplies the error by ``1 - (k_p / w)(e^{w dt} - 1)`` per tick, which needs
``k_p < 2 w / (e^{w dt} - 1)`` (about ``2 / dt``, hundreds of 1/s at 1-5 ms: never the binding limit).

Saturation and capturability. The feet can only produce a ZMP inside the support polygon, so ``p_cmd`` is
projected onto it (the nearest point) and the stability of (3) holds only while the command is unsaturated.
Whether a saturated command still recovers is a question of capturability: while the DCM is inside the polygon,
a ZMP exists that stops or reverses it (the ankle strategy suffices); once it is outside, every admissible ZMP
pushes it farther out (by (1), ``xi - p`` has a positive component along the separating direction for every
``p`` in the polygon) and only a step can recover it. Anti-windup: the integrator is frozen (it only leaks) on any
tick where the command is limited, so a long saturation cannot charge it.

COM correction for a position-controlled robot (ZMP compliance control, as mc_rtc's ``comAdmittance`` / ZMPCC,
after Kajita et al. 2010 and the COM-ZMP regulator of Choi et al. 2006). A position-controlled robot cannot command
a ZMP; it can only move its COM reference. By ``p = c - c''/w^2`` the ZMP answers a COM acceleration with the
opposite sign: to raise the ZMP, lower ``c''``, i.e. step the COM velocity back. The COM reference is therefore
shifted by an offset ``d`` (m) whose rate opposes the ZMP error ``z = p_cmd - p_meas``:

    d' = -A z - d / T_c,        |d_x|, |d_y| <= d_max                         (4)

with ``A`` = ``com_admittance`` (1/s) and ``T_c`` = ``com_offset_time_constant`` (s), a slow leak that returns the
offset to zero when the error vanishes so it cannot drift. When no measured ZMP is given, the robot is taken to
realise its planned ZMP (it tracks the planned COM, whose pendulum ZMP is ``p_ref``), so ``z = p_cmd - p_ref``: the
correction is then derived from the DCM law alone. Add ``d`` and ``d'`` to the planned COM position and velocity.
How well (4) works, and with which ``A``, depends on how the robot turns COM motion into ZMP (its servos and its
compliance), which this module cannot know: the stability condition above is the DCM law's alone, and the
admittance is off by default.

State. The only state is explicit and reset by :meth:`DcmFeedback.reset`: the integral ``I``, the COM offset
``d`` and, only when ``max_zmp_speed`` is set, the previous commanded ZMP offset ``p_cmd - p_ref``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

from rtgait.core.geometry.polygon import ConvexPolygon

MIN_DT = 1e-6
"""Shortest control period accepted (s)."""
MAX_DT = 1.0
"""Longest control period accepted (s): beyond it (1) is no model of a balancing robot's tick."""
MAX_OMEGA = 1000.0
"""Largest pendulum frequency accepted (1/s); a COM 1 cm high on Earth gives 31 1/s."""


def _check_real(name: str, value: object, low: float, high: float, unit: str, optional: bool = False) -> float | None:
    """``value`` as a float if a finite real within ``[low, high]`` (or ``None`` when ``optional``), else a
    ValueError naming ``name`` and the range."""
    if value is None and optional:
        return None
    allowed = f"[{low:g}, {high:g}] {unit}" + (" or None" if optional else "")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a real number in {allowed}, got {value!r}")
    number = float(value)
    if not (math.isfinite(number) and low <= number <= high):
        raise ValueError(f"{name} must be finite and within {allowed}, got {value!r}")
    return number


@dataclass(frozen=True)
class DcmFeedbackGains:
    """Gains and limits of the DCM feedback law (SI units); see the module docstring for the equations.

    The defaults are stable (``k_p > 0, k_i >= 0``; error poles -1.81 and -0.26 1/s) and sensible for a
    humanoid with ``w`` about 3-4 1/s: ``k_p`` = 2 1/s sits inside mc_rtc's usual ``dcmPropGain`` 1-5 (same
    meaning: mc_rtc's desired COM acceleration ``c''_ref + w (k_p (xi_ref - xi) + c'_ref - c')`` also makes
    ``e' = -k_p e``) and is BaselineWalkingController's ``dcmGainP``. mc_rtc's integral term is ``dcmIntegralGain``
    times an exponential moving average of the error over ``T_i``, which is ``I / T_i`` here: ``k_i`` is that gain
    over ``T_i``, and its defaults (5, over 15 s) give the ``k_i`` below. The COM admittance is off by default, as
    in mc_rtc's ZMPCC (it depends on the robot's servos and must be tuned on it); its leak and clamp are ZMPCC's
    defaults (``integratorLeakRate`` 0.1 1/s, ``maxCoMOffset`` 0.05 m).

    Attributes:
        k_p: proportional gain, the decay rate of the DCM error (1/s), in [0, 20]; stability needs ``k_p > 0``.
        k_i: integral gain (1/s^2), in [0, 100].
        integrator_time_constant: leak ``T_i`` of the integral (s), in [0.01, 1e4]; ``None``: a pure integral.
        com_admittance: ``A`` of eq. (4), COM offset velocity per metre of ZMP error (1/s), in [0, 20]; 0 = off.
        com_offset_time_constant: leak ``T_c`` of the COM offset back to zero (s), in [0.01, 1e4].
        max_com_offset: largest COM offset on each axis (m), in [0, 1].
        max_zmp_speed: largest speed of the commanded ZMP offset ``p_cmd - p_ref`` (m/s), in [1e-6, 100];
            ``None`` (default): unlimited. It softens the ZMP jumps that a DCM measurement step would cause.
    """

    k_p: float = 2.0
    k_i: float = 1.0 / 3.0
    integrator_time_constant: float | None = 15.0
    com_admittance: float = 0.0
    com_offset_time_constant: float = 10.0
    max_com_offset: float = 0.05
    max_zmp_speed: float | None = None

    def __post_init__(self) -> None:
        ranges = {
            "k_p": (0.0, 20.0, "1/s", False),
            "k_i": (0.0, 100.0, "1/s^2", False),
            "integrator_time_constant": (0.01, 1e4, "s", True),
            "com_admittance": (0.0, 20.0, "1/s", False),
            "com_offset_time_constant": (0.01, 1e4, "s", False),
            "max_com_offset": (0.0, 1.0, "m", False),
            "max_zmp_speed": (1e-6, 100.0, "m/s", True),
        }
        for field in fields(self):
            low, high, unit, optional = ranges[field.name]
            value = _check_real(f"DcmFeedbackGains.{field.name}", getattr(self, field.name), low, high, unit, optional)
            object.__setattr__(self, field.name, value)  # normalise ints to floats in the frozen instance

    def error_poles(self) -> tuple[complex, complex]:
        """Roots (1/s) of ``s^2 + (k_p + 1/T_i) s + (k_i + k_p/T_i)``, the continuous-time poles of the DCM error
        and its integral under ideal ZMP tracking, eq. (3) (``1/T_i = 0`` without a leak). Both have negative real
        parts for ``k_p > 0`` unless ``k_i = 0`` without a leak: that pole at 0 is the integral's, which is then not
        fed back to the error (see :attr:`is_stable`)."""
        leak = 0.0 if self.integrator_time_constant is None else 1.0 / self.integrator_time_constant
        b = self.k_p + leak
        c = self.k_i + self.k_p * leak
        root = complex(b * b - 4.0 * c) ** 0.5
        return (-b + root) / 2.0, (-b - root) / 2.0

    @property
    def is_stable(self) -> bool:
        """Whether the DCM error of eq. (3) decays to zero under ideal ZMP tracking.

        ``k_p > 0`` suffices for any accepted ``k_i >= 0`` and leak (with ``k_i = 0`` and no leak, the integrator's
        pole at 0 is not fed back to the error). With ``k_p = 0`` only a leaky integral with ``k_i > 0`` is stable,
        barely: ``s^2 + s / T_i + k_i`` has damping ``1 / (2 T_i)`` 1/s.
        """
        return self.k_p > 0.0 or (self.k_i > 0.0 and self.integrator_time_constant is not None)


class DcmFeedbackOutput(NamedTuple):
    """One tick of :class:`DcmFeedback`: plain ``(x, y)`` float pairs (m, m/s), ``np.asarray`` makes them ``(2,)``.

    Attributes:
        zmp: commanded ZMP (m), rate-limited and inside or on the support polygon: send this to the robot.
        zmp_unsaturated: the law's ZMP, eq. (2), before any limit (m).
        saturated: whether ``zmp`` differs from ``zmp_unsaturated`` (projected onto the polygon or rate-limited);
            the integrator did not integrate on this tick.
        com_offset: COM correction ``d`` of eq. (4) (m), to add to the planned COM position.
        com_offset_vel: its rate over this tick (m/s), to add to the planned COM velocity.
    """

    zmp: tuple[float, float]
    zmp_unsaturated: tuple[float, float]
    saturated: bool
    com_offset: tuple[float, float]
    com_offset_vel: tuple[float, float]


def _pair(name: str, value: object) -> tuple[float, float]:
    """``value`` (an array ``(2,)`` or a pair) as two floats, else a ValueError naming ``name``."""
    try:
        if type(value) is np.ndarray:
            value = value.tolist()  # Python floats at once: unpacking an array makes slow numpy scalars
        x, y = value  # type: ignore[misc]
        return float(x), float(y)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (x, y) of numbers in m, got {value!r}") from None


class DcmFeedback:
    """The DCM feedback law of eq. (2) with saturation, anti-windup and the COM correction of eq. (4).

    Call :meth:`update` once per control tick with the reference and the measurement; the values in and out are all
    in the world frame (m, s). The law is per axis and never couples x and y, except through the polygon projection
    and the ZMP speed limit (a norm, so a limited command keeps its direction).

    Args:
        w: pendulum frequency ``sqrt(g / z_c)`` (1/s), e.g. :func:`rtgait.core.lipm.closed_form.omega`, in (0, 1000].
        gains: :class:`DcmFeedbackGains` (default: its defaults).
        dt: default control period (s) for :meth:`update`, in [1e-6, 1]; ``None``: pass ``dt`` on every tick.
    """

    def __init__(self, w: float, gains: DcmFeedbackGains | None = None, dt: float | None = None) -> None:
        checked_w = _check_real("w", w, 0.0, MAX_OMEGA, "1/s")
        if not checked_w:
            raise ValueError(f"w must be > 0 (1/s), got {w!r}")
        if gains is not None and not isinstance(gains, DcmFeedbackGains):
            raise ValueError(f"gains must be a DcmFeedbackGains, got {type(gains).__name__}")
        # Read-only after construction (properties below): the per-tick constants are derived from them here.
        self._w = checked_w
        self._gains = g = gains if gains is not None else DcmFeedbackGains()
        self._dt = _check_real("dt", dt, MIN_DT, MAX_DT, "s", optional=True)
        self._gain_e = 1.0 + g.k_p / checked_w
        self._gain_i = g.k_i / checked_w
        self._admittance = g.com_admittance
        self._max_offset = g.max_com_offset
        self._max_speed = g.max_zmp_speed
        # Per-dt discretisation, cached: every tick of a fixed-rate loop reuses it.
        self._tick_dt = math.nan
        self._leak_i = self._input_i = self._leak_c = self._input_c = 0.0
        # Last polygon seen, its bytes as the cache key, and its edges as floats.
        self._polygon_key: tuple[object, ...] | None = None
        self._polygon: ConvexPolygon | None = None
        self.reset()

    def reset(self) -> None:
        """Zero the state: the integral, the COM offset and the memory of the ZMP speed limit."""
        self._ix = self._iy = 0.0
        self._dx = self._dy = 0.0
        self._ox = self._oy = 0.0

    @property
    def w(self) -> float:
        """Pendulum frequency ``sqrt(g / z_c)`` (1/s)."""
        return self._w

    @property
    def gains(self) -> DcmFeedbackGains:
        """The gains and limits in use."""
        return self._gains

    @property
    def dt(self) -> float | None:
        """Default control period of :meth:`update` (s), or ``None``."""
        return self._dt

    @property
    def integral(self) -> tuple[float, float]:
        """The leaky integral ``I`` of the DCM error (m s), as it enters the next tick."""
        return self._ix, self._iy

    @property
    def com_offset(self) -> tuple[float, float]:
        """The COM offset ``d`` of eq. (4) (m) after the last tick."""
        return self._dx, self._dy

    def _set_dt(self, dt: float) -> None:
        """Validate a new control period and discretise the two leaky integrators exactly for it.

        With the input held over the tick, ``y' = u - y / T`` gives ``y+ = a y + T (1 - a) u`` with
        ``a = exp(-dt / T)``; without a leak, ``y+ = y + dt u``.
        """
        checked = _check_real("dt", dt, MIN_DT, MAX_DT, "s")
        assert checked is not None
        T_i = self._gains.integrator_time_constant
        if T_i is None:
            self._leak_i, self._input_i = 1.0, checked
        else:
            self._leak_i = math.exp(-checked / T_i)
            self._input_i = -T_i * math.expm1(-checked / T_i)
        T_c = self._gains.com_offset_time_constant
        self._leak_c = math.exp(-checked / T_c)
        self._input_c = -T_c * math.expm1(-checked / T_c)
        self._tick_dt = checked

    def _set_polygon(self, polygon: object, key: tuple[object, ...] | None) -> None:
        self._polygon = ConvexPolygon(polygon)
        self._polygon_key = key

    def update(
        self,
        zmp_ref: np.ndarray,
        dcm_ref: np.ndarray,
        dcm: np.ndarray,
        polygon: np.ndarray,
        dt: float | None = None,
        zmp_measured: np.ndarray | None = None,
    ) -> DcmFeedbackOutput:
        """One control tick: the commanded ZMP for the measured DCM, and the COM correction.

        Args:
            zmp_ref: planned ZMP ``p_ref`` (m), ``(2,)``.
            dcm_ref: planned DCM ``xi_ref = c_ref + c'_ref / w`` (m), ``(2,)``; it must obey
                ``xi_ref' = w (xi_ref - p_ref)`` (any LIPM plan does, e.g. the online planner's samples).
            dcm: measured DCM ``xi = c + c' / w`` (m), ``(2,)``.
            polygon: support polygon, counter-clockwise vertices ``(k, 2)`` (m), convex, e.g.
                :func:`rtgait.core.geometry.support.support_polygon`. Validated only when it changes between ticks.
            dt: the tick's period (s); ``None``: the ``dt`` given to the constructor.
            zmp_measured: measured ZMP ``p_meas`` (m), ``(2,)``, for the COM admittance; ``None``: ``p_ref``.

        Returns:
            :class:`DcmFeedbackOutput`. The integral advances by this tick's error unless the command was limited;
            the COM offset advances by eq. (4) with the commanded (limited) ZMP.

        Raises:
            ValueError: a non-finite or malformed input, a non-convex or clockwise polygon, or no ``dt``.
        """
        px_ref, py_ref = _pair("zmp_ref", zmp_ref)
        xx_ref, xy_ref = _pair("dcm_ref", dcm_ref)
        xx, xy = _pair("dcm", dcm)
        if zmp_measured is None:
            mx, my = px_ref, py_ref
        else:
            mx, my = _pair("zmp_measured", zmp_measured)
        # One finiteness test for all of them: a NaN or an infinity anywhere makes the sum non-finite.
        if not math.isfinite(px_ref + py_ref + xx_ref + xy_ref + xx + xy + mx + my):
            named = {"zmp_ref": (px_ref, py_ref), "dcm_ref": (xx_ref, xy_ref), "dcm": (xx, xy)}
            named["zmp_measured"] = (mx, my)
            bad = [name for name, (a, b) in named.items() if not (math.isfinite(a) and math.isfinite(b))]
            raise ValueError(f"{', '.join(bad) or 'inputs'} must be finite (m), got {named}")
        if dt is None:
            if self._dt is None:
                raise ValueError("dt must be given to update() or to the constructor (s)")
            dt = self._dt
        if dt != self._tick_dt:
            self._set_dt(dt)
        # The polygon changes only when the contacts do: validate and convert it then, not on every tick.
        key = (polygon.shape, polygon.dtype.char, polygon.tobytes()) if isinstance(polygon, np.ndarray) else None
        if key is None or key != self._polygon_key:
            self._set_polygon(polygon, key)

        # Eq. (2), with the integral of the past ticks.
        ex = xx - xx_ref
        ey = xy - xy_ref
        ux = self._gain_e * ex + self._gain_i * self._ix
        uy = self._gain_e * ey + self._gain_i * self._iy
        unsaturated = (px_ref + ux, py_ref + uy)

        limited = False
        if self._max_speed is not None:
            # The offset from the reference moves at most max_zmp_speed * dt from where the last tick left it.
            step_x = ux - self._ox
            step_y = uy - self._oy
            step = math.hypot(step_x, step_y)
            reach = self._max_speed * dt
            if step > reach:
                scale = reach / step
                ux = self._ox + step_x * scale
                uy = self._oy + step_y * scale
                limited = True
        zx, zy, projected = self._polygon.nearest(px_ref + ux, py_ref + uy)  # type: ignore[union-attr]
        saturated = limited or projected
        self._ox = zx - px_ref
        self._oy = zy - py_ref

        # Anti-windup: on a limited tick the law is not what the robot gets, so the error is not integrated.
        leak_i = self._leak_i
        if saturated:
            self._ix *= leak_i
            self._iy *= leak_i
        else:
            self._ix = leak_i * self._ix + self._input_i * ex
            self._iy = leak_i * self._iy + self._input_i * ey

        # Eq. (4): the COM offset moves against the ZMP error, leaks to zero, and is clamped on each axis.
        dx0, dy0 = self._dx, self._dy
        a = self._admittance
        dx = self._leak_c * dx0 - self._input_c * a * (zx - mx)
        dy = self._leak_c * dy0 - self._input_c * a * (zy - my)
        limit = self._max_offset
        dx = -limit if dx < -limit else (limit if dx > limit else dx)
        dy = -limit if dy < -limit else (limit if dy > limit else dy)
        self._dx, self._dy = dx, dy
        return DcmFeedbackOutput((zx, zy), unsaturated, saturated, (dx, dy), ((dx - dx0) / dt, (dy - dy0) / dt))
