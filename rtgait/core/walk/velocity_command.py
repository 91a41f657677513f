"""Walking by velocity command: the command, the bounds on the strides it makes, and how a command becomes a stride.

A joystick-like command ``(vx, vy, wz)`` (forward and lateral speed in m/s, positive left; yaw rate in rad/s)
asks, over the step period ``T = single_support + double_support`` (s), a forward stride ``vx T`` per step and,
per pair of steps (one by each foot), a lateral displacement ``D = 2 vy T`` and a heading change ``2 wz T``.
:func:`stride_from_command` turns it into the next :class:`~rtgait.core.geometry.footsteps.Stride`, within
:class:`StepLimits` (length ``L``, lateral ``Dmax``, turn ``Tmax``). The three demands share one reach: a command's
share of its limits,

    r = sqrt((vx T / L)^2 + (2 vy T / Dmax)^2 + (2 wz T / Tmax)^2),

must be at most 1 (an ellipsoid whose semi-axes are the limits; a command along one axis may go to that axis's
limit, a diagonal one less on each). A command with ``r > 1`` is scaled down by ``1 / r`` (:func:`clamp_command`:
its direction and curvature kept), and :func:`warn_if_clamped` says so with a :class:`CommandClampedWarning` that
names the command walked. :class:`~rtgait.core.walk.walk.Walk` makes the strides of a walk by command with these.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

from rtgait.core.geometry.footsteps import Footstep, Side, Stride, other_side
from rtgait.core.input_bounds import InputOutOfBoundsError


class CommandClampedWarning(UserWarning):
    """A velocity command asked for steps beyond the configured step limits; it was scaled down to them."""


@dataclass(frozen=True)
class VelocityCommand:
    """Joystick-like walking command: forward (m/s), lateral (m/s, positive left) and yaw rate (rad/s)."""

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0

    def __post_init__(self) -> None:
        for name in ("vx", "vy", "wz"):
            if not math.isfinite(getattr(self, name)):
                raise InputOutOfBoundsError(f"velocity command {name} must be finite, got {getattr(self, name)}")


@dataclass(frozen=True)
class StepLimits:
    """Bounds on the strides made from velocity commands (:meth:`~rtgait.core.walk.walk.Walk.set_velocity`): forward
    stride (m), lateral displacement per pair of steps (m), heading change per pair of steps (rad), and the narrowest
    stance a sideways walk may close to (m; ``None``: the walk's ``step_width``)."""

    length: float
    lateral: float
    turn: float
    min_width: float | None = None


REACH_TOLERANCE = 1e-12
"""Relative rounding allowed on a command's reach before it counts as beyond the limits."""


def command_reach(command: VelocityCommand, limits: StepLimits, period: float) -> float:
    """The command's share of the step limits over a step period ``period`` (s): ``r`` of the module docstring,
    0 standing still, 1 on the limits' ellipsoid."""
    return math.hypot(  # hypot: no overflow on huge finite commands (their reach is then inf)
        command.vx * period / limits.length,
        2.0 * command.vy * period / limits.lateral,
        2.0 * command.wz * period / limits.turn,
    )


def clamp_command(command: VelocityCommand, limits: StepLimits, period: float) -> VelocityCommand:
    """``command`` scaled down onto the limits' ellipsoid when its reach (:func:`command_reach`) exceeds 1, else
    itself: a diagonal command keeps its direction rather than each component being cut to its own limit (which
    would leave it asking for every limit at once, beyond what the legs reach)."""
    reach = command_reach(command, limits, period)
    if reach <= 1.0 + REACH_TOLERANCE:
        return command
    if not math.isfinite(reach):  # components near the float range: take the direction first, then scale it
        biggest = max(abs(command.vx), abs(command.vy), abs(command.wz))
        command = VelocityCommand(command.vx / biggest, command.vy / biggest, command.wz / biggest)
        reach = command_reach(command, limits, period)
    return VelocityCommand(command.vx / reach, command.vy / reach, command.wz / reach)


def stride_from_command(
    stance: Footstep, command: VelocityCommand | None, limits: StepLimits, period: float, step_width: float
) -> Stride:
    """The stride of the next step from ``stance`` under ``command`` (``None``: standing still), within ``limits``.

    Over a step period ``T`` (``period``, s) a command ``(vx, vy, wz)``, first scaled onto the limits' ellipsoid
    (:func:`clamp_command`), asks per step a forward stride ``vx T`` and per pair of steps (one by each foot) a
    lateral displacement ``D = 2 vy T`` and a heading change ``2 wz T``:

    - Forward: every step ``vx T``, within ``+-limits.length``.
    - Sideways: the feet cannot cross, so only the step toward the motion can carry the body sideways: it lands
      ``D`` wider than the step after it, and the two widths are spread evenly around the straight-walking
      stance ``w0`` (``step_width``, m), ``w0 + D/2`` and ``w0 - D/2``, the narrow one never below
      ``limits.min_width`` (whatever it cannot close goes to the wide one). Over a pair of steps the body moves
      ``D``; the stance opens at most ``D/2`` beyond ``w0`` where the robot allows narrowing, instead of ``D`` (the
      leg's sideways lean and the hip's abduction are what limit a sideways walk). ``D <= limits.lateral``.
    - Turning: every step turns ``wz T`` (both feet alike), so the feet alternate between toeing out and in by
      ``wz T`` rather than one foot turning ``2 wz T`` and the other closing: half the angle between the feet
      (their heels or toes, and the hips' yaw, are what limit a turn). ``2 |wz| T <= limits.turn``.
    """
    command = clamp_command(command or VelocityCommand(), limits, period)
    landing: Side = other_side(stance.side)
    length = min(max(command.vx * period, -limits.length), limits.length)
    shift = min(2.0 * abs(command.vy) * period, limits.lateral)
    nominal = step_width
    narrowest = nominal if limits.min_width is None else min(limits.min_width, nominal)
    narrow = max(nominal - 0.5 * shift, narrowest)
    toward = "left" if command.vy > 0.0 else "right"
    width = narrow + shift if landing == toward else narrow
    half_turn = 0.5 * limits.turn
    turn = min(max(command.wz * period, -half_turn), half_turn)
    return Stride(length=length, width=width, turn=turn)


def warn_if_clamped(command: VelocityCommand, limits: StepLimits, period: float) -> None:
    """Warn (:class:`CommandClampedWarning`) when ``command`` asks more than ``limits`` allow over a step period
    ``period`` (s): its reach (:func:`command_reach`) exceeds 1, and :func:`stride_from_command` walks it scaled
    down (:func:`clamp_command`), the command the warning names. The warning names the caller's caller
    (``stacklevel=3``: whoever called the method that calls this)."""
    walked = clamp_command(command, limits, period)
    if walked is not command:
        reach = command_reach(command, limits, period)
        warnings.warn(
            f"velocity command ({command.vx:g} m/s, {command.vy:g} m/s, {command.wz:g} rad/s) exceeds the step "
            f"limits ({reach:.3g} of them: step length {limits.length:g} m per {period:g} s step; lateral "
            f"{limits.lateral:g} m and turn {limits.turn:g} rad per pair of steps, their squared shares adding up to "
            f"at most 1): clamped to ({walked.vx:.4g} m/s, {walked.vy:.4g} m/s, {walked.wz:.4g} rad/s)",
            CommandClampedWarning,
            stacklevel=3,
        )


__all__ = [
    "CommandClampedWarning",
    "StepLimits",
    "VelocityCommand",
    "clamp_command",
    "command_reach",
    "stride_from_command",
    "warn_if_clamped",
]
