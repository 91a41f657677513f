"""Compensation of a known external force: the robot leans against a pull so that its ZMP stays where it is planned.

A horizontal force ``F = (F_x, F_y)`` (N) on the robot at height ``h`` (m) above the ground, say a person's hand
pulling the robot's hand, adds a moment about the ground. Moments about the ZMP ``p`` of a robot of mass ``m`` with
its COM ``c`` at constant height ``z``, whose angular momentum about the COM does not change, give

    m g (c - p) - m z c'' + h F = 0,   so   p = c - c'' / w^2 + h F / (m g),     w = sqrt(g / z),

the pendulum's ZMP shifted by ``h F / (m g)`` in the direction of the pull (Harada et al., "Pushing manipulation by
humanoid considering two kinds of ZMPs", 2003). A robot that tracks a COM planned for ``F = 0`` therefore stands
with its centre of pressure that far off the plan. With the COM shifted by the *lean*

    delta = -h F / (m g)

the same planned ZMP balances the pull: ``c = c_plan + delta`` with ``delta`` constant gives ``c'' = c_plan''`` and
``p = c_plan - c_plan'' / w^2 = p_plan``. So the controller plans and feeds back in the frame of the unpulled
pendulum: it takes the measured COM (and DCM) minus ``delta`` in, and gives the IK the COM target plus ``delta``.
hrpsys's AutoBalancer does the same for its hands' reference forces.

The force reaches :class:`ExternalForce` as it is measured (a wrist sensor). The COM cannot follow a sudden lean
without moving the ZMP: by the pendulum equation its own motion makes the ZMP ``-delta'' / w^2``. So the lean
follows the measured force through a first-order low-pass of time constant ``T = 2 / w`` (two of the pendulum's time
constants: 0.58 s on Talos, 0.51 s on G1): after a step of the force, ``delta''`` peaks at ``Delta / T^2`` and the
ZMP the lean makes at ``Delta / (w T)^2 = Delta / 4``, a quarter of the lean itself. The lean so compensates the
pull's slow part, the mean pull of a person leading the robot, and leaves its ripple at the walking frequency to the
feedback law. The controller takes the measured COM velocity minus ``delta'`` in with the COM minus ``delta``, so
that a lean under way is no DCM error.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from rtgait.core.lipm.closed_form import GRAVITY

if TYPE_CHECKING:
    from rtgait.estimation.state import Measurement

__all__ = ["ExternalForce", "lean", "shifted_measurement"]


def lean(force: tuple[float, float], height: float, mass: float, gravity: float = GRAVITY) -> tuple[float, float]:
    """The COM shift ``-h F / (m g)`` (m) that balances a horizontal ``force`` (N) at ``height`` (m) above the
    ground on a robot of ``mass`` (kg) (module docstring)."""
    scale = -height / (mass * gravity)
    return (scale * force[0], scale * force[1])


def shifted_measurement(
    m: Measurement, offset: tuple[float, float], rate: tuple[float, float], w: float
) -> Measurement:
    """``m`` with its COM moved by ``offset`` (m), its COM velocity by ``rate`` (m/s) and its DCM by
    ``offset + rate / w`` (m); the ZMP and the feet as measured.

    The moved DCM is made as that of the moved COM state, ``(c + offset) + (c' + rate) / w``: equal to
    ``m.dcm + offset + rate / w`` but for round-off, and in the float operations the controller has always
    used (a walk led by the hand stays bit for bit what it was)."""
    dx, dy = offset
    vx, vy = rate
    cx, cy = m.com[0] + dx, m.com[1] + dy
    cvx, cvy = m.com_vel[0] + vx, m.com_vel[1] + vy
    return m._replace(com=(cx, cy, m.com[2]), com_vel=(cvx, cvy, m.com_vel[2]), dcm=(cx + cvx / w, cy + cvy / w))


class ExternalForce:
    """The lean of a controller against a measured horizontal force (module docstring): :meth:`set` each tick with
    the measurement; :attr:`offset` (m) and :attr:`rate` (m/s) are then the COM shift and its rate, to add to the
    COM target and to subtract from the measured COM state.

    Args:
        mass: the robot's mass (kg).
        w: the pendulum's ``w = sqrt(g / z)`` (1/s); the lean's time constant is ``2 / w``.
        dt: the control period (s), the time between two :meth:`set`.
        gravity: ``g`` (m/s^2).
    """

    def __init__(self, mass: float, w: float, dt: float, gravity: float = GRAVITY) -> None:
        for name, value in (("mass", mass), ("w", w), ("dt", dt), ("gravity", gravity)):
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be > 0, got {value}")
        self.mass, self.gravity = float(mass), float(gravity)
        self.time_constant = 2.0 / w
        self._smoothing = -math.expm1(-dt / self.time_constant)
        self.reset()

    def reset(self) -> None:
        """No force: no lean."""
        self.offset: tuple[float, float] = (0.0, 0.0)
        self.rate: tuple[float, float] = (0.0, 0.0)

    @property
    def active(self) -> bool:
        """Whether the robot leans (a force was measured since the last reset)."""
        return self.offset != (0.0, 0.0) or self.rate != (0.0, 0.0)

    def set(self, force: tuple[float, float], height: float) -> tuple[float, float]:
        """This tick's measured ``force`` (N, world frame) at ``height`` (m above the ground); returns the lean (m)."""
        fx, fy = float(force[0]), float(force[1])
        if not (math.isfinite(fx) and math.isfinite(fy) and math.isfinite(height)):
            raise ValueError(f"external force and height must be finite, got {force} N at {height} m")
        target = lean((fx, fy), height, self.mass, self.gravity)
        a, tau = self._smoothing, self.time_constant
        x = self.offset[0] + a * (target[0] - self.offset[0])
        y = self.offset[1] + a * (target[1] - self.offset[1])
        self.offset = (x, y)
        self.rate = ((target[0] - x) / tau, (target[1] - y) / tau)  # the low-pass's own derivative
        return self.offset
