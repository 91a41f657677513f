"""A push: an external force on the robot, constant over a time window (a hand on the pelvis, a collision).

Both closed loops take the same :class:`Push`: the point-mass bench (:mod:`rtgait.core.pendulum`) applies its
horizontal force to the mass, the MuJoCo loop (:mod:`rtgait.sim`) applies the whole force at a body's centre of mass.
Times are on the walk's clock (0 when the walk starts; the MuJoCo loop's start transition runs at negative times).

Size check. A push of impulse ``J`` changes the COM speed of the free robot by ``|J| / m`` and moves its DCM by
``|J| / (m w)``, ``w = sqrt(g / z_c)``. :meth:`Push.check` refuses a push beyond :data:`PUSH_SPEED_LIMIT` times
``sqrt(g z_c)`` of speed, i.e. a DCM moved ``PUSH_SPEED_LIMIT * z_c``: the largest DCM offset from which any number
of steps still recovers is below about ``0.5 z_c`` for a humanoid (a step shorter than its leg), so the limit is some
twenty times beyond any recoverable push. It refuses physical nonsense (a collision, a unit error such as N for N s
or kg for g), never a push worth simulating: 2.5 kN s for 90 kg with ``z_c = 0.8 m`` (a change of speed of 28 m/s),
2.6 kN s for Talos (90 kg, COM 0.84 m high), 0.84 kN s for G1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rtgait.core.lipm.closed_form import GRAVITY

__all__ = ["PUSH_SPEED_LIMIT", "Push", "max_push_impulse"]

PUSH_SPEED_LIMIT = 10.0
"""Largest push accepted, as the COM speed change ``|J| / m`` it gives the free robot, in units of ``sqrt(g z_c)``
(module docstring)."""


def max_push_impulse(mass: float, cog_height: float, gravity: float = GRAVITY) -> float:
    """Largest push impulse accepted (N s) for ``mass`` (kg) walking with its COM ``cog_height`` (m) high under
    ``gravity`` (m/s^2): ``PUSH_SPEED_LIMIT * m * sqrt(g z_c)``."""
    return PUSH_SPEED_LIMIT * mass * math.sqrt(gravity * cog_height)


@dataclass(frozen=True)
class Push:
    """A force on the robot, constant over the half-open window ``[start, start + duration)``.

    Attributes:
        start: when it begins (s, on the walk's clock).
        duration: how long it lasts (s), > 0.
        force: world-frame force ``(fx, fy, fz)`` (N); two numbers ``(fx, fy)`` are a horizontal force (``fz = 0``).
            The MuJoCo loop applies it at the body's centre of mass; the point-mass pendulum takes horizontal
            pushes only.
        body: the MuJoCo body pushed; ``None`` for the floating base (the pendulum's only body, its mass).

    Only finiteness and ``duration > 0`` are checked here; the size against a robot by :meth:`check`. A sustained
    force (a hand pulling the robot along, wind) is no push: the loops take it per tick (the pendulum plant's
    ``force`` argument of :meth:`~rtgait.core.pendulum.plant.LipmPlant.step`, the MuJoCo loop's ``on_tick`` hook).
    """

    start: float
    duration: float
    force: tuple[float, float, float]
    body: str | None = None

    def __post_init__(self) -> None:
        if not _is_number(self.start):
            raise ValueError(f"push start must be a finite time in s, got {self.start!r}")
        if not (_is_number(self.duration) and self.duration > 0.0):
            raise ValueError(f"push duration must be a finite time > 0 s, got {self.duration!r}")
        try:
            force = tuple(self.force)
        except TypeError:
            force = ()
        if len(force) not in (2, 3) or not all(_is_number(f) for f in force):
            raise ValueError(f"push force must be two or three finite numbers (fx, fy[, fz]) in N, got {self.force!r}")
        if self.body is not None and not (isinstance(self.body, str) and self.body):
            raise ValueError(f"push body must be a body's name or None (the floating base), got {self.body!r}")
        fx, fy, fz = (float(f) for f in (*force, 0.0)[:3])
        object.__setattr__(self, "start", float(self.start))
        object.__setattr__(self, "duration", float(self.duration))
        object.__setattr__(self, "force", (fx, fy, fz))

    @property
    def end(self) -> float:
        """When it stops (s); the window is half-open, the force is zero from this instant on."""
        return self.start + self.duration

    @property
    def impulse(self) -> tuple[float, float, float]:
        """``force * duration`` (N s)."""
        fx, fy, fz = self.force
        return (fx * self.duration, fy * self.duration, fz * self.duration)

    @property
    def impulse_norm(self) -> float:
        """Size of the impulse (N s)."""
        return math.hypot(*self.impulse)

    def check(self, mass: float, cog_height: float, gravity: float = GRAVITY) -> None:
        """Refuse a push beyond physical sense for ``mass`` (kg) walking with its COM ``cog_height`` (m) high
        (:data:`PUSH_SPEED_LIMIT`).

        Raises:
            ValueError: naming the impulse and the limit.
        """
        limit = PUSH_SPEED_LIMIT * mass * math.sqrt(gravity * cog_height)
        if self.impulse_norm > limit:
            raise ValueError(
                f"push impulse {self.impulse_norm:.4g} N s exceeds {limit:.4g} N s, a change of COM speed of "
                f"{PUSH_SPEED_LIMIT:g} sqrt(g z_c) for {mass:.1f} kg: check the units (N, s)"
            )

    def summary(self) -> dict[str, object]:
        """JSON-ready: ``start``, ``duration`` (s), ``force`` (N), ``impulse`` (N s), ``impulse_norm`` (N s),
        ``body``."""
        return {
            "start": self.start,
            "duration": self.duration,
            "force": list(self.force),
            "impulse": list(self.impulse),
            "impulse_norm": self.impulse_norm,
            "body": self.body,
        }


def _is_number(value: object) -> bool:
    """A finite int or float (numpy's included), not a bool."""
    try:
        return not isinstance(value, bool) and math.isfinite(value)  # type: ignore[arg-type]
    except TypeError:
        return False
