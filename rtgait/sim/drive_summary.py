"""What a run's drives did, for ``summary.json``'s ``drive``: the drive settings, how often torques saturated, the
peak joint torque and speed against their envelopes, and how well the COM tracked the plan.

* ``feedforward_clipped_share``: the share of the walk's ticks at which the safety layer clipped some joint's
  feed-forward torque to its torque limit (:mod:`rtgait.stack.command_limits`); ``None`` without feed-forward.
* ``drive_saturated_share``: the share of ticks at which some joint's applied torque (the drive's, averaged over the
  tick's physics steps, as ``sim.csv`` has it) was within :data:`SATURATION_FRACTION` of its bound: the joint's torque
  limit or, with the motor model, its motor's envelope at the joint's speed (:mod:`rtgait.sim.motors`). A drive
  saturated on some physics steps of a tick only is not counted.
* ``peak_torque`` and ``peak_speed``: the joint closest to its envelope, ``|tau| / bound`` (the torque limit, N m) and
  ``|dq| / bound`` (the motor's no-load speed with the motor model, else the URDF's speed limit, rad/s).
* ``peak_envelope``: with the motor model, the tick and joint whose torque came closest to its motor's torque-speed
  envelope at that tick's speed, ``|tau| / bound(dq)`` (the bound of ``drive_saturated_share``; a ratio of 1 is a
  saturated drive); ``None`` without the motor model or the joints' speeds.
* ``com_tracking_rms``: the RMS horizontal distance (m) over the walk's ticks from the planner's COM to the
  estimator's COM (``vs_estimated``) and to the simulator's true COM (``vs_true``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from rtgait.robot.joint_limits import joint_limits

if TYPE_CHECKING:
    from rtgait.sim.model import SimModel

__all__ = ["SATURATION_FRACTION", "ComTracking", "drive_summary"]

SATURATION_FRACTION = 0.99
"""A drive is saturated at a tick when its torque is at least this fraction of its bound."""


class ComTracking:
    """Sums of the squared horizontal COM errors over the walk's ticks (module docstring)."""

    def __init__(self) -> None:
        self.ticks = 0
        self._estimated = self._true = 0.0

    def add(self, planned: tuple[float, float], estimated: tuple[float, ...], true: tuple[float, ...]) -> None:
        """One tick: the planner's COM, the estimator's and the true one (m; the first two coordinates used)."""
        ex, ey = estimated[0] - planned[0], estimated[1] - planned[1]
        tx, ty = true[0] - planned[0], true[1] - planned[1]
        self.ticks += 1
        self._estimated += ex * ex + ey * ey
        self._true += tx * tx + ty * ty

    def rms(self) -> dict[str, float | None]:
        """``vs_estimated`` and ``vs_true`` (m), ``None`` before any tick."""
        if not self.ticks:
            return {"vs_estimated": None, "vs_true": None}
        return {"vs_estimated": math.sqrt(self._estimated / self.ticks), "vs_true": math.sqrt(self._true / self.ticks)}


def drive_summary(
    sim: SimModel,
    settings: dict[str, Any],
    torque: np.ndarray,
    joint_velocity: np.ndarray | None,
    clipped_ticks: int | None,
    walk_ticks: int,
    tracking: ComTracking,
) -> dict[str, Any]:
    """The ``drive`` entry of a run's summary (module docstring).

    Args:
        sim: the simulated robot.
        settings: the drive settings to report (gains, drive mode, feed-forward, motor model, command delay).
        torque: the drives' torques per tick (N m), shape ``(k, n)``.
        joint_velocity: the joints' speeds per tick (rad/s), shape ``(k, n)``; ``None``: not recorded.
        clipped_ticks: the walk's ticks with a feed-forward torque clipped; ``None``: no feed-forward.
        walk_ticks: the walk's ticks (the start transition's left out).
        tracking: the COM's tracking errors.
    """
    names = sim.joint_names
    limit = sim.actuation.effort_limit
    motors = sim.motors
    ticks = len(torque)
    envelope = None
    if motors is not None and joint_velocity is not None and len(joint_velocity) == ticks:
        lower, upper = np.empty_like(torque), np.empty_like(torque)
        for k in range(ticks):
            motors.bounds(joint_velocity[k], lower[k], upper[k])
        bound = np.where(torque >= 0.0, upper, -lower)
        if ticks:
            envelope = _envelope_peak(names, torque, joint_velocity, bound)
    else:
        bound = np.broadcast_to(limit, torque.shape)
    saturated = (np.abs(torque) >= SATURATION_FRACTION * bound).any(axis=1) if ticks else np.zeros(0, bool)
    speed_bound = motors.no_load_speed if motors is not None else joint_limits(sim.robot).velocity
    return {
        **settings,
        "feedforward_clipped_share": None if clipped_ticks is None else clipped_ticks / max(walk_ticks, 1),
        "drive_saturated_share": float(saturated.mean()) if ticks else None,
        "peak_torque": _peak(names, np.abs(torque), limit, "N m"),
        "peak_speed": None if joint_velocity is None else _peak(names, np.abs(joint_velocity), speed_bound, "rad/s"),
        "peak_envelope": envelope,
        "com_tracking_rms": tracking.rms(),
    }


def _peak(names: tuple[str, ...], values: np.ndarray, bound: np.ndarray, unit: str) -> dict[str, Any] | None:
    """The joint whose largest value comes closest to its bound: its name, the value, the bound and their ratio."""
    if not len(values):
        return None
    peaks = np.nanmax(values, axis=0)
    ratios = np.where(np.isfinite(bound), peaks / bound, 0.0)
    i = int(np.argmax(ratios))
    return {"joint": names[i], "value": float(peaks[i]), "bound": float(bound[i]), "ratio": float(ratios[i]),
            "unit": unit}  # fmt: skip


def _envelope_peak(names: tuple[str, ...], torque: np.ndarray, speed: np.ndarray, bound: np.ndarray) -> dict[str, Any]:
    """The tick and joint whose torque is the largest share of its motor's bound at its speed (``bound`` > 0 where
    a motor can push; 0 beyond the no-load speed, where any torque along the motion is beyond it)."""
    magnitude = np.abs(torque)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.where(bound > 0.0, magnitude / bound, np.where(magnitude > 0.0, np.inf, 0.0))
    k, i = np.unravel_index(int(np.argmax(ratios)), ratios.shape)
    return {"joint": names[i], "tick": int(k), "torque": float(torque[k, i]), "speed": float(speed[k, i]),
            "bound": float(bound[k, i]), "ratio": float(ratios[k, i]), "unit": "N m"}  # fmt: skip
