"""The multibody ZMP of a walk's commanded motion, where the commanded configurations are a motion.

The *commanded motion* is the configuration the servos were given at each control tick (the IK's floating base and
joint angles, the foot force control's ankle tilts added). Its multibody ZMP (:mod:`rtgait.robot.dynamics`) is where
the ground reaction would be if the servos tracked it exactly, so the measured ZMP against it isolates the servos'
and the contacts' error from the pendulum model's. It needs accelerations, second differences of configurations
one control period ``dt`` apart, and the controller moves some of its references rather than the robot:

* **Retargeting ticks.** At each of the controller's events (a landing, the planner re-anchoring a footprint on the
  measured sole, a replan from the measured state, a step adjustment) and at the walk's start (the controller takes
  over from the start transition) the IK's targets may jump at once: a replan moves the COM target by millimetres
  (4.2 mm after the step adjustment of a pushed Talos walk), a re-anchoring a loaded foot's target by the servo lag
  (3.7 mm). A jump ``J`` in one tick reads as an acceleration ``J / dt^2`` at the two ticks beside it: 4200 m/s^2 and
  a ZMP 1300 m away for that replan at ``dt = 1 ms``, a number of the sampling, not of a motion. The commanded motion
  is differentiated piecewise between these ticks (``breaks`` of :func:`~rtgait.robot.dynamics.finite_differences`),
  so a jump leaves out nothing but the difference that spans it; a continuous move of the controller's (a COM
  offset whose rate changes, a step of the plan's velocity) stays in.
* **Re-anchoring of a swing.** A touch-down of the plan's swing foot before the plan's double support (a landing on
  time or early) re-anchors its footprint where it landed, and what is left of the swing, 3 to 80 ms, takes the
  foot's target there (or holds it there, after an early one, until a jump at the double support): millimetres in a
  few ticks, hundreds of m/s^2, the reference catching up with a foot that is already on the ground. The ZMP is NaN
  from such a touch-down to the first tick of the plan's double support, 1 to 6 % of the single-support ticks of
  the built-in walks.

Where a motion is left, the measure is the finite-difference multibody ZMP, unchanged to the bit. Off the ground
(a vertical force of the motion not within 90 % of the weight) it is NaN too.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from rtgait.robot.dynamics import multibody_check

if TYPE_CHECKING:
    import pinocchio as pin

    from rtgait.control.settings import ControlEvent

__all__ = ["commanded_motion_zmp", "reanchoring_mask", "retarget_ticks"]

_SIDES = ("left", "right")


def _tick(times: np.ndarray, t: float, dt: float) -> int:
    """The index of the tick at time ``t`` (s) in the uniform ``times`` (a tick past the end: ``len(times)``)."""
    return int(np.searchsorted(times, t - 0.5 * dt))


def retarget_ticks(times: np.ndarray, events: Sequence[ControlEvent], dt: float, walk_start: float = 0.0) -> list[int]:
    """The ticks at which the commanded motion may jump (module docstring), in order, each within ``[1, k - 1]``:
    those of the controller's ``events`` and of ``walk_start`` (s), on the uniform clock ``times`` of period ``dt``."""
    ticks = {_tick(times, t, dt) for t in [walk_start, *(event.t for event in events)]}
    return sorted(k for k in ticks if 1 <= k < len(times))


def reanchoring_mask(times: np.ndarray, swinging: np.ndarray, events: Sequence[ControlEvent], dt: float) -> np.ndarray:
    """The ticks of re-anchored swings (module docstring), shape ``(k,)``: from each touch-down of a foot the plan
    has swinging (``swinging``: shape ``(k, 2)``, left and right) to the first tick the plan has it down again."""
    mask = np.zeros(len(times), dtype=bool)
    for event in events:
        if event.kind != "touchdown" or event.side not in _SIDES:
            continue
        k = _tick(times, event.t, dt)
        swing = swinging[k:, _SIDES.index(event.side)]
        if len(swing) and swing[0]:
            down = np.flatnonzero(~swing)
            mask[k : k + (int(down[0]) + 1 if len(down) else len(swing))] = True
    return mask


def commanded_motion_zmp(
    model: pin.Model,
    commanded_q: np.ndarray,
    times: np.ndarray,
    dt: float,
    swinging: np.ndarray,
    events: Sequence[ControlEvent],
    weight: float,
) -> np.ndarray:
    """The multibody ZMP of the commanded motion (m), shape ``(k, 2)`` (module docstring).

    Args:
        model: the reduced Pinocchio model of ``commanded_q``.
        commanded_q: the commanded configurations, shape ``(k, nq)``, ``k >= 3``.
        times: the ticks' times (s, the walk's clock, uniform with period ``dt``), shape ``(k,)``.
        dt: the control period (s).
        swinging: whether the plan has each foot (left, right) swinging at the tick, shape ``(k, 2)``.
        events: the controller's events of the run.
        weight: the robot's weight (N).
    """
    uniform = times[0] + np.arange(len(times)) * dt  # exactly uniform, as multibody_check wants
    check = multibody_check(model, uniform, commanded_q, breaks=retarget_ticks(times, events, dt))
    zmp = np.array(check.zmp)
    # A ZMP needs the feet pressed on the ground: NaN where the motion's vertical force is not near the weight.
    with np.errstate(invalid="ignore"):
        zmp[~(np.abs(check.vertical_force - weight) < 0.9 * weight)] = math.nan
    zmp[reanchoring_mask(times, swinging, events, dt)] = math.nan
    return zmp
