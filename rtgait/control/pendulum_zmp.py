"""The measured ZMP as the pendulum's: the ZMP the COM admittance compares with its command, at the robot's weight.

The COM admittance (:mod:`rtgait.core.laws.feedback`, eq. 4) reads a ZMP error as a COM acceleration error through
the linear inverted pendulum, ``c'' = w^2 (c - p)`` with ``w^2 = g / z_c``: a pendulum carried by its weight ``m g``.
The ground's horizontal force is ``F (c - p) / z_c`` for a total normal force ``F`` at the measured ZMP ``p``, so the
COM's horizontal acceleration is ``(F / (m g)) w^2 (c - p)``: the measured ZMP stands for the pendulum ZMP

    p_w = c + (F / (m g)) (p - c)                                                        (1)

the ZMP a pendulum carried by its weight would have under that acceleration. At ``F = m g`` it is ``p``. As ``F`` falls
to zero (a foot bouncing off, both feet off the ground for a few ticks, or one foot's sensor reading a pull against the
other's push) ``p = M / F`` runs off to metres while ``F (p - c) = M - F c`` stays the measured moment: ``p_w`` goes to
the COM's ground point, where a body without support has its ZMP (no horizontal acceleration). Fed ``p`` instead, the
admittance ``d' = -A (p_cmd - p)`` steps the IK's COM target by centimetres in one tick when the feet barely touch
(``docs/results.md``, "A DCM-error replan's step of the COM target").
"""

from __future__ import annotations

import math

__all__ = ["pendulum_zmp"]


def pendulum_zmp(zmp: tuple[float, float], com: tuple[float, ...], force: float, weight: float) -> tuple[float, float]:
    """(1) of the module docstring: the measured ``zmp`` (m) with total normal force ``force`` (N) as the ZMP of a
    pendulum carried by ``weight`` (N, ``m g``), its COM at ``com`` (``(x, y, ...)``, m); ``zmp`` itself when
    ``force`` is not finite."""
    if not math.isfinite(force):
        return zmp
    k = force / weight
    cx, cy = com[0], com[1]
    return (cx + k * (zmp[0] - cx), cy + k * (zmp[1] - cy))
