"""A point-mass plant on the linear inverted pendulum, for closed-loop simulation at the pendulum level.

Model. A mass ``m`` (kg) at constant height ``z_c`` (m) above flat ground; per horizontal axis

    c'' = w^2 (c - p) + f / m,        w = sqrt(g / z_c)

with ``c`` the COM (m), ``p`` the *real* ZMP (m) and ``f`` an external horizontal force on the mass (N). The real ZMP
is the commanded one when the feet on the ground can produce it, otherwise the nearest point of their support
polygon (the foot rolls onto that edge or corner).

Exact integration. Over one control tick ``dt`` the commanded ZMP and the force are held (a zero-order hold, as a
digital controller applies them). With ``p_eff = p - f / (m w^2)`` constant, ``x = c - p_eff`` obeys ``x'' = w^2 x``:

    x(dt)  = x(0) cosh(w dt) + x'(0) sinh(w dt) / w
    x'(dt) = x(0) w sinh(w dt) + x'(0) cosh(w dt)

:class:`~rtgait.core.push.Push` windows that begin or end inside a tick split it at their boundaries, each piece
integrated in closed form, so the delivered impulse is ``force * duration`` to round-off whatever the control period.
The DCM ``xi = c + c' / w`` obeys ``xi' = w (xi - p) + f / (m w)``: a DCM outside the support polygon cannot be brought
back without a step.

*Fallen.* The ground force the LIPM needs, ``m (w^2 (c - p), g)``, leans from the vertical by ``atan(|c - p| / z_c)``,
at least ``atan(D / z_c)`` for a COM a horizontal distance ``D`` from the support polygon. The plant has fallen when

    D > fall_distance,            default fall_distance = z_c tan(25 degrees) ~ 0.47 z_c

Past that lean the model fails twice: holding the COM at ``z_c`` needs a leg longer than ``z_c / cos(25 deg) = 1.10
z_c``, and the ground force a friction coefficient above ``tan(25 deg) = 0.47`` (rubber soles on a common floor hold
about 0.5 to 1). The verdict hardly depends on the threshold: a diverging pendulum's distance grows like ``e^{w t}``,
so halving or doubling it moves the fall time by ``ln 2 / w`` (0.2 s at ``z_c = 0.8 m``). It is a state test, not a
prediction (that is :mod:`rtgait.core.laws.capturability`'s job).

*At rest* (:meth:`LipmPlant.at_rest`): the COM speed below a tolerance (default 1 cm/s) and the DCM inside the support
polygon; with the DCM inside, a ZMP held on it keeps it fixed and ``c - xi`` decays like ``e^{-w t}``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence

import numpy as np

from rtgait.core.geometry.polygon import ConvexPolygon, vertex_list
from rtgait.core.geometry.support import signed_margin
from rtgait.core.lipm.closed_form import GRAVITY, omega
from rtgait.core.push import PUSH_SPEED_LIMIT, Push, max_push_impulse

DEFAULT_MAX_LEAN = math.radians(25.0)
"""Lean of the ground force from the vertical beyond which the point mass counts as fallen (rad); module docstring."""

DEFAULT_REST_SPEED = 0.01
"""COM speed below which the pendulum may count as at rest (m/s): 1-10 % of walking speeds (0.1-1 m/s); with it the
COM is within ``speed / w`` (3 mm at ``z_c = 0.8 m``) of its DCM."""


def _floats2(name: str, value: Sequence[float] | np.ndarray) -> tuple[float, float]:
    """``value`` as two finite floats, else a ValueError naming ``name``."""
    try:
        a, b = value
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be two numbers (x, y), got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise ValueError(f"{name} must be finite, got ({a}, {b})")
    return a, b


def push_force(pushes: Iterable[Push], t: float) -> np.ndarray:
    """Sum of the forces (N) of the pushes active at time ``t`` (s), shape ``(2,)``; windows are ``[start, end)``."""
    fx = fy = 0.0
    for push in pushes:
        if push.start <= t < push.end:
            fx += push.force[0]
            fy += push.force[1]
    return np.array([fx, fy])


def push_impulse(pushes: Iterable[Push], t0: float, t1: float) -> np.ndarray:
    """Impulse (N s) the pushes deliver over ``[t0, t1]``, shape ``(2,)``: each force times its overlap.

    Divided by ``t1 - t0`` it is the mean force over a tick, for integrators that cannot split a tick at push
    boundaries (it delivers the exact impulse, though not the exact motion within the tick).
    """
    if not t1 >= t0:
        raise ValueError(f"need t1 >= t0, got [{t0}, {t1}]")
    jx = jy = 0.0
    for push in pushes:
        overlap = min(t1, push.end) - max(t0, push.start)
        if overlap > 0.0:
            jx += push.force[0] * overlap
            jy += push.force[1] * overlap
    return np.array([jx, jy])


class LipmPlant:
    """Point mass on the linear inverted pendulum at constant height, integrated exactly tick by tick.

    Args:
        cog_height: ``z_c`` (m), > 0.
        mass: ``m`` (kg), > 0; only external forces depend on it.
        gravity: ``g`` (m/s^2).
        cog: initial horizontal COM position ``(x, y)`` (m).
        cog_vel: initial horizontal COM velocity (m/s).
        time: initial time on the plant's clock (s); :class:`Push` windows use this clock.
        fall_distance: COM distance from the support polygon beyond which :meth:`fallen` is true (m); default
            ``z_c tan(DEFAULT_MAX_LEAN)`` (module docstring).
        pushes: pushes to apply, validated as by :meth:`add_push`.

    Per tick call :meth:`step`; it costs a few microseconds (Python floats, the prepared polygon is reused while its
    vertices do not change).
    """

    __slots__ = (
        "_cosh",
        "_dt",
        "_fall_distance",
        "_g",
        "_live",
        "_m",
        "_poly",
        "_pushes",
        "_sinh",
        "_t",
        "_vx",
        "_vy",
        "_w",
        "_x",
        "_y",
        "_zc",
        "_zmp",
    )

    def __init__(
        self,
        cog_height: float,
        mass: float,
        gravity: float = GRAVITY,
        cog: Sequence[float] | np.ndarray = (0.0, 0.0),
        cog_vel: Sequence[float] | np.ndarray = (0.0, 0.0),
        *,
        time: float = 0.0,
        fall_distance: float | None = None,
        pushes: Iterable[Push] = (),
    ) -> None:
        self._w = omega(cog_height, gravity)  # validates height and gravity
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"mass must be a finite mass > 0 kg, got {mass}")
        self._zc, self._g, self._m = float(cog_height), float(gravity), float(mass)
        if fall_distance is None:
            fall_distance = self._zc * math.tan(DEFAULT_MAX_LEAN)
        if not (math.isfinite(fall_distance) and fall_distance > 0.0):
            raise ValueError(f"fall_distance must be a finite distance > 0 m, got {fall_distance}")
        self._fall_distance = float(fall_distance)
        self._x = self._y = self._vx = self._vy = self._t = 0.0
        self.set_state(cog, cog_vel, time)
        self._dt = math.nan  # last full-tick duration and its cosh/sinh, reused at a constant control period
        self._cosh = self._sinh = math.nan
        self._poly: ConvexPolygon | None = None
        self._zmp: tuple[float, float] | None = None
        self._pushes: list[Push] = []
        self._live = 0  # pushes before this index have ended
        for push in pushes:
            self.add_push(push)

    # ----- state ------------------------------------------------------------------------------------------------
    @property
    def omega(self) -> float:
        """Pendulum frequency ``w = sqrt(g / z_c)`` (1/s)."""
        return self._w

    @property
    def cog_height(self) -> float:
        """``z_c`` (m)."""
        return self._zc

    @property
    def mass(self) -> float:
        """``m`` (kg)."""
        return self._m

    @property
    def gravity(self) -> float:
        """``g`` (m/s^2)."""
        return self._g

    @property
    def fall_distance(self) -> float:
        """COM distance from the support polygon beyond which the mass counts as fallen (m)."""
        return self._fall_distance

    @property
    def time(self) -> float:
        """Plant clock (s)."""
        return self._t

    @property
    def cog(self) -> np.ndarray:
        """Horizontal COM position ``(x, y)`` (m)."""
        return np.array([self._x, self._y])

    @property
    def cog_vel(self) -> np.ndarray:
        """Horizontal COM velocity (m/s)."""
        return np.array([self._vx, self._vy])

    @property
    def dcm(self) -> np.ndarray:
        """Divergent component of motion ``xi = c + c' / w`` (m)."""
        return np.array([self._x + self._vx / self._w, self._y + self._vy / self._w])

    @property
    def zmp(self) -> np.ndarray | None:
        """Real ZMP applied over the last tick (m); ``None`` before the first :meth:`step`."""
        return None if self._zmp is None else np.array(self._zmp)

    @property
    def pushes(self) -> tuple[Push, ...]:
        """The scheduled pushes, by start time."""
        return tuple(self._pushes)

    def set_state(
        self, cog: Sequence[float] | np.ndarray, cog_vel: Sequence[float] | np.ndarray, time: float | None = None
    ) -> None:
        """Overwrite the COM position (m), velocity (m/s) and, if given, the clock (s)."""
        x, y = _floats2("cog (m)", cog)
        vx, vy = _floats2("cog_vel (m/s)", cog_vel)
        if time is not None:
            if not math.isfinite(time):
                raise ValueError(f"time must be finite (s), got {time}")
            self._t = float(time)
            self._live = 0
        self._x, self._y, self._vx, self._vy = x, y, vx, vy

    def copy(self) -> LipmPlant:
        """An independent plant in the same state, with the same pushes (e.g. to compare two futures)."""
        twin = LipmPlant(
            self._zc, self._m, self._g, (self._x, self._y), (self._vx, self._vy), time=self._t,
            fall_distance=self._fall_distance,
        )  # fmt: skip
        twin._pushes = list(self._pushes)
        twin._live = self._live
        twin._zmp = self._zmp
        return twin

    # ----- external forces ----------------------------------------------------------------------------------
    @property
    def max_impulse(self) -> float:
        """Largest push impulse accepted (N s): ``PUSH_SPEED_LIMIT * m * sqrt(g z_c)``."""
        return max_push_impulse(self._m, self._zc, self._g)

    def _check_impulse(self, jx: float, jy: float, what: str) -> None:
        size = math.hypot(jx, jy)
        if size > self.max_impulse:
            raise ValueError(
                f"{what} of {size:.4g} N s exceeds the plant's limit {self.max_impulse:.4g} N s "
                f"(a COM speed change of {PUSH_SPEED_LIMIT:g} sqrt(g z_c)); check units"
            )

    def add_push(self, push: Push) -> None:
        """Schedule ``push``; it is applied by :meth:`step` over exactly its window.

        Raises ValueError if it is not horizontal (a mass at constant height has no vertical motion), names a body
        (the mass is the only one), or its impulse exceeds :attr:`max_impulse` (:meth:`Push.check`).
        """
        if not isinstance(push, Push):
            raise ValueError(f"expected a Push, got {type(push).__name__}")
        if push.force[2] != 0.0:
            raise ValueError(f"the pendulum takes horizontal pushes only (fz = 0 N), got force {push.force}")
        if push.body is not None:
            raise ValueError(f"the pendulum's only body is its mass: a push's body must be None, got {push.body!r}")
        push.check(self._m, self._zc, self._g)
        self._pushes.append(push)
        self._pushes.sort(key=lambda p: p.start)
        self._live = 0

    def apply_impulse(self, impulse: Sequence[float] | np.ndarray) -> None:
        """An instantaneous push: the COM velocity jumps by ``impulse / m`` (N s in), the DCM by ``impulse / (m w)``."""
        jx, jy = _floats2("impulse (N s)", impulse)
        self._check_impulse(jx, jy, "impulse")
        self._vx += jx / self._m
        self._vy += jy / self._m

    # ----- integration --------------------------------------------------------------------------------------
    def _polygon(self, polygon: np.ndarray) -> ConvexPolygon:
        vertices = vertex_list(polygon)
        poly = self._poly
        if poly is None or poly.key != vertices:  # rebuild only when the contacts change
            poly = self._poly = ConvexPolygon(vertices, min_vertices=1)  # one foot's edge or corner is a contact
        return poly

    def _advance(self, tau: float, ex: float, ey: float, full_tick: bool) -> None:
        """Exact motion over ``tau`` (s) about the constant effective ZMP ``(ex, ey)`` (m)."""
        if full_tick:
            if tau != self._dt:
                self._dt = tau
                self._cosh, self._sinh = math.cosh(self._w * tau), math.sinh(self._w * tau)
            ch, sh = self._cosh, self._sinh
        else:
            ch, sh = math.cosh(self._w * tau), math.sinh(self._w * tau)
        w = self._w
        x, y, vx, vy = self._x - ex, self._y - ey, self._vx, self._vy
        self._x = ex + x * ch + vx * sh / w
        self._y = ey + y * ch + vy * sh / w
        self._vx = x * w * sh + vx * ch
        self._vy = y * w * sh + vy * ch

    def step(
        self,
        dt: float,
        zmp_command: Sequence[float] | np.ndarray,
        polygon: np.ndarray,
        force: Sequence[float] | np.ndarray = (0.0, 0.0),
    ) -> np.ndarray:
        """Advance the clock by ``dt`` (s) with the commanded ZMP (m) and ``force`` (N) held over the tick.

        Args:
            dt: tick length (s), > 0.
            zmp_command: ZMP asked of the feet ``(x, y)`` (m).
            polygon: counter-clockwise vertices ``(k, 2)`` (m) of the convex support polygon of the feet on the
                ground during this tick (e.g. :func:`rtgait.core.geometry.support.support_polygon`). Empty: ValueError.
            force: external horizontal force on the mass (N), added to the scheduled pushes.

        Returns:
            The real ZMP ``(2,)`` (m): the command, or the nearest point of the polygon when the command is outside.
        """
        dt = float(dt)
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"dt must be a finite time > 0 s, got {dt}")
        cx, cy = _floats2("zmp_command (m)", zmp_command)
        fx, fy = (0.0, 0.0) if force is None else _floats2("force (N)", force)
        px, py, _ = self._polygon(polygon).nearest(cx, cy)
        self._zmp = (px, py)
        k = 1.0 / (self._m * self._w * self._w)  # force to ZMP shift (m/N)
        t0 = self._t
        t1 = t0 + dt

        pushes = self._pushes
        n = len(pushes)
        while self._live < n and pushes[self._live].end <= t0:
            self._live += 1
        cuts: list[float] | None = None
        for i in range(self._live, n):
            push = pushes[i]
            if push.start >= t1:
                break
            if push.end > t0:
                if cuts is None:
                    cuts = []
                if push.start > t0:
                    cuts.append(push.start)
                if push.end < t1:
                    cuts.append(push.end)
        if cuts is None:
            self._advance(dt, px - k * fx, py - k * fy, True)
        else:
            # Split the tick at every push boundary inside it; the force is constant on each piece.
            times = [t0, *sorted(cuts), t1]
            for a, b in itertools.pairwise(times):
                if b <= a:
                    continue
                mid = 0.5 * (a + b)
                gx, gy = fx, fy
                for i in range(self._live, n):
                    push = pushes[i]
                    if push.start > mid:
                        break
                    if mid < push.end:
                        gx += push.force[0]
                        gy += push.force[1]
                self._advance(b - a, px - k * gx, py - k * gy, False)
        self._t = t1
        return np.array([px, py])

    # ----- verdicts -----------------------------------------------------------------------------------------
    def distance_to_polygon(self, polygon: np.ndarray) -> float:
        """Horizontal distance (m) from the COM to the support polygon; 0 inside."""
        qx, qy, moved = self._polygon(polygon).nearest(self._x, self._y)
        return math.hypot(self._x - qx, self._y - qy) if moved else 0.0

    def fallen(self, polygon: np.ndarray) -> bool:
        """True when the COM is farther than :attr:`fall_distance` from the support polygon (module docstring)."""
        return self.distance_to_polygon(polygon) > self._fall_distance

    def at_rest(self, polygon: np.ndarray, speed_tol: float = DEFAULT_REST_SPEED, margin: float = 0.0) -> bool:
        """True when the COM speed is at most ``speed_tol`` (m/s) and the DCM is at least ``margin`` (m) inside the
        support polygon, so that the ZMP held on the DCM stops the mass without a step (module docstring).

        Meant for judging the end of a walk, not for every tick (it calls
        :func:`rtgait.core.geometry.support.signed_margin`, some tens of microseconds).
        """
        if not (math.isfinite(speed_tol) and speed_tol >= 0.0):
            raise ValueError(f"speed_tol must be a finite speed >= 0 m/s, got {speed_tol}")
        if math.hypot(self._vx, self._vy) > speed_tol:
            return False
        poly = self._polygon(polygon)
        if poly.degenerate:  # a point or line contact has no inside: the DCM must lie on it
            xi = self.dcm
            moved = poly.nearest(float(xi[0]), float(xi[1]))[2]
            return not moved and margin <= 0.0
        return bool(signed_margin(self.dcm, np.asarray(poly.key, dtype=float))[0] >= margin)
